"""Force limits where a lab's controller puts them (issue 31, item 2).

``max_force_N`` bounds the setpoint, ``max_flow_term_N`` what a harness-side compensator adds to
it, and ``load_cell_limit`` watches the force fed back (docs/SAFETY.md, "What max_force_N must bound").
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from harness.safety.actuator_detectors import LoadCellLimit
from harness.safety.config import ForceConfig, SafetyConfig, check_config
from harness.safety.events import Action
from harness.safety.health import TickHealth
from harness.safety.interlocks import ForceClamp
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor

DT = 0.002
FORCE = ForceConfig()
MAX, FLOW, CELL = FORCE.max_force_N, FORCE.max_flow_term_N, FORCE.load_cell_limit_N


def armed_supervisor(config: SafetyConfig | None = None) -> tuple[Supervisor, TickHealth]:
    """A running supervisor on a fresh health, its sensors quiet (no new samples)."""
    supervisor, health = Supervisor(config or SafetyConfig(), period_s=DT), TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    health.table_fresh = health.base_fresh = False
    return supervisor, health


# ------------------------------------------------------------------ the clamp: setpoint and addition apart


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_the_setpoint_is_clamped_at_max_force_and_the_addition_at_max_flow_term(sign: float) -> None:
    clamp = ForceClamp(FORCE)
    # at each bound: untouched
    assert clamp.apply_compensated(sign * MAX, sign * (MAX + FLOW)) == sign * (MAX + FLOW) and not clamp.acted
    # just beyond the setpoint's bound: the setpoint is clamped, the addition kept
    assert clamp.apply_compensated(sign * (MAX + 1.0), sign * (MAX + 1.0 + 100.0)) == sign * (MAX + 100.0)
    assert clamp.acted
    # just beyond the addition's bound: the addition is clamped, the setpoint kept
    assert clamp.apply_compensated(sign * 1000.0, sign * (1000.0 + FLOW + 1.0)) == sign * (1000.0 + FLOW)
    assert clamp.acted
    # just inside both
    assert clamp.apply_compensated(sign * (MAX - 1.0), sign * (MAX - 1.0 + FLOW - 1.0)) == sign * (MAX + FLOW - 2.0)
    assert not clamp.acted
    # an addition against the setpoint is bounded the same way
    assert clamp.apply_compensated(sign * MAX, sign * (MAX - FLOW - 50.0)) == sign * (MAX - FLOW)
    assert clamp.acted


def test_the_command_never_exceeds_max_force_plus_max_flow_term_and_the_flow_term_no_longer_eats_the_setpoint() -> None:
    clamp = ForceClamp(FORCE)
    for setpoint in (-3 * MAX, -MAX, -1.0, 0.0, 2500.0, MAX, 3 * MAX):
        for addition in (-4 * FLOW, -FLOW, 0.0, 700.0, FLOW, 4 * FLOW):
            command = clamp.apply_compensated(setpoint, setpoint + addition)
            assert abs(command) <= MAX + FLOW
            assert command - max(-MAX, min(MAX, setpoint)) == pytest.approx(max(-FLOW, min(FLOW, addition)))
    # the defect of the clamp on the command: a 9 kN setpoint plus a 3 kN flow term used to go out as 10 kN
    assert clamp.apply_compensated(9000.0, 12_000.0) == 12_000.0


def test_the_compensated_clamps_detail_states_the_setpoint_the_addition_and_the_command_sent() -> None:
    clamp = ForceClamp(FORCE)
    setpoint, command = 9_000.0, 9_000.0 + FLOW + 1_500.0
    detail = clamp.detail(command, setpoint)
    assert detail.startswith(f"setpoint 9000 N within +/-{MAX:g} N (safety.force.max_force_N)")
    assert f"compensator's addition {FLOW + 1_500.0:.6g} N within +/-{FLOW:g} N (safety.force.max_flow_term_N)" in detail
    assert detail.endswith(f"command {command:.6g} N clamped to {9_000.0 + FLOW:.6g} N")
    assert clamp.detail(-12_000.0) == f"demanded -12000 N, clamped to +/-{MAX:g} N (safety.force.max_force_N)"


def test_the_supervisor_bounds_a_compensated_command_by_its_setpoint_and_flow_term() -> None:
    supervisor, health = armed_supervisor()
    force = 0.0
    for k in range(1, 25):  # the rate limit lets the command rise 800 N a tick (force_tracking would trip after 50)
        force = supervisor.update(k * DT, DT, health, 30_000.0, 20_000.0).force_N
    assert force == MAX + FLOW
    events: list[tuple[str, str]] = []
    supervisor.events.drain(lambda t, kind, name, detail: events.append((name, detail)))
    assert "safety.force.max_flow_term_N" in dict(events)["force_clamp"]
    supervisor, health = armed_supervisor()
    for k in range(1, 25):  # without a setpoint the command is the setpoint: max_force_N alone
        force = supervisor.update(k * DT, DT, health, 30_000.0).force_N
    assert force == MAX
    supervisor, health = armed_supervisor()
    command = supervisor.update(DT, DT, health, 0.0, math.nan)
    assert command.trip_reason == "controller_output" and "setpoint" in supervisor.trip_detail


# ------------------------------------------------------------------ load_cell_limit


def _cell_run(force_N: float, ticks: int, config: ForceConfig = FORCE) -> int | None:
    det = LoadCellLimit(config)
    health = TickHealth()
    health.measured_force_N = force_N
    for k in range(ticks):
        if det.update(k * DT, DT, health):
            return k
    return None


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_load_cell_limit_at_and_around_its_limit_and_time(sign: float) -> None:
    n = round(FORCE.load_cell_limit_time_s / DT)
    assert _cell_run(sign * (CELL + 1.0), 10 * n) == n  # held load_cell_limit_time_s after the onset at tick 0
    assert _cell_run(sign * CELL, 100 * n) is None  # at the limit: within
    assert _cell_run(sign * (CELL - 1.0), 100 * n) is None
    # beyond for one tick less than the time, then back: no trip
    det, health = LoadCellLimit(FORCE), TickHealth()
    for k in range(3 * n):
        health.measured_force_N = sign * (CELL + 1.0) if k < n else 0.0
        assert not det.update(k * DT, DT, health)
    assert det.peak_N == CELL + 1.0
    assert LoadCellLimit.ACTION is Action.TRIP


def test_load_cell_limit_fails_safe_and_refuses_a_reset_while_beyond() -> None:
    assert _cell_run(math.nan, 100) == round(FORCE.load_cell_limit_time_s / DT)
    supervisor, health = armed_supervisor()
    health.measured_force_N = -(CELL + 10.0)
    for k in range(1, 100):
        if supervisor.update(k * DT, DT, health, 0.0).trip_reason:
            break
    assert supervisor.state is State.TRIPPED and supervisor.command.trip_reason == "load_cell_limit"
    assert "safety.force.load_cell_limit_N" in supervisor.trip_detail
    with pytest.raises(Exception, match="load cell"):
        supervisor.reset(1.0, health)
    health.measured_force_N = 0.0
    supervisor.reset(1.0, health)
    assert supervisor.state is State.IDLE


def test_the_profile_must_put_the_load_cell_limit_above_max_force_and_the_command_inside_the_cylinder() -> None:
    def problems(**changes: float) -> list[str]:
        return check_config(SafetyConfig(force=dataclasses.replace(FORCE, **changes)))

    healthy = MAX + FORCE.tracking_tolerance_N
    assert any("load_cell_limit_N" in p for p in problems(load_cell_limit_N=healthy))
    assert not any("load_cell_limit_N" in p for p in problems(load_cell_limit_N=healthy + 1.0))
    supply = MAX + FLOW
    assert not any("max_flow_term_N" in p for p in problems(supply_force_N=supply))
    assert any("max_flow_term_N" in p for p in problems(supply_force_N=supply - 1.0))
    [refusal] = [p for p in problems(supply_force_N=supply - 1.0) if "max_flow_term_N" in p]
    assert refusal == (
        f"force.max_force_N + force.max_flow_term_N ({supply:g} N) exceeds force.supply_force_N ({supply - 1.0:g} N): "
        "the command would ask a blocked piston for more than the cylinder gives, a flow the valve cannot pass "
        "(docs/SAFETY.md, What max_force_N must bound)"
    )


def test_a_tracking_tolerance_of_twice_max_force_is_refused_and_just_below_it_is_not() -> None:
    def problems(tolerance_N: float) -> list[str]:
        force = dataclasses.replace(FORCE, tracking_tolerance_N=tolerance_N, load_cell_limit_N=MAX + tolerance_N + 1.0)
        return [p for p in check_config(SafetyConfig(force=force)) if "tracking_tolerance_N" in p]

    assert problems(2 * MAX) == [
        f"force.tracking_tolerance_N ({2 * MAX:g} N) is at least twice force.max_force_N ({MAX:g} N): "
        "the tracking detector could never act"
    ]
    assert problems(2 * MAX - 1.0) == []


def test_load_cell_limits_detail_word_for_word_and_its_peak_from_zero() -> None:
    check = LoadCellLimit(FORCE)
    health = TickHealth()
    health.measured_force_N = -0.5  # below 1 N: a peak that started anywhere but 0 would not show it
    check.update(0.0, DT, health)
    assert check.peak_N == 0.5
    check.reset()
    health.measured_force_N = 0.25
    check.update(DT, DT, health)
    assert check.peak_N == 0.25
    health.measured_force_N = 13_000.0
    assert check.detail(health) == (
        f"load cell 13000 N beyond +/-{CELL:g} N (safety.force.load_cell_limit_N) "
        f"for {FORCE.load_cell_limit_time_s * 1e3:g} ms; expected within: the load path carries more than any "
        "healthy command gives (a blocked piston, a servo controller's feed-forward or loop out of bounds)"
    )
