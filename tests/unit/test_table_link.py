"""``harness run``'s link to the table controller (``table.link: can``): start, stop, and record time
counted from the controller's RIG_STATUS ``table_running``."""

from __future__ import annotations

import pytest

from drivers.protocol.protocol_values import RigCommand
from harness.loop.config import LoopConfig
from harness.loop.runner import TABLE_START_TIMEOUT_S, ControlLoop
from harness.loop.table_link import CanTableLink
from harness.profile import load_profile
from harness.safety.lifecycle import State
from tests.unit.test_control_tick import Bench


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def test_the_link_sends_start_and_stop_and_reads_running(bench):
    link = CanTableLink()
    link.attach(bench.link)
    control = bench.rig_side.sample("RIG_CONTROL")
    link.start(0.0)
    bench.rig_side.poll(0.0)
    assert control.values[control.index("command")] == RigCommand.START_TABLE
    assert link.stop(0.01)
    bench.rig_side.poll(0.01)
    assert control.values[control.index("command")] == RigCommand.STOP_TABLE and (link.starts, link.stops) == (1, 1)
    assert not link.running()
    bench.rig.writer.rig_status(True, False, False, 0.0, 0, 0.02)
    bench.tick.reader.poll(0.02)
    assert link.running()


def _loop_waiting_for_the_table(bench, running: list[bool]) -> ControlLoop:
    loop = ControlLoop(bench.tick, LoopConfig(), 500.0, 1.0, table_running=lambda: running[0])
    bench.run_until_running()
    loop._awaiting_table = True
    return loop


def test_record_time_counts_from_the_table_reporting_running(bench):
    running = [False]
    loop = _loop_waiting_for_the_table(bench, running)
    started, _, _ = loop._phase(0.3, 0.0, 1.0, 0.0)
    assert started == 0.0, "not running yet: record time has not begun"
    running[0] = True
    started, _, _ = loop._phase(0.5, started, 1.0, 0.0)
    assert started == 0.5 and bench.supervisor.state is State.RUNNING
    started, _, _ = loop._phase(0.5 + 1.0 + LoopConfig().tail_s - 0.01, started, 1.0, 0.0)
    assert bench.supervisor.state is State.RUNNING, "the record runs its whole length from the table's start"


def test_a_table_that_never_runs_stops_the_run_safely(bench):
    loop = _loop_waiting_for_the_table(bench, [False])
    loop._phase(TABLE_START_TIMEOUT_S, 0.0, 1.0, 0.0)
    assert bench.supervisor.state is State.STOPPING


def test_table_link_is_validated_like_every_profile_key():
    assert load_profile(None).table.link == "can"
    assert load_profile(None, overrides=["table.link=none"]).table.link == "none"
    from harness.errors import ProfileError

    with pytest.raises(ProfileError, match="table.link"):
        load_profile(None, overrides=["table.link=wifi"])
