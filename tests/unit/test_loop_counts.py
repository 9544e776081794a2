"""What the real-time loop counts, on a fake clock: missed periods, stalls, compute time.

The whole :class:`~harness.loop.runner.ControlLoop` runs its real-time path (scheduler,
poll, supervisor) against the rig-side node of tests/unit/test_control_tick.py, on a
clock that moves only when the loop reads or sleeps it; the node publishes whenever the
loop sleeps. Once, the host wakes the loop late (the sleep overshoots): seen from the
gaps between ticks that is one stall of two whole missed periods, though the scheduler skips only
one deadline; every count the loop shows is the gaps' (harness.signals.timing_counts), the same
in the status block, the timing summary and the rows' ``overrun`` column.
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.loop.config import LoopConfig
from harness.loop.runner import ControlLoop
from harness.loop.status import LoopStatus
from harness.signals import columns as layout
from harness.signals.timing_counts import TimingCounts
from tests.unit.test_control_tick import PERIOD_S, Bench

#: Arm, settle 20 ms, 0.2 s of record, no tail.
CONFIG = LoopConfig(settle_s=0.02, tail_s=0.0, after_s=0.01)
#: The sleep that overshoots, and by how much (s): the loop wakes 2.5 periods late, less the spin.
LATE_SLEEP, OVERSHOOT_S = 60, 2.5 * PERIOD_S


class Clock:
    """Moves 1 us per read and on sleep; the rig-side node publishes on every sleep."""

    def __init__(self, bench: Bench) -> None:
        self.bench = bench
        self.now = 0.0
        self.sleeps = 0

    def __call__(self) -> float:
        self.now += 1e-6
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps += 1
        self.now += seconds + (OVERSHOOT_S if self.sleeps == LATE_SLEEP else 0.0)
        self.bench.publish()


class Rows:
    """The tick's recorder: keeps a copy of every row."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []

    def record_row(self, values: np.ndarray) -> None:
        self.rows.append(values.copy())

    def record_event(self, t: float, kind: str, name: str, detail: str) -> None:
        pass


@pytest.fixture(scope="module")
def run():
    bench = Bench()
    rows = Rows()
    bench.tick.recorder = rows
    clock = Clock(bench)
    try:
        with LoopStatus() as status:
            loop = ControlLoop(bench.tick, CONFIG, 1.0 / PERIOD_S, 0.2, status=status, clock=clock, sleep=clock.sleep)
            result = loop.run()
            counts = (status.missed_periods, status.stalls)
    finally:
        bench.close()
    return loop, result, np.array(rows.rows), counts


def test_the_run_completes_and_passes_the_late_wake_up(run) -> None:
    loop, result, rows, _ = run
    assert result.outcome == "completed", result.trip_reason
    assert len(rows) == loop.timing.count > 200


def test_missed_periods_and_stalls_are_counted_from_the_gaps_between_ticks_everywhere(run) -> None:
    loop, result, rows, (missed_periods, stalls) = run
    # the late tick began 2.5 periods (less the spin) after its deadline: 3.4 periods after the tick
    # before it, 2 whole periods missed; the tick after it found one deadline already passed, which
    # the scheduler alone counts (its own bookkeeping, shown nowhere)
    assert (missed_periods, stalls) == (2, 1)
    assert loop.scheduler.skipped_deadlines == 1
    assert "overruns" not in result.timing
    assert (result.timing["missed_periods"], result.timing["stalls"]) == (missed_periods, stalls)
    assert result.timing["stalls_ridden_through"] + result.timing["gaps_past_budget"] == stalls
    column = TimingCounts.of_overrun_column(rows[:, layout.CONTROL_ROW_INDEX[layout.OVERRUN]])
    assert column == loop.counts == TimingCounts(missed_periods, stalls)


def test_the_row_and_the_timing_summary_take_one_compute_measurement(run) -> None:
    loop, _, rows, _ = run
    n = loop.timing.count
    column = rows[:, layout.CONTROL_ROW_INDEX[layout.COMPUTE]]
    assert np.all(column > 0.0)
    assert np.array_equal(loop.timing.compute_s[:n], column)
    assert np.all(loop.timing.cpu_s[:n] > 0.0)
