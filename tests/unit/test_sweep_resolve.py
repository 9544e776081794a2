"""A case's profile through the sweep's fast path equals ``load_profile`` with the same overrides."""

from __future__ import annotations

import pytest

from harness.errors import ProfileError
from harness.profile import load_profile
from harness.sweep.axes import override, scaled, value_at
from harness.sweep.resolve import BaseProfile, case_profile
from tests.conftest import PROFILES

EIGHT = str(PROFILES / "eight_story.yaml")


@pytest.mark.parametrize(
    "overrides",
    [
        ("bearing.mu_max=0.08",),
        ("bearing.a_mu_s_per_m=0.5 s/cm", "control.design_stiffness_scale=0.7"),
        (override("structure.story_stiffness_N_per_m", [3.1e8, 3e8, 2.8e8, 2.6e8, 2.4e8, 2e8, 1.7e8, 1.4e8]),),
        ("control.designs.FSF-I.surface.q.drifts=500", "record.duration_s=5", "simulation.rtol=1e-7"),
        ("safety.stroke.hard_limit_m=0.1",),  # not a fast section: load_profile itself
    ],
)
def test_the_fast_path_equals_load_profile(overrides):
    base = BaseProfile(EIGHT, "a_mu_0.5", ("record.pga_g=0.2",))
    expected = load_profile(EIGHT, variant="a_mu_0.5", overrides=["record.pga_g=0.2", *overrides])
    assert case_profile(base, overrides) == expected


def test_no_override_is_the_base_profile_itself():
    base = BaseProfile(EIGHT)
    assert case_profile(base, ()) is base.load()


@pytest.mark.parametrize(
    ("overrides", "message"),
    [
        (("bearing.mu_max=-0.1",), r"bearing.mu_max: found -0.1, expected a value >= 0"),
        (("bearing.mu_delta=0.2",), r"mu_delta = 0.2 exceeds mu_max = 0.1"),
        (("loop.rate_hz=500",), r"loop.rate_hz is no longer a key: the profile has one rate, control.rate_hz"),
        (("bearing.friction=1",), r"unknown key 'friction'"),
    ],
)
def test_the_fast_path_refuses_what_the_file_would(overrides, message):
    with pytest.raises(ProfileError, match=message):
        case_profile(BaseProfile(EIGHT), overrides)
    with pytest.raises(ProfileError, match=message):
        load_profile(EIGHT, overrides=list(overrides))


def test_scaling_multiplies_a_number_or_every_element():
    profile = load_profile(EIGHT)
    stiffness = value_at(profile, "structure.story_stiffness_N_per_m")
    assert scaled(stiffness, 0.5) == [k * 0.5 for k in stiffness]
    assert scaled(value_at(profile, "control.designs.OF-I.p1_per_s"), 2.0) == 20.0
    with pytest.raises(ValueError, match="expected a number or a list of numbers"):
        scaled("estimator", 2.0)
