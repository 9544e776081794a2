"""A run's story as the event log tells it: each state change's time and words, the loop-timing
trip's detail, and the table check's end of record and cadence (mutation survivors)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.safety.lifecycle import IllegalTransition, State
from harness.safety.table_record import EVALUATE_EVERY_S, TableRecordCheck
from harness.safety.weakening import is_weaker
from tests.unit.test_supervisor_late_clock import DT, _running, _tick


def _drained(supervisor) -> list[tuple]:
    events: list[tuple] = []
    supervisor.events.drain(lambda *event: events.append(event))
    return events


def test_each_state_change_is_stamped_and_worded() -> None:
    supervisor, health = _running(1.0)
    assert [e for e in _drained(supervisor) if e[1] == "state"] == [
        (1.0, "state", "ARMED", "IDLE -> ARMED: armed: all pre-arm checks passed"),
        (1.0, "state", "RUNNING", "ARMED -> RUNNING: start"),
    ]
    assert supervisor.lifecycle.entered_s == 1.0
    command = _tick(supervisor, health, 1.002, 100.0)
    assert command.t == 1.002 and command.trip_reason == "" and command.enable
    supervisor.stop(1.004)
    assert supervisor.lifecycle.entered_s == 1.004
    t = 1.004
    while supervisor.state is State.STOPPING:
        t += DT
        command = _tick(supervisor, health, t, 0.0)
    assert command.t == t and supervisor.lifecycle.entered_s == t
    assert [e for e in _drained(supervisor) if e[1] == "state"] == [
        (1.004, "state", "STOPPING", "RUNNING -> STOPPING: stop requested"),
        (t, "state", "DONE", "STOPPING -> DONE: stopping ramp complete"),
    ]
    assert command.state is State.DONE and command.trip_reason == ""
    supervisor.trip(t + 1.0, "operator_trip")
    assert supervisor.lifecycle.trip_detail == ""


def test_arming_outside_idle_is_illegal_whatever_the_health() -> None:
    supervisor, health = _running(1.0)
    health.drive_ready = False  # a pre-arm check would fail, but arming is not even legal here
    with pytest.raises(IllegalTransition):
        supervisor.arm(1.01, health)


@pytest.mark.parametrize(("t", "dt", "at"), [(math.nan, DT, 0.0), (5.0, 0.0, 5.0), (5.0, math.inf, 5.0)])
def test_a_tick_with_an_impossible_clock_trips_loop_timing_naming_it(t: float, dt: float, at: float) -> None:
    supervisor, health = _running(1.0)
    command = supervisor.update(t, dt, health, 0.0)
    assert command.state is State.TRIPPED and supervisor.lifecycle.trip_reason == "loop_timing"
    assert supervisor.lifecycle.trip_detail == f"t = {t!r} s, dt = {dt!r} s, expected finite t and dt > 0"
    assert supervisor.lifecycle.entered_s == at


def _told(seconds: float = 4.0) -> np.ndarray:
    rng = np.random.default_rng(3)
    tt = np.arange(0.0, seconds, DT)
    v = sum(rng.normal() * np.sin(2 * np.pi * f * tt + rng.uniform(0, 6.28)) for f in rng.uniform(0.5, 4.0, 20))
    return 0.1 * v / np.std(v)


def test_the_table_check_evaluates_every_half_second_then_once_at_the_records_end() -> None:
    told = _told()
    check = TableRecordCheck(0.02)
    check.expect(told, DT, (told.size - 1) * DT, DT)
    length = check.tracking.length
    judged: list[float] = []
    check.update(0.0, float(told[0]))
    assert check.tracking.count == 1, "record time 0 is the record's first sample"
    for n in range(1, length):
        before = check.evaluations
        check.update(n * DT, float(told[n]))
        if check.evaluations > before:
            judged.append(check.judged_at_s)
    assert judged[0] == pytest.approx(check.gate * DT) and np.allclose(np.diff(judged), EVALUATE_EVERY_S, atol=1e-9)
    during = check.evaluations
    check.update(length * DT, 0.0)  # the first tick past the record's end: judged once more, over all of it
    assert check.evaluations == during + 1 and check.judged_at_s == pytest.approx((length - 1) * DT)
    for n in range(length + 1, length + 5):
        check.update(n * DT, 0.0)
    assert check.evaluations == during + 1, "the record has ended: no more evaluations"


def test_a_record_never_gated_is_not_judged_at_its_end_either() -> None:
    quiet = np.full(1500, 1e-4)
    check = TableRecordCheck(0.02)
    check.expect(quiet, DT, (quiet.size - 1) * DT, DT)
    for n in range(quiet.size + 3):
        check.update(n * DT, 1e-4)
    assert check.gate is None and check.evaluations == 0


def test_an_unknown_direction_is_refused_naming_the_known_ones() -> None:
    with pytest.raises(ValueError, match=r"unknown direction 'sideways', expected one of larger, smaller, milder, fewer, off"):
        is_weaker("sideways", 1.0, 2.0)  # type: ignore[arg-type]
