"""What the real-time loop counts, on a fake clock: overruns, missed periods, compute time.

The whole :class:`~harness.loop.runner.ControlLoop` runs its real-time path (scheduler,
poll, supervisor) against the rig-side node of tests/unit/test_control_tick.py, on a
clock that moves only when the loop reads or sleeps it; the node publishes whenever the
loop sleeps. Once, the host wakes the loop late (the sleep overshoots): seen from the
gaps between ticks that is a stall of whole missed periods, seen from the deadlines one
skipped deadline, and the loop keeps the two counts apart.
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.loop.config import LoopConfig
from harness.loop.runner import ControlLoop
from harness.loop.status import LoopStatus
from harness.signals import columns as layout
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
            counts = (status.overruns, status.missed_periods, status.stalls)
    finally:
        bench.close()
    return loop, result, np.array(rows.rows), counts


def test_the_run_completes_and_passes_the_late_wake_up(run) -> None:
    loop, result, rows, _ = run
    assert result.outcome == "completed", result.trip_reason
    assert len(rows) == loop.timing.count > 200


def test_overruns_count_skipped_deadlines_and_missed_periods_the_gaps_between_ticks(run) -> None:
    loop, result, rows, (overruns, missed_periods, stalls) = run
    # the late tick began 2.5 periods (less the spin) after its deadline: 3.4 periods after the tick
    # before it, 2 whole periods missed; the tick after it found one deadline already passed
    assert (overruns, missed_periods, stalls) == (1, 2, 1)
    assert overruns == loop.scheduler.overruns == result.timing["overruns"]
    assert missed_periods == loop.missed_periods == rows[:, layout.CONTROL_ROW_INDEX[layout.OVERRUN]].sum()


def test_the_row_and_the_timing_summary_take_one_compute_measurement(run) -> None:
    loop, _, rows, _ = run
    n = loop.timing.count
    column = rows[:, layout.CONTROL_ROW_INDEX[layout.COMPUTE]]
    assert np.all(column > 0.0)
    assert np.array_equal(loop.timing.compute_s[:n], column)
    assert np.all(loop.timing.cpu_s[:n] > 0.0)
