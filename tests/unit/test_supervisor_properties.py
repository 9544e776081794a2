"""Property-based tests of the supervisor: for ANY sequence of measurements, raw forces
(NaN and inf included), faults and operator requests, the command stays inside the limits.
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from harness.errors import SafetyError
from harness.safety.checks import bit
from harness.safety.config import SafetyConfig, SensorConfig, StrokeConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import DRIVE_STATES, State
from harness.safety.supervisor import Supervisor

DEFAULT = SafetyConfig()
#: Sensor checks relaxed so that random sequences spend most ticks RUNNING and exercise the interlocks.
RELAXED = dataclasses.replace(
    DEFAULT,
    sensors=SensorConfig(
        displacement_range_m=1.0, velocity_range_m_s=5.0, jump_limit_m=10.0, jump_limit_m_s=100.0,
        stuck_samples=10**6, disagree_tolerance_m_s=100.0, max_sensor_age_s=0.002,
    ),
    # a short look-ahead, so random sequences reach the fade band; the stall budget and the
    # sensor age must still fit inside it (check_config), so they are short too
    stroke=StrokeConfig(stop_time_s=0.004),
    force=dataclasses.replace(DEFAULT.force, actuator_time_constant_s=0.0),
    run=dataclasses.replace(DEFAULT.run, max_stall_s=0.002),
)
CONFIGS = st.sampled_from([RELAXED, RELAXED, DEFAULT])

FAULTS = ("estop", "bus_off", "operator_stop", "operator_trip", "meas_nan", "stale", "drive_fault")
_finite_force = st.floats(-30_000.0, 30_000.0, allow_nan=False)
_special_force = st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -1e300, 0.0, 10_000.0, -10_000.0])

TICK = st.fixed_dictionaries({
    "kind": st.just("tick"),
    "x0": st.floats(-0.1, 0.1),
    "xb": st.one_of(st.floats(-0.1, 0.1), st.floats(0.045, 0.065), st.floats(-0.065, -0.045)),
    "v0": st.floats(-0.5, 0.5),
    "vb": st.floats(-0.5, 0.5),
    "raw": st.one_of(_finite_force, _finite_force, _special_force),
    "dt": st.one_of(st.sampled_from([0.001, 0.004]), st.floats(1e-4, 0.02)),
    "fault": st.one_of(st.none(), st.none(), st.none(), st.none(), st.sampled_from(FAULTS)),
})
ACTION = st.fixed_dictionaries({"kind": st.sampled_from(["arm_start", "arm_start", "arm", "start", "stop", "reset"])})
STEPS = st.lists(st.one_of(TICK, TICK, TICK, ACTION), min_size=1, max_size=40)

#: 1000 sequences each; ``make mutation`` lowers it (HARNESS_PROPERTY_EXAMPLES) so a surviving mutant of the
#: supervisor costs seconds, not a minute: its kill rate is then a lower bound.
PROPERTY = settings(max_examples=int(os.environ.get("HARNESS_PROPERTY_EXAMPLES", "1000")), deadline=None)


@dataclasses.dataclass
class TickRecord:
    """What one tick looked like, for the properties."""

    before: State
    after: State
    raw: float
    x_b: float
    dt: float
    previous_N: float
    force_N: float
    enable: bool
    acted: int


def _apply_fault(health: TickHealth, fault: str | None) -> None:
    health.estop = fault == "estop"
    health.bus_off = fault == "bus_off"
    health.operator_stop = fault == "operator_stop"
    health.operator_trip = fault == "operator_trip"
    health.drive_fault = fault == "drive_fault"
    health.base_age_s = 1.0 if fault == "stale" else 0.0
    if fault == "meas_nan":
        health.meas.base_velocity_m_s = math.nan


def _action(sup: Supervisor, health: TickHealth, kind: str, t: float) -> bool:
    """Perform an operator request; True if it was a successful reset."""
    _apply_fault(health, None)
    try:
        if kind in ("arm", "arm_start"):
            health.meas.set(0.0, 0.0, 0.0, 0.0)
            sup.arm(t, health)
            if kind == "arm_start":
                sup.start(t)
        elif kind == "start":
            sup.start(t)
        elif kind == "stop":
            sup.stop(t)
        else:
            sup.reset(t, health)
            return True
    except SafetyError:
        pass
    return False


def simulate(config: SafetyConfig, steps: list[dict[str, Any]]) -> list[TickRecord | str]:
    """Run the steps; return a trace of tick records and the marker "reset" after each successful reset."""
    sup = Supervisor(config)
    health = TickHealth()
    trace: list[TickRecord | str] = []
    t = 0.0
    for step in steps:
        if step["kind"] != "tick":
            if _action(sup, health, step["kind"], t):
                trace.append("reset")
            continue
        t += step["dt"]
        health.meas.set(step["x0"], step["v0"], step["x0"] + step["xb"], step["v0"] + step["vb"])
        _apply_fault(health, step["fault"])
        health.measured_force_N = sup.command.force_N
        before, previous = sup.state, sup.command.force_N
        command = sup.update(t, step["dt"], health, step["raw"])
        trace.append(TickRecord(before, command.state, step["raw"], step["xb"], step["dt"], previous,
                                command.force_N, command.enable, command.acted))
        assert command.state is sup.state
    return trace


def _ticks(trace: list[TickRecord | str]) -> list[TickRecord]:
    return [r for r in trace if isinstance(r, TickRecord)]


@PROPERTY
@given(CONFIGS, STEPS)
def test_force_and_force_rate_limits_hold(config: SafetyConfig, steps: list[dict[str, Any]]) -> None:
    max_N, rate = config.force.max_force_N, config.force.max_force_rate_N_per_s
    for r in _ticks(simulate(config, steps)):
        assert math.isfinite(r.force_N) and abs(r.force_N) <= max_N
        if r.after is State.TRIPPED:
            continue  # a trip drops to zero at once, by design
        step = rate * r.dt * (1 + 1e-12) + 1e-9
        if r.acted & bit("stroke_soft"):
            # the fade may only move the rate-limited force towards zero
            low, high = min(0.0, r.previous_N - step), max(0.0, r.previous_N + step)
            assert low <= r.force_N <= high
        else:
            assert abs(r.force_N - r.previous_N) <= step


@PROPERTY
@given(CONFIGS, STEPS)
def test_never_pushes_further_out_past_the_soft_limit(config: SafetyConfig, steps: list[dict[str, Any]]) -> None:
    stroke, max_N = config.stroke, config.force.max_force_N
    for r in _ticks(simulate(config, steps)):
        beyond = abs(r.x_b) - stroke.soft_limit_m
        if beyond <= 0.0 or r.force_N * r.x_b <= 0.0:
            continue
        # outward force beyond the soft limit: never more than the fade allows, none past the band end
        allowed = max_N * max(0.0, 1.0 - beyond / stroke.fade_band_m)
        assert abs(r.force_N) <= allowed * (1 + 1e-9) + 1e-9
        assert abs(r.x_b) < stroke.soft_limit_m + stroke.fade_band_m


@PROPERTY
@given(CONFIGS, STEPS)
def test_zero_and_disabled_outside_drive_states_and_latched_until_reset(
    config: SafetyConfig, steps: list[dict[str, Any]]
) -> None:
    latched = False
    for r in simulate(config, steps):
        if r == "reset":
            latched = False
            continue
        assert isinstance(r, TickRecord)
        if r.after in DRIVE_STATES:
            assert r.enable
            if r.after is State.ARMED:
                assert r.force_N == 0.0  # ARMED: drive enabled, force held at zero
        else:
            assert (r.force_N, r.enable) == (0.0, False)
        if latched:
            assert r.after is State.TRIPPED and (r.force_N, r.enable) == (0.0, False)
        latched = latched or r.after is State.TRIPPED


@PROPERTY
@given(CONFIGS, STEPS)
def test_non_finite_raw_force_trips_on_its_tick(config: SafetyConfig, steps: list[dict[str, Any]]) -> None:
    for r in _ticks(simulate(config, steps)):
        if r.before in DRIVE_STATES and not math.isfinite(r.raw):
            assert r.after is State.TRIPPED and (r.force_N, r.enable) == (0.0, False)
