"""Fixed cases for bugs the safety review planted that only random property tests caught, or none did.

- a reset allowed after a predictive stroke trip while the projection is still past the hard limit;
- a stopping ramp that skips the force-rate limit;
- a rate limit computed with a different ``dt`` than the tick's (and, since the stall budget,
  never more than one nominal period's worth after a stall);
- sample ages that are negative or not finite (a clock mix-up) passing the staleness checks,
  the E-stop panel's age included (`estop_lost` and the `estop_panel_live` pre-arm check).
"""

from __future__ import annotations

import itertools
import math

import pytest

from harness.safety.config import ForceConfig, SafetyConfig, StrokeConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import ArmRefused, ResetRefused, State
from harness.safety.supervisor import Supervisor

RATE_N_PER_S = 400_000.0


def _running(config: SafetyConfig | None = None, period_s: float | None = None) -> tuple[Supervisor, TickHealth]:
    sup = Supervisor(config or SafetyConfig(), period_s=period_s)
    health = TickHealth()
    sup.arm(0.0, health)
    sup.start(0.0)
    return sup, health


def _tick(sup: Supervisor, health: TickHealth, t: float, dt: float, force: float):
    health.meas.base_displacement_m = 1e-6 * (round(t / 1e-3) % 3 - 1)  # sensor noise: never bit-for-bit constant
    health.measured_force_N = sup.command.force_N
    return sup.update(t, dt, health, force)


def test_reset_is_refused_while_the_projection_is_still_past_the_hard_limit():
    stroke = StrokeConfig(soft_limit_m=0.05, fade_band_m=0.01, hard_limit_m=0.075, stop_time_s=0.1)
    sup, health = _running(SafetyConfig(stroke=stroke))
    health.meas.base_displacement_m, health.meas.base_velocity_m_s = 0.07, 0.1  # 0.07 + 0.1 * 0.1 = 0.08 > 0.075
    assert sup.update(0.002, 0.002, health, 0.0).trip_reason == "stroke_predictive"
    with pytest.raises(ResetRefused, match="stroke_predictive"):
        sup.reset(0.004, health)
    health.meas.base_velocity_m_s = -0.1  # moving back in: 0.07 - 0.01 = 0.06, inside
    sup.reset(0.006, health)
    assert sup.state is State.IDLE


def test_the_stopping_ramp_never_grows_the_force_faster_than_the_rate_limit():
    sup, health = _running(SafetyConfig(force=ForceConfig(max_force_rate_N_per_s=RATE_N_PER_S)))
    dt = 0.002
    assert _tick(sup, health, dt, dt, 0.0).force_N == 0.0
    sup.stop(dt, "test")  # STOPPING with the force at zero ...
    forces = [_tick(sup, health, dt * k, dt, 9_000.0).force_N for k in range(2, 40)]  # ... and a large demand
    steps = [abs(b - a) for a, b in itertools.pairwise([0.0, *forces])]
    assert max(steps) <= RATE_N_PER_S * dt * (1 + 1e-9)


@pytest.mark.parametrize("dt", [0.001, 0.002, 0.004])
def test_the_rate_limit_uses_the_ticks_own_dt(dt: float):
    sup, health = _running(SafetyConfig(force=ForceConfig(max_force_rate_N_per_s=RATE_N_PER_S)))
    first = _tick(sup, health, dt, dt, 5_000.0).force_N
    second = _tick(sup, health, 2 * dt, dt, 5_000.0).force_N
    assert first == pytest.approx(RATE_N_PER_S * dt)
    assert second - first == pytest.approx(RATE_N_PER_S * dt)


def test_after_a_stall_the_rate_limit_allows_one_nominal_period_only():
    period = 0.002
    sup, health = _running(SafetyConfig(force=ForceConfig(max_force_rate_N_per_s=RATE_N_PER_S)), period_s=period)
    before = _tick(sup, health, period, period, 5_000.0).force_N
    after = _tick(sup, health, period + 0.015, 0.015, 5_000.0).force_N  # 15 ms since the previous tick
    assert after - before == pytest.approx(RATE_N_PER_S * period)  # 800 N, not 6 kN


@pytest.mark.parametrize("age", [-1.8e9, -0.001, math.nan, math.inf])
@pytest.mark.parametrize("field", ["table_age_s", "base_age_s", "actuator_status_age_s"])
def test_a_negative_or_non_finite_age_trips_and_refuses_arming(field: str, age: float):
    sup, health = _running()
    setattr(health, field, age)
    command = sup.update(0.002, 0.002, health, 100.0)
    expected = "actuator_status_stale" if field == "actuator_status_age_s" else "sensor_stale"
    assert command.trip_reason == expected and command.force_N == 0.0 and not command.enable
    idle = Supervisor(SafetyConfig())
    with pytest.raises(ArmRefused):
        idle.arm(0.0, health)


@pytest.mark.parametrize("age", [-1.8e9, -0.001, math.nan, math.inf])
def test_a_negative_or_non_finite_panel_age_trips_estop_lost_and_refuses_arming(age: float):
    # docs/SAFETY.md, estop_lost: a panel age that is not a finite age in 0..max_panel_age_s trips and refuses arming
    sup, health = _running()
    assert sup.update(0.002, 0.002, health, 100.0).force_N > 0.0  # a live panel: force flows
    health.estop_panel_age_s = age
    command = sup.update(0.004, 0.002, health, 100.0)
    assert command.trip_reason == "estop_lost" and command.force_N == 0.0 and not command.enable
    idle = Supervisor(SafetyConfig())
    with pytest.raises(ArmRefused) as refused:
        idle.arm(0.0, health)
    assert [failure.split(":")[0] for failure in refused.value.failed] == ["estop_panel_live"]
    assert idle.state is State.IDLE


@pytest.mark.parametrize(("field", "reason", "stale_s", "message"), [
    ("estop_panel_age_s", "estop_lost", 0.25, "newest panel frame 250.0 ms old, expected 0 <= age <= 200.0 ms"),
    ("actuator_status_age_s", "actuator_status_stale", 0.075, "actuator status age 75.000 ms, expected 0 <= age <= 50.000 ms"),
])
def test_a_stale_age_trip_names_the_age_and_resets_only_once_fresh_again(field, reason, stale_s, message):
    sup, health = _running()
    setattr(health, field, stale_s)
    command = sup.update(0.002, 0.002, health, 100.0)
    assert command.trip_reason == reason and message in sup.trip_detail
    with pytest.raises(ResetRefused, match=message):
        sup.reset(0.004, health)  # still stale: the reset is refused and says why
    setattr(health, field, 0.001)
    sup.reset(0.006, health)  # fresh again
    assert sup.state is State.IDLE


def test_a_panel_age_exactly_on_its_bound_still_arms():
    bound = SafetyConfig().estop.max_panel_age_s
    idle = Supervisor(SafetyConfig())
    idle.arm(0.0, TickHealth(estop_panel_age_s=bound))  # 0 <= age <= bound, like estop_lost
    assert idle.state is State.ARMED
