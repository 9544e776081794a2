"""One rule for how a run ended (harness/loop/ending.py), used by the loop and the twin."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from harness.loop.ending import run_ending
from harness.safety.lifecycle import State


def _supervisor(state: State, trip_reason: str = "", stop_reason: str = "") -> SimpleNamespace:
    return SimpleNamespace(
        state=state, command=SimpleNamespace(trip_reason=trip_reason), trip_detail="trip detail" if trip_reason else "",
        stop_reason=stop_reason, stop_detail="stop detail" if stop_reason else "",
    )


def test_done_completed_and_tripped_carries_the_trips_reason_and_detail() -> None:
    done = run_ending(_supervisor(State.DONE))
    assert (done.outcome, done.reason, done.detail) == ("completed", "", "")
    ending = run_ending(_supervisor(State.TRIPPED, trip_reason="stroke_hard"))
    assert (ending.outcome, ending.reason, ending.detail) == ("tripped", "stroke_hard", "trip detail")


def test_an_operator_stop_or_a_checks_safe_stop_is_stopped_with_the_checks_name() -> None:
    operator = run_ending(_supervisor(State.DONE), stop_requested=True)
    assert (operator.outcome, operator.reason, operator.detail) == ("stopped", "", "")
    check = run_ending(_supervisor(State.DONE, stop_reason="force_oscillation"))
    assert (check.outcome, check.reason, check.detail) == ("stopped", "force_oscillation", "stop detail")


@pytest.mark.parametrize("state", [State.IDLE, State.ARMED, State.RUNNING, State.STOPPING])
def test_a_loop_that_left_before_done_or_a_trip_is_stopped(state: State) -> None:
    assert run_ending(_supervisor(state)).outcome == "stopped"


def test_the_twin_whose_record_ran_out_while_running_completed_unless_a_check_stopped_it() -> None:
    assert run_ending(_supervisor(State.RUNNING), record_ended=True).outcome == "completed"
    assert run_ending(_supervisor(State.STOPPING), record_ended=True).outcome == "stopped"
    stopped = run_ending(_supervisor(State.DONE, stop_reason="load_cell_limit"), record_ended=True)
    assert (stopped.outcome, stopped.reason) == ("stopped", "load_cell_limit")
