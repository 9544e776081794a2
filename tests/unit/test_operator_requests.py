"""An operator's request is never lost between the command line's handlers and the loop's (issue 30, item 1)."""

from __future__ import annotations

import os
import signal

import pytest

from harness.errors import StoppedByOperator
from harness.loop.operator import OperatorSignals, interruptible, request_pending, stop_if_requested
from harness.realtime.interrupts import stop_on_signals


def test_the_loops_handlers_take_over_a_pending_stop_and_hand_back_what_comes_during_the_run():
    with OperatorSignals() as early:
        os.kill(os.getpid(), signal.SIGINT)  # during the imports: a flag, no exception
        assert early.stop_requested and request_pending()
        with OperatorSignals() as loop:
            assert loop.stop_requested, "a stop pending at arming is the loop's too"
            os.kill(os.getpid(), signal.SIGINT)
            assert loop.trip_requested
        assert early.trip_requested and early.interrupts == 2, "what came during the run counts after it"


def test_a_sigterm_before_the_loop_is_taken_over_as_a_trip():
    with OperatorSignals() as early:
        os.kill(os.getpid(), signal.SIGTERM)
        with OperatorSignals() as loop:
            assert loop.trip_requested and loop.what == "SIGTERM"
        assert early.requested


def test_a_safe_point_ends_the_command_only_when_a_request_is_pending():
    with OperatorSignals():
        stop_if_requested("while nothing was asked")  # no request: goes on
        os.kill(os.getpid(), signal.SIGINT)
        with pytest.raises(StoppedByOperator, match="before anything moved, while loading"):
            stop_if_requested("while loading")


def test_a_question_at_the_terminal_is_ended_by_ctrl_c_at_once():
    with OperatorSignals() as signals, pytest.raises(StoppedByOperator, match="at the question"):
        with interruptible("at the question"):
            os.kill(os.getpid(), signal.SIGINT)  # input() would wait on after a handler that only sets a flag
            pytest.fail("the Ctrl-C did not end the block")
    assert not signals.raise_interrupt


def test_a_serving_process_stops_at_once_for_a_request_made_before_it_served():
    with OperatorSignals():
        os.kill(os.getpid(), signal.SIGINT)
        with pytest.raises(KeyboardInterrupt), stop_on_signals():
            pytest.fail("served although a stop was pending")
