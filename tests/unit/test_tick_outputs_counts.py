"""Counters and stamps of the tick and its trip outputs that a run's record and console show
(mutation survivors: each kept its value by luck of a single event)."""

from __future__ import annotations

import pytest

from drivers.protocol.codec import load_protocol
from drivers.protocol.decoder import Decoder, RxStatus
from harness.loop.trip_outputs import TripOutputs
from harness.safety.lifecycle import State
from tests.unit.test_control_tick import Bench
from tests.unit.test_trip_actions import BOTH, EVERY, RecordingWriter, TableStop


def test_table_stops_and_failures_count_every_one() -> None:
    table = TableStop()
    outputs = TripOutputs(RecordingWriter(), BOTH, EVERY, table)
    for trip in range(2):  # trip, reset, trip again: two table stops
        outputs.update(State.TRIPPED, "stroke_hard", float(trip))
        outputs.update(State.IDLE, "", float(trip) + 0.5)
    assert outputs.table_stops == 2 and table.calls == [0.0, 1.0]
    failing = TripOutputs(RecordingWriter(False), BOTH, EVERY, TableStop(OSError("bus gone")))
    for trip in range(2):
        failing.update(State.TRIPPED, "stroke_hard", float(trip))
        failing.update(State.IDLE, "", float(trip) + 0.5)
    assert failing.failures == 4, "each refused ESTOP and each table stop that raised"


def test_a_safe_stops_table_stop_that_fails_adds_one_failure_to_those_before() -> None:
    outputs = TripOutputs(RecordingWriter(False), BOTH, EVERY, TableStop(OSError("bus gone")))
    outputs.update(State.TRIPPED, "stroke_hard", 0.0)  # the ESTOP refused and the trip's table stop raised: 2
    outputs.update(State.IDLE, "", 0.5)
    assert outputs.failures == 2
    outputs.stop_the_table(1.0)
    assert outputs.failures == 3 and outputs.table_stops == 0
    outputs.stop_the_table(1.1)
    assert outputs.failures == 3, "once per run"


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def test_the_tick_reports_whether_this_tick_brought_fresh_table_and_base_samples(bench) -> None:
    bench.step()
    assert bench.tick.health.table_fresh is True and bench.tick.health.base_fresh is True
    bench.publish_sensors = False
    bench.step()
    assert bench.tick.health.table_fresh is False and bench.tick.health.base_fresh is False


def test_the_tick_reports_whether_this_tick_brought_a_fresh_load_cell_sample(bench) -> None:
    """``force_oscillation`` filters the load cell once per sample (its ACTUATOR_STATUS frame), not per tick."""
    bench.step()
    assert bench.tick.health.actuator_status_fresh is True
    bench.publish_status = False
    bench.step()
    assert bench.tick.health.actuator_status_fresh is False
    bench.publish_status = True
    bench.step()
    assert bench.tick.health.actuator_status_fresh is True


def test_a_controller_exception_trips_at_the_ticks_time_naming_the_exception(bench) -> None:
    bench.run_until_running()
    bench.controller.raise_next = True
    t = bench.t
    command, sent = bench.step()
    assert sent == (False, 0.0) and command.state is State.TRIPPED
    supervisor = bench.supervisor
    assert supervisor.lifecycle.trip_reason == "tick_exception"
    assert supervisor.lifecycle.trip_detail == "RuntimeError: controller bug"
    assert supervisor.lifecycle.entered_s == pytest.approx(t), "tripped at the tick's own time"


def test_the_ticks_cpu_time_is_its_own(bench) -> None:
    for _ in range(5):
        bench.step()
        assert 0.0 <= bench.tick.cpu_s < 0.05, bench.tick.cpu_s  # one tick's CPU, not the thread's since it began


def test_reset_counter_forgets_one_messages_counter_only() -> None:
    protocol = load_protocol()
    decoder = Decoder(protocol)
    table, base = protocol["TABLE_SENSORS"], protocol["BASE_SENSORS"]
    zeros = [0.0] * len(table.signal_names)
    for codec in (table, base):
        assert decoder.decode(codec.frame_id, codec.encode(zeros, 3)) is RxStatus.OK
    decoder.reset_counter(table.frame_id)
    assert decoder.decode(table.frame_id, table.encode(zeros, 9)) is RxStatus.OK, "forgotten: any counter is first"
    assert decoder.decode(base.frame_id, base.encode(zeros, 9)) is RxStatus.SKIPPED_COUNTER, "the other message kept its"
    decoder.reset_counter(0x7FF)  # an ID the protocol does not have: nothing to forget, no error


def _internal_stops_the_table():
    import dataclasses

    from harness.safety.config import TripActionsConfig
    from tests.unit.test_trip_actions import SAFETY

    return dataclasses.replace(SAFETY, trip_actions=TripActionsConfig(internal=("disable", "estop", "stop_table")))


def test_the_tick_hands_its_table_stop_on_and_stops_the_table_only_when_a_trip_asks() -> None:
    from harness.loop.tick import ControlTick

    b = Bench(_internal_stops_the_table())
    try:
        stops: list[float] = []
        b.tick = ControlTick(b.link, b.controller, b.tick.estimator, b.supervisor, None, heartbeat_every=1,
                             stop_table=stops.append)
        b.run_until_running()
        assert stops == [], "no check asked: the table plays on"
        b.controller.raise_next = True
        t = b.t
        b.step()
        assert stops == [t], "the trip tick stops the table, stamped with the tick's clock"
    finally:
        b.close()


def test_a_command_that_cannot_be_sent_trips_at_the_ticks_time_naming_why(bench) -> None:
    from harness.signals import columns as layout

    bench.run_until_running()
    enabled = layout.CONTROL_ROW.index(layout.DRIVE_ENABLED)
    assert bench.tick.row[enabled] == 1.0, "the recorded row says the drive is enabled"

    def refuse(*args) -> bool:
        raise OSError("ENOBUFS")

    bench.tick.writer.command = refuse
    bench.publish()
    t = bench.t
    command = bench.tick.run(t, 0.002, t)
    assert command.state is State.TRIPPED and bench.supervisor.lifecycle.trip_reason == "tick_exception"
    assert bench.supervisor.lifecycle.trip_detail == "OSError: ENOBUFS"
    assert bench.supervisor.lifecycle.entered_s == pytest.approx(t)
    assert bench.tick.disable_failures == 1, "the disable that followed could not be sent either: counted"
    assert bench.tick.row[enabled] == 0.0
