"""Bearing friction (Eq. 3-5) and the local update of the hysteretic variable."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from harness.model.bearing import (
    BearingConfig,
    advance_hysteretic,
    friction_coefficient,
    friction_force,
    hysteretic_rate,
)

RIG = BearingConfig(mu_max=0.06, mu_delta=0.03, a_mu_s_per_m=90.16, yield_displacement_m=2.54e-5, eta=3)
EIGHT = BearingConfig(mu_max=0.10, mu_delta=0.05, a_mu_s_per_m=20.0, yield_displacement_m=1.2e-4, eta=2)
WEIGHT = 40_000.0


def test_friction_coefficient_depends_on_velocity_not_displacement():
    p = EIGHT.packed(WEIGHT)
    assert friction_coefficient(0.0, p) == pytest.approx(0.05)
    assert friction_coefficient(10.0, p) == pytest.approx(0.10)
    assert friction_coefficient(0.05, p) == pytest.approx(0.10 - 0.05 * np.exp(-20 * 0.05))
    assert friction_coefficient(-0.05, p) == friction_coefficient(0.05, p)


def test_friction_force_is_mu_weight_nu():
    p = RIG.packed(WEIGHT)
    assert friction_force(0.2, -0.5, p) == pytest.approx(friction_coefficient(0.2, p) * WEIGHT * -0.5)


def test_hysteretic_rate_loading_and_unloading():
    p = EIGHT.packed(WEIGHT)
    # loading at the bound: no change; unloading from the bound: slope alpha / D_y (beta = gamma)
    assert hysteretic_rate(0.1, 1.0, p) == pytest.approx(0.0, abs=1e-9)
    assert hysteretic_rate(-0.1, 1.0, p) == pytest.approx(-0.1 / 1.2e-4)
    assert hysteretic_rate(0.1, 0.0, p) == pytest.approx(0.1 / 1.2e-4)


def _reference_nu(nu0: float, velocity: float, dt: float, params: np.ndarray) -> float:
    solution = solve_ivp(
        lambda t, y: [hysteretic_rate(velocity, y[0], params)], (0, dt), [nu0], method="Radau", rtol=1e-11, atol=1e-13
    )
    return float(solution.y[0, -1])


@pytest.mark.slow
@settings(max_examples=60, deadline=None)
@given(
    nu0=st.floats(-1.0, 1.0),
    velocity=st.floats(-1.0, 1.0).filter(lambda v: abs(v) > 1e-6),
    dt=st.sampled_from([1e-4, 1e-3, 2e-3, 4e-3]),
    bearing=st.sampled_from([RIG, EIGHT]),
)
def test_local_update_matches_tight_reference(nu0, velocity, dt, bearing):
    params = bearing.packed(WEIGHT)
    expected = _reference_nu(nu0, velocity, dt, params)
    assert advance_hysteretic(nu0, velocity, dt, params) == pytest.approx(expected, abs=2e-5)


@settings(max_examples=200, deadline=None)
@given(nu0=st.floats(-1.0, 1.0), velocity=st.floats(-5.0, 5.0), dt=st.floats(0.0, 0.01))
def test_local_update_stays_within_the_bound(nu0, velocity, dt):
    nu = advance_hysteretic(nu0, velocity, dt, RIG.packed(WEIGHT))
    assert -1.0 - 1e-9 <= nu <= 1.0 + 1e-9


def test_long_travel_saturates_at_the_bound():
    p = RIG.packed(WEIGHT)
    assert advance_hysteretic(-1.0, 0.5, 0.01, p) == pytest.approx(1.0)
    assert RIG.nu_bound == pytest.approx(1.0)


@pytest.mark.parametrize(
    "changes, message",
    [({"mu_delta": 0.2}, "exceeds mu_max"), ({"beta": 0.0, "gamma": 0.0}, "beta \\+ gamma")],
)
def test_inconsistent_bearing_is_refused(changes, message):
    values = dict(mu_max=0.1, mu_delta=0.05, a_mu_s_per_m=20.0, yield_displacement_m=1e-4)
    values.update(changes)
    with pytest.raises(ValueError, match=message):
        BearingConfig(**values)
