"""TripOutputs alone, against a writer that records or fails: what a trip sends, when, and what it counts.

tests/unit/test_trip_actions.py proves the frames on a real bus; these pin the counters and
the failure paths that a bus cannot produce on demand (a send refused, a send that raises).
"""

from __future__ import annotations

import pytest

from harness.loop.trip_outputs import SUPERVISOR_SOURCE, TripOutputs
from harness.safety.config import TripActionsConfig
from harness.safety.events import CHECK_NAMES
from harness.safety.lifecycle import State

EVERY = 3
BOTH = TripActionsConfig(stroke=("disable", "estop", "stop_table"))


class Writer:
    """Records each ESTOP send as (active, now, source, reason); answers ``result`` or raises it."""

    def __init__(self, result: bool | Exception = True) -> None:
        self.result = result
        self.sent: list[tuple[bool, float, int, int]] = []

    def estop(self, active: bool, now: float, source: int, reason: int) -> bool:
        self.sent.append((active, now, source, reason))
        if isinstance(self.result, Exception):
            raise self.result
        return self.result


class TableStop:
    """Records each table stop's ``now``; raises ``error`` if given."""

    def __init__(self, error: Exception | None = None) -> None:
        self.error = error
        self.calls: list[float] = []

    def __call__(self, now: float) -> None:
        self.calls.append(now)
        if self.error is not None:
            raise self.error


def test_the_trip_tick_sends_the_estop_with_its_reason_and_stops_the_table_once() -> None:
    writer, table = Writer(), TableStop()
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    outputs.update(State.RUNNING, "", 1.0)
    assert writer.sent == [] and table.calls == []
    outputs.update(State.TRIPPED, "stroke_hard", 1.25)
    assert writer.sent == [(True, 1.25, SUPERVISOR_SOURCE, CHECK_NAMES.index("stroke_hard") + 1)]
    assert table.calls == [1.25]
    assert (outputs.estop_frames, outputs.table_stops, outputs.failures) == (1, 1, 0)
    assert outputs.estop_asserted


def test_the_estop_repeats_every_estop_every_ticks_while_tripped_and_stops_after() -> None:
    writer, table = Writer(), TableStop()
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    for k in range(1 + 3 * EVERY):
        outputs.update(State.TRIPPED, "stroke_hard", float(k))
    assert [now for _, now, _, _ in writer.sent] == [0.0, 3.0, 6.0, 9.0]
    assert (outputs.estop_frames, outputs.table_stops) == (4, 1)
    outputs.update(State.IDLE, "", 10.0)  # reset: no longer tripped
    assert not outputs.estop_asserted and len(writer.sent) == 4


@pytest.mark.parametrize("result", [False, OSError("ENOBUFS")], ids=["refused", "raised"])
def test_a_failed_estop_send_is_counted_once_per_attempt_and_never_raises(result: bool | Exception) -> None:
    writer = Writer(result)
    outputs = TripOutputs(writer, BOTH, EVERY)
    for k in range(1 + EVERY):
        outputs.update(State.TRIPPED, "stroke_hard", float(k))
    assert len(writer.sent) == 2
    assert (outputs.estop_frames, outputs.failures) == (0, 2)


def test_a_table_stop_that_raises_is_counted_and_the_trip_stands() -> None:
    writer, table = Writer(), TableStop(OSError("bus gone"))
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    outputs.update(State.TRIPPED, "stroke_hard", 2.0)
    assert table.calls == [2.0]
    assert (outputs.estop_frames, outputs.table_stops, outputs.failures) == (1, 0, 1)


def test_a_reason_of_no_known_check_sends_nothing_beyond_the_disable() -> None:
    writer, table = Writer(), TableStop()
    everything = TripActionsConfig(**{group: ("disable", "estop", "stop_table") for group in (
        "stroke", "sensor", "comms", "actuator", "loop", "operator", "internal")})
    outputs = TripOutputs(writer, everything, EVERY, table)
    outputs.update(State.TRIPPED, "no_such_check", 0.0)  # never raises
    assert writer.sent == [] and table.calls == [] and not outputs.estop_asserted
