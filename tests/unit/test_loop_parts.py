"""Loop parts that need no bus: real-time requests, timing statistics, operator signals, the console."""

from __future__ import annotations

import gc
import os
import signal

import numpy as np
import pytest
from rich.console import Console

from harness.console.live import LiveConsole, stroke_bar
from harness.loop.operator import OperatorSignals
from harness.loop.status import LoopStatus
from harness.loop.timing import TimingStats
from harness.realtime.config import RealtimeConfig
from harness.realtime.host import apply_realtime, restore_realtime


def test_realtime_requests_are_granted_or_refused_plainly_and_gc_is_restored():
    was_enabled = gc.isenabled()
    cpu = sorted(os.sched_getaffinity(0))[0]
    report = apply_realtime(RealtimeConfig(fifo_priority=1, cpu_affinity=(cpu,), lock_memory=False, disable_gc=True))
    try:
        assert not gc.isenabled()
        fifo = next(line for line in report.lines if line.startswith("SCHED_FIFO"))
        assert ": granted" in fifo or "refused" in fifo and "CAP_SYS_NICE" in fifo
        assert any(line.startswith(f"CPU affinity [{cpu}]") for line in report.lines)
    finally:
        restore_realtime(report)  # gives the priority back
        os.sched_setaffinity(0, set(range(os.cpu_count() or 1)))
    assert gc.isenabled() == was_enabled


def test_nothing_is_requested_when_nothing_is_asked():
    report = apply_realtime(RealtimeConfig(fifo_priority=0, disable_gc=False))
    restore_realtime(report)
    assert report.lines == []


def test_timing_statistics_summarise_what_was_added():
    stats = TimingStats(1000)
    for k in range(2000):  # more than the capacity: counters go on, arrays stop
        stats.add(k * 1e-6, 5e-5, 4e-5)
    summary = stats.summary()
    assert summary["ticks"] == 2000
    assert summary["lateness_max_s"] == pytest.approx(999e-6)
    assert summary["lateness_median_s"] == pytest.approx(np.median(np.arange(1000) * 1e-6))
    assert summary["compute_median_s"] == 5e-5
    assert summary["cpu_median_s"] == 4e-5


def test_first_ctrl_c_asks_for_a_stop_second_for_a_trip_sigterm_trips():
    before = signal.getsignal(signal.SIGINT)  # Python's default, or SIG_IGN when the suite runs as a background job
    with OperatorSignals() as signals:
        os.kill(os.getpid(), signal.SIGINT)
        assert signals.stop_requested and not signals.trip_requested
        os.kill(os.getpid(), signal.SIGINT)
        assert signals.trip_requested
    with OperatorSignals() as signals:
        os.kill(os.getpid(), signal.SIGTERM)
        assert signals.trip_requested and not signals.stop_requested
    assert signal.getsignal(signal.SIGINT) is before, "the handler the process had is back"


def test_stroke_bar_puts_the_cursor_where_the_stroke_is():
    centre = stroke_bar(0.0, 0.08, 0.1, width=41).plain
    right = stroke_bar(0.1, 0.08, 0.1, width=41).plain
    assert centre.index("█") == 20 and right.index("█") == 40
    assert stroke_bar(0.5, 0.08, 0.1, width=41).plain.index("█") == 40  # clipped at the hard limit


def test_console_shows_state_stroke_force_timing_and_the_last_event():
    status = LoopStatus(state="TRIPPED", trip_reason="stroke_hard", run_t_s=12.0, duration_s=30.0, stroke_m=0.0952,
                        force_N=-2500.0, sliding_variable=0.0123, missed_periods=2, stalls=1, e2e_rejects=3,
                        last_event="12.000 s fault stroke_hard")
    console = Console(record=True, width=120)
    live = LiveConsole(status, 0.08, 0.1, 10_000.0, "test", console, enabled=False)
    console.print(live)
    text = console.export_text()
    for expected in (
        "TRIPPED", "stroke_hard", "12.0 / 30.0 s", "+95.20 mm", "-2.500 kN", "2 missed periods in 1 stall",
        "E2E rejects 3", "fault stroke_hard",
    ):
        assert expected in text, expected
