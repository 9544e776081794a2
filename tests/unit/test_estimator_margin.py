"""The friction estimator's own yield displacement keeps its loop a 6 dB gain margin (issue 31, item 6).

On the stuck bearing the estimator is a spring ``mu(0) W / D_y_est`` fed back positively through
the loop's delay (harness/control/estimator_margin.py). With the bearing's ``D_y`` (the source's
design) the plain loop's gain at its phase-0 crossing was 1.18 in real time: the 48 Hz limit cycle.
"""

from __future__ import annotations

import pytest

from harness.control.estimator_margin import (
    LOCKSTEP_DELAY_S,
    MAX_CROSSING_GAIN,
    REALTIME_DELAY_S,
    crossing_gain,
    estimator_yield_displacement_m,
    margin_yield_displacement_m,
    phase_crossings,
)
from harness.control.factory import make_friction_estimator
from harness.errors import ProfileError
from harness.profile import load_profile
from tests.conftest import PROFILES


@pytest.fixture(scope="module")
def profile():
    return load_profile(PROFILES / "nceer_4dof.yaml")


def test_the_shipped_yield_displacement_is_the_estimators_own_and_wider_than_the_bearings(profile) -> None:
    assert profile.bearing.yield_displacement_m == pytest.approx(2.54e-5)  # the bearing keeps the source's D_y
    assert estimator_yield_displacement_m(profile) == pytest.approx(6.5e-5)


@pytest.mark.parametrize("alpha", [0.0, None], ids=["no feed-forward", "the profile's feed-forward"])
@pytest.mark.parametrize("delay_s", [LOCKSTEP_DELAY_S, REALTIME_DELAY_S], ids=["lockstep", "real time"])
def test_the_shipped_estimator_keeps_a_6_db_gain_margin(profile, alpha, delay_s) -> None:
    crossings = phase_crossings(profile, delay_s, alpha)
    assert crossings, "the loop's phase crosses 0 in the band"
    assert max(gain for _, gain in crossings) <= MAX_CROSSING_GAIN  # real time, alpha = 0: 0.46


def test_the_bearings_own_yield_displacement_does_not(profile) -> None:
    source = profile.bearing.yield_displacement_m
    assert crossing_gain(profile, REALTIME_DELAY_S, 0.0, source) > 1.0  # 1.18: unstable, the limit cycle
    assert crossing_gain(profile, REALTIME_DELAY_S, None, source) > MAX_CROSSING_GAIN  # 0.71: 3 dB only


def test_the_derived_yield_displacement_sits_on_the_margin_and_the_shipped_one_at_or_above_it(profile) -> None:
    derived = margin_yield_displacement_m(profile)
    assert crossing_gain(profile, REALTIME_DELAY_S, 0.0, derived) == pytest.approx(MAX_CROSSING_GAIN, rel=1e-9)
    assert derived == pytest.approx(6.02e-5, rel=0.01)  # 0.0254 mm x 1.18 / 0.5
    assert derived <= estimator_yield_displacement_m(profile) <= 1.25 * derived  # rounded up, not far


def test_the_factory_builds_the_estimator_with_the_setting_and_the_bearings_d_y_without(profile) -> None:
    weight = profile.structure.total_weight_N
    shipped = make_friction_estimator(profile)
    source = make_friction_estimator(load_profile(PROFILES / "nceer_4dof.yaml",
                                                  overrides=["control.estimator.yield_displacement_m=null"]))
    # the same sliding travel loads the narrower band's nu faster: 10 um at 1 mm/s, 10 steps of 1 ms
    for estimator in (shipped, source):
        estimator.update(0.0, 1e-3, 1e-3)
        for step in range(1, 11):
            estimator.update(step * 1e-3, 1e-3, 1e-3)
    assert 0.0 < shipped.nu < source.nu < 1.0
    assert source.force_N <= profile.bearing.mu_max * weight


def test_a_yield_displacement_that_is_not_positive_is_refused() -> None:
    with pytest.raises(ProfileError, match=r"control\.estimator\.yield_displacement_m"):
        load_profile(PROFILES / "nceer_4dof.yaml", overrides=["control.estimator.yield_displacement_m=0"])
