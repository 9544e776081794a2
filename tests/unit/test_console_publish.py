"""The live console shows story drifts, floor accelerations, a scrolling list of events and the named fault code."""

from __future__ import annotations

import tracemalloc

from rich.console import Console

from drivers.protocol.protocol_values import DriveState, FaultCode
from harness.console.live import LiveConsole, fault_name
from harness.loop.status import LoopStatus
from harness.loop.status_block import EVENT_LINES
from tests.unit.test_control_tick import PERIOD_S, Bench


def _panel_text(status: LoopStatus, width: int = 80) -> str:
    console = Console(record=True, width=width)
    console.print(LiveConsole(status, 0.08, 0.1, 10_000.0, "title", console=console, enabled=False))
    return console.export_text()


def test_the_status_block_carries_stories_and_the_last_events_across_processes() -> None:
    with LoopStatus(n_stories=3) as status:
        for j in range(3):
            status.set_story(j, 0.001 * (j + 1), 0.5 * (j + 1))
        for k in range(EVENT_LINES + 2):
            status.add_event(f"event {k}")
        reader = LoopStatus.attach(status.path)
        try:
            assert reader.stories() == [(0.001, 0.5), (0.002, 1.0), (0.003, 1.5)]
            assert reader.recent_events() == [f"event {k}" for k in range(2, EVENT_LINES + 2)]
        finally:
            reader.close()


def test_the_panel_lists_drifts_floor_accelerations_events_and_names_the_fault() -> None:
    with LoopStatus(state="TRIPPED", trip_reason="drive_fault", fault_code=int(FaultCode.HEARTBEAT_WATCHDOG),
                    n_stories=3) as status:
        status.set_story(0, 0.00205, 0.656)
        status.set_story(2, 0.00059, 0.920)
        status.add_event("  1.110 s  interlock force_rate: ")
        status.add_event("  2.500 s  fault drive_fault: drive reports FAULT")
        text = _panel_text(status)
    assert "drive fault: HEARTBEAT_WATCHDOG (2)" in text
    assert "s3  +0.590" in text and "s1  +2.050" in text and "f3  +0.920" in text
    assert "1.110 s  interlock force_rate" in text and "2.500 s  fault drive_fault" in text
    assert max(len(line) for line in text.splitlines()) <= 80
    assert fault_name(77) == "code 77 (not a FaultCode)"


def test_the_tick_publishes_stories_fault_code_and_events_into_the_status() -> None:
    bench = Bench()
    try:
        with LoopStatus() as status:
            bench.tick.attach_status(status)
            rig = bench.rig.writer
            for _ in range(3):
                rig.drifts(0.001, 0.002, 0.003, bench.t)
                rig.accels(0.1, 0.2, 0.3, bench.t)
                bench.step()
            bench.supervisor.arm(bench.t, bench.tick.health)  # a state event for the list
            rig.actuator_status(0.0, DriveState.FAULT, True, FaultCode.HEARTBEAT_WATCHDOG, bench.t)
            bench.rig.writer.drifts(0.001, 0.002, 0.003, bench.t)
            bench.tick.run(bench.t, PERIOD_S, bench.t)
            assert status.stories() == [(0.001, 0.1), (0.002, 0.2), (0.003, 0.3)]
            assert status.fault_code == FaultCode.HEARTBEAT_WATCHDOG
            assert any("ARMED" in line for line in status.recent_events())
    finally:
        bench.close()


def test_publishing_allocates_nothing_that_outlives_the_tick() -> None:
    bench = Bench()
    try:
        with LoopStatus() as status:
            bench.tick.attach_status(status)
            bench.tick.publish(status)
            tracemalloc.start()
            before = tracemalloc.take_snapshot()
            for _ in range(1000):
                bench.tick.publish(status)
            after = tracemalloc.take_snapshot()
            tracemalloc.stop()
        grown = sum(stat.size_diff for stat in after.compare_to(before, "filename") if stat.size_diff > 0)
        assert grown < 2000, f"publishing grew memory by {grown} bytes over 1000 ticks"
    finally:
        bench.close()
