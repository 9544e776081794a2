"""A loop stall is named as the stall, not as what it let happen: the supervisor's order and the loop's gap trace."""

from __future__ import annotations

import pytest

from drivers.protocol.protocol_values import DriveState, FaultCode
from harness.loop.timing import GAP_PARTS, GapTrace
from harness.safety.config import SafetyConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor
from tests.unit.test_control_tick import Bench

PERIOD_S = 0.002


def _running() -> tuple[Supervisor, TickHealth]:
    supervisor, health = Supervisor(SafetyConfig(), period_s=PERIOD_S), TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    health.table_fresh = health.base_fresh = False
    return supervisor, health


def test_a_stall_and_the_drives_watchdog_fault_in_one_tick_trip_loop_stall_naming_both() -> None:
    supervisor, health = _running()
    supervisor.update(PERIOD_S, PERIOD_S, health, 0.0)
    health.stall_s, health.missed_periods = 0.1013, 49  # the loop was away longer than the drive's 50 ms watchdog
    health.drive_fault, health.drive_ready, health.drive_fault_code = True, False, int(FaultCode.HEARTBEAT_WATCHDOG)
    command = supervisor.update(0.104, 0.102, health, 0.0)
    assert supervisor.state is State.TRIPPED and command.trip_reason == "loop_stall"
    detail = supervisor.trip_detail
    assert "101.3 ms without a command (49 missed periods)" in detail
    assert "fault code 2 (HEARTBEAT_WATCHDOG) after it, a consequence of the stall" in detail
    assert command.force_N == 0.0 and not command.enable


def test_a_drive_fault_with_no_stall_is_the_drives_and_names_its_code() -> None:
    supervisor, health = _running()
    health.stall_s = 0.02  # at the budget: ridden through
    health.drive_fault, health.drive_fault_code = True, int(FaultCode.PRESSURE_LOST)
    command = supervisor.update(PERIOD_S, PERIOD_S, health, 0.0)
    assert command.trip_reason == "drive_fault"
    assert supervisor.trip_detail == "actuator drive reports a fault: fault code 3 (PRESSURE_LOST)"


def test_a_stall_alone_names_no_drive_fault() -> None:
    supervisor, health = _running()
    health.stall_s, health.missed_periods = 0.045, 21
    supervisor.update(PERIOD_S, PERIOD_S, health, 0.0)
    assert supervisor.command.trip_reason == "loop_stall" and "drive" not in supervisor.trip_detail


def test_the_operators_estop_in_the_same_tick_as_a_stall_is_the_operators() -> None:
    supervisor, health = _running()
    health.stall_s, health.estop = 0.1, True
    supervisor.update(PERIOD_S, PERIOD_S, health, 0.0)
    assert supervisor.command.trip_reason == "estop"  # the operator's act is no consequence of the stall


class Clock:
    """A clock a test moves by hand."""

    def __init__(self) -> None:
        self.now = 10.0

    def __call__(self) -> float:
        return self.now


def test_the_gap_trace_splits_a_gap_into_its_parts_and_names_the_longest() -> None:
    clock = Clock()
    trace = GapTrace(clock)
    trace.woke()  # the first tick begins at 10.0
    spent_ms = {"read": 0.1, "control": 0.3, "supervise": 0.06, "write": 0.02, "record": 0.2, "phase": 95.0}
    for part, name in enumerate(GAP_PARTS[:-1]):
        clock.now += spent_ms[name] * 1e-3
        trace.mark(part)
    clock.now += 1.5e-3  # the wait
    trace.woke()
    expected = [*(spent_ms[name] * 1e-3 for name in GAP_PARTS[:-1]), 1.5e-3]
    assert trace.parts_s == pytest.approx(expected, abs=1e-12)
    assert GAP_PARTS[trace.longest_part()] == "phase"
    words = trace.describe()
    assert words.startswith("the loop was the loop's phases, console status and timing for 95.0 ms (phase; parts in ms:")
    assert "read 0.1, control 0.3, supervise 0.1, write 0.0, record 0.2, phase 95.0, wait 1.5)" in words
    assert trace.marks[0] == clock.now  # the next tick begins where the wait ended


def test_a_part_the_tick_skipped_counts_nothing_and_the_wait_takes_the_rest() -> None:
    clock = Clock()
    trace = GapTrace(clock)
    trace.woke()
    clock.now += 0.001
    trace.mark(0)  # read
    clock.now += 0.002
    trace.mark(2)  # supervise: control was skipped (the controller raised)
    clock.now += 0.120  # then the loop stalled before it wrote anything more
    trace.woke()
    assert trace.parts_s == pytest.approx([0.001, 0.0, 0.002, 0.0, 0.0, 0.0, 0.120], abs=1e-12)
    assert GAP_PARTS[trace.longest_part()] == "wait"
    assert trace.describe().startswith("the loop was waiting for the next deadline (sleep and spin) for 120.0 ms (wait;")


def test_the_first_part_wins_a_tie() -> None:
    clock = Clock()
    trace = GapTrace(clock)
    trace.woke()
    for part in range(len(GAP_PARTS) - 1):
        clock.now += 0.001
        trace.mark(part)
    clock.now += 0.001
    trace.woke()
    assert trace.longest_part() == 0


class Counter:
    """A clock that reads 1, 2, 3, ...: the order of the marks, one read each."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        self.now += 1.0
        return self.now


def test_the_tick_marks_each_of_its_parts_once_in_order() -> None:
    bench = Bench()
    try:
        bench.tick.trace = GapTrace(Counter())
        bench.step()
        assert bench.tick.trace.marks == [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 0.0, 0.0]  # read .. record; phase and wait: the loop's
        bench.controller.raise_next = True
        bench.tick.trace = GapTrace(Counter())
        bench.step()  # the controller raises: the control part is skipped, the rest still marked
        assert bench.tick.trace.marks == [0.0, 1.0, 0.0, 2.0, 3.0, 4.0, 0.0, 0.0]
    finally:
        bench.close()


def test_the_tick_reads_the_drives_fault_code_and_drive_fault_names_it() -> None:
    bench = Bench()
    try:
        bench.run_until_running()
        bench.publish()
        bench.rig.writer.actuator_status(0.0, DriveState.FAULT, True, FaultCode.HEARTBEAT_WATCHDOG, bench.t)
        command = bench.tick.run(bench.t, PERIOD_S, bench.t)
        assert bench.tick.health.drive_fault_code == int(FaultCode.HEARTBEAT_WATCHDOG)
        assert command.trip_reason == "drive_fault"  # no stall: the drive's own fault
        assert bench.supervisor.trip_detail == "actuator drive reports a fault: fault code 2 (HEARTBEAT_WATCHDOG)"
    finally:
        bench.close()


def test_a_gap_past_the_budget_before_arming_is_recorded_and_named_in_a_refusal_to_arm() -> None:
    from harness.loop.runner import ControlLoop
    from harness.profile import load_profile

    bench = Bench()
    try:
        loop = ControlLoop(bench.tick, load_profile(None).loop, 1.0 / PERIOD_S, 1.0)
        assert loop._stall_note() == ""  # no gap past the budget yet: nothing to add
        drained: list[tuple[str, str]] = []
        missed = loop._note_stall(0.3, 0.0199, 0.3)  # within the budget: ridden through, not past it
        assert missed == 8 and loop.gaps_past_budget == 0 and loop.stalls_ridden_through == 1 and loop.counts.stalls == 1
        missed = loop._note_stall(0.5, 0.1013, 0.5014)  # in IDLE (the loop's phase before arming)
        assert missed == 49 and loop.gaps_past_budget == 1 and loop.stalls_ridden_through == 1
        assert (loop.counts.stalls, loop.counts.missed_periods) == (2, 8 + 49)  # every stall, ridden through or not
        assert loop.longest_stall_s == 0.1013 and loop.last_gap_past_budget_s == 0.1013
        bench.supervisor.events.drain(lambda t, kind, name, detail: drained.append((name, detail)))
        name, detail = drained[-1]
        assert name == "stall_past_budget"
        assert detail.startswith("101.3 ms between two ticks (49 missed periods), past the 20.0 ms stall budget: "
                                 "from 0.4001 s to 0.5014 s (loop time), begun in IDLE; the loop was ")
        note = loop._stall_note()
        assert note.startswith("; the loop itself stalled 101.3 ms up to t = 0.500 s, past its 20.0 ms stall budget")
        assert "a drive's watchdog fault after it is the stall's" in note
    finally:
        bench.close()
