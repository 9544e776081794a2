"""Tests of the run lifecycle: legal and illegal transitions, the latch, enable rules."""

from __future__ import annotations

import itertools

import pytest

from harness.errors import SafetyError
from harness.safety.config import SafetyConfig, SensorConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import (
    DRIVE_STATES,
    TRANSITIONS,
    ArmRefused,
    IllegalTransition,
    Lifecycle,
    Request,
    ResetRefused,
    State,
)
from harness.safety.supervisor import Supervisor

#: A path from IDLE to each state, as requests.
_PATHS: dict[State, tuple[Request, ...]] = {
    State.IDLE: (),
    State.ARMED: (Request.ARM,),
    State.RUNNING: (Request.ARM, Request.START),
    State.STOPPING: (Request.ARM, Request.START, Request.STOP),
    State.DONE: (Request.ARM, Request.START, Request.STOP, Request.FINISH),
    State.TRIPPED: (Request.TRIP,),
}

_EXPECTED_LEGAL = {
    (State.IDLE, Request.ARM): State.ARMED,
    (State.ARMED, Request.START): State.RUNNING,
    (State.ARMED, Request.STOP): State.STOPPING,
    (State.RUNNING, Request.STOP): State.STOPPING,
    (State.STOPPING, Request.FINISH): State.DONE,
    (State.TRIPPED, Request.RESET): State.IDLE,
    (State.DONE, Request.RESET): State.IDLE,
    **{(s, Request.TRIP): State.TRIPPED for s in State},
}


def _apply(lc: Lifecycle, request: Request, t: float = 0.0) -> None:
    if request is Request.ARM:
        lc.arm(t)
    elif request is Request.START:
        lc.start(t)
    elif request is Request.STOP:
        lc.stop(t)
    elif request is Request.FINISH:
        lc.finish(t)
    elif request is Request.TRIP:
        lc.trip(t, "estop", "test")
    else:
        lc.reset(t)


def _in_state(state: State) -> Lifecycle:
    lc = Lifecycle()
    for request in _PATHS[state]:
        _apply(lc, request)
    assert lc.state is state
    return lc


def test_transition_table_is_the_documented_one() -> None:
    assert TRANSITIONS == _EXPECTED_LEGAL


@pytest.mark.parametrize(("state", "req"), list(itertools.product(State, Request)))
def test_every_state_request_pair(state: State, req: Request) -> None:
    lc = _in_state(state)
    target = _EXPECTED_LEGAL.get((state, req))
    if target is None:
        with pytest.raises(SafetyError) as info:
            _apply(lc, req, t=1.0)
        assert isinstance(info.value, IllegalTransition)
        assert state.name in str(info.value) and req.name in str(info.value)
        assert lc.state is state
    else:
        _apply(lc, req, t=1.0)
        assert lc.state is target
        assert lc.entered_s == (1.0 if (state, target) != (State.TRIPPED, State.TRIPPED) else 0.0)


def test_drive_enabled_only_in_armed_running_stopping() -> None:
    for state in State:
        assert _in_state(state).drive_enabled == (state in (State.ARMED, State.RUNNING, State.STOPPING))
    assert DRIVE_STATES == {State.ARMED, State.RUNNING, State.STOPPING}


def test_arm_with_failed_checks_is_refused_and_names_them() -> None:
    lc = Lifecycle()
    with pytest.raises(ArmRefused) as info:
        lc.arm(0.0, ("stroke_centred: far", "hydraulic_pressure: low"))
    assert info.value.failed == ("stroke_centred: far", "hydraulic_pressure: low")
    assert "stroke_centred" in str(info.value) and "hydraulic_pressure" in str(info.value)
    assert lc.state is State.IDLE


def test_trip_latches_first_reason_until_reset() -> None:
    lc = _in_state(State.RUNNING)
    assert lc.trip(2.0, "stroke_hard", "x")
    assert not lc.trip(3.0, "estop", "y")
    assert (lc.state, lc.trip_reason, lc.entered_s) == (State.TRIPPED, "stroke_hard", 2.0)
    for request in (Request.ARM, Request.START, Request.STOP, Request.FINISH):
        with pytest.raises(IllegalTransition):
            _apply(lc, request)
        assert lc.trip_reason == "stroke_hard"
    lc.reset(4.0)
    assert (lc.state, lc.trip_reason) == (State.IDLE, "")


def test_reset_refused_while_condition_present() -> None:
    lc = _in_state(State.TRIPPED)
    with pytest.raises(ResetRefused) as info:
        lc.reset(1.0, still_present="E-stop is asserted")
    assert "E-stop is asserted" in str(info.value) and info.value.reason == "estop"
    assert lc.state is State.TRIPPED
    lc.reset(2.0)
    assert lc.state is State.IDLE


# --------------------------------------------------------------- through the supervisor

DT = 0.004


def _armed_running(config: SafetyConfig | None = None) -> tuple[Supervisor, TickHealth]:
    sup = Supervisor(config or SafetyConfig())
    health = TickHealth()
    sup.arm(0.0, health)
    sup.start(0.0)
    return sup, health


def _tick(sup: Supervisor, health: TickHealth, k: int, force: float) -> None:
    health.measured_force_N = sup.command.force_N
    sup.update(k * DT, DT, health, force)


def test_supervisor_zero_and_disabled_on_the_trip_tick() -> None:
    sup, health = _armed_running()
    for k in range(1, 20):
        _tick(sup, health, k, 4000.0)
    assert sup.command.enable and sup.command.force_N == pytest.approx(4000.0)
    health.estop = True
    health.measured_force_N = sup.command.force_N
    command = sup.update(20 * DT, DT, health, 4000.0)
    assert (command.force_N, command.enable, command.state, command.trip_reason) == (0.0, False, State.TRIPPED, "estop")


def test_supervisor_latch_holds_until_reset_and_reset_needs_condition_gone() -> None:
    sup, health = _armed_running()
    health.estop = True
    sup.update(DT, DT, health, 100.0)
    health.estop = False  # the trip condition clears by itself: still latched
    for k in range(2, 50):
        command = sup.update(k * DT, DT, health, 100.0)
        assert (command.force_N, command.enable, command.state) == (0.0, False, State.TRIPPED)
    health.estop = True
    with pytest.raises(ResetRefused):
        sup.reset(1.0, health)
    health.estop = False
    sup.reset(1.0, health)
    assert sup.state is State.IDLE and sup.command.trip_reason == ""
    command = sup.update(1.0 + DT, DT, health, 100.0)
    assert (command.force_N, command.enable) == (0.0, False)


def test_estop_in_idle_latches_and_blocks_arming() -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth(estop=True)
    sup.update(0.0, DT, health, 0.0)
    assert sup.state is State.TRIPPED
    with pytest.raises(IllegalTransition):
        sup.arm(DT, health)


def test_armed_enables_the_drive_at_zero_force() -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth()
    sup.arm(0.0, health)
    command = sup.update(DT, DT, health, 5000.0)
    assert (command.enable, command.force_N, command.state) == (True, 0.0, State.ARMED)


@pytest.mark.parametrize("ramp_s", [0.2, 0.5, 1.0])
def test_stopping_ramps_to_zero_within_the_ramp_time_then_disables(ramp_s: float) -> None:
    config = SafetyConfig()
    # the measurements here are noise-free, so every channel repeats to the bit: a real sensor's never
    # does, and sensor_stuck would (rightly) trip after stuck_samples ticks; this test is about the ramp
    config = type(config)(run=type(config.run)(stopping_ramp_s=ramp_s), sensors=SensorConfig(stuck_samples=10**6))
    sup, health = _armed_running(config)
    force = 5000.0
    for k in range(1, 50):
        _tick(sup, health, k, force)
    t_stop = 50 * DT
    sup.stop(t_stop)
    previous = sup.command.force_N
    k = 50
    while sup.state is State.STOPPING:
        k += 1
        _tick(sup, health, k, force)
        elapsed = k * DT - t_stop
        if sup.state is State.STOPPING:
            expected = force * max(0.0, 1.0 - elapsed / ramp_s)
            assert sup.command.force_N == pytest.approx(expected, abs=1e-6)
            assert sup.command.enable
            assert abs(sup.command.force_N) <= abs(previous) + 1e-9
        previous = sup.command.force_N
        assert k < 1000
    done_at = k * DT - t_stop
    assert ramp_s - 1e-9 <= done_at <= ramp_s + DT + 1e-9
    assert (sup.command.state, sup.command.enable, sup.command.force_N) == (State.DONE, False, 0.0)


def test_stop_from_armed_finishes_without_force() -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth()
    sup.arm(0.0, health)
    sup.stop(DT)
    command = sup.update(2 * DT, DT, health, 9000.0)
    assert (command.state, command.enable, command.force_N) == (State.DONE, False, 0.0)


def test_illegal_requests_through_supervisor_raise_safety_error() -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth()
    with pytest.raises(SafetyError, match="START refused in state IDLE"):
        sup.start(0.0)
    with pytest.raises(SafetyError, match="RESET refused in state IDLE"):
        sup.reset(0.0, health)
    sup.arm(0.0, health)
    with pytest.raises(SafetyError, match="ARM refused in state ARMED"):
        sup.arm(0.0, health)
