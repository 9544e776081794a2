"""The fixed-rate scheduler on simulated time: absolute deadlines, lateness, skipped deadlines."""

from __future__ import annotations

import pytest

from harness.realtime.scheduler import FixedRateScheduler


class FakeClock:
    """A clock that only moves when slept on or told to."""

    def __init__(self) -> None:
        self.now = 100.0
        self.sleeps: list[float] = []

    def __call__(self) -> float:
        self.now += 1e-7  # every reading costs a little time, so spins end
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps.append(seconds)
        self.now += seconds


def test_ticks_follow_absolute_deadlines_without_drift():
    clock = FakeClock()
    scheduler = FixedRateScheduler(0.002, spin_s=0.0002, clock=clock, sleep=clock.sleep)
    origin = scheduler.start()
    times = []
    for _ in range(1000):
        times.append(scheduler.wait())
        clock.now += 0.0005  # the tick's work
    assert times[0] == pytest.approx(0.0)
    assert times[-1] == pytest.approx(999 * 0.002)
    assert clock.now - origin == pytest.approx(999 * 0.002 + 0.0005, abs=1e-5)  # no accumulated drift
    assert scheduler.skipped_deadlines == 0
    assert max(clock.sleeps) < 0.002


def test_lateness_is_measured_against_the_deadline():
    clock = FakeClock()
    scheduler = FixedRateScheduler(0.001, spin_s=0.0, clock=clock, sleep=lambda s: setattr(clock, "now", clock.now + s + 3e-5))
    scheduler.start()
    scheduler.wait()
    scheduler.wait()
    assert scheduler.lateness_s == pytest.approx(3e-5, abs=2e-6)


def test_a_long_tick_counts_and_skips_the_deadlines_it_missed():
    clock = FakeClock()
    scheduler = FixedRateScheduler(0.002, spin_s=0.0, clock=clock, sleep=clock.sleep)
    scheduler.start()
    scheduler.wait()
    clock.now += 0.0071  # the tick ran 3.5 periods long: deadlines 0.002 and 0.004 passed entirely
    t = scheduler.wait()
    assert scheduler.skipped_deadlines == 2
    assert scheduler.consecutive_skips == 1
    assert t == pytest.approx(3 * 0.002)  # runs at once on the latest deadline, late
    assert scheduler.lateness_s == pytest.approx(0.0011, abs=1e-5)
    scheduler.wait()
    assert scheduler.consecutive_skips == 0


def test_consecutive_skips_accumulate():
    clock = FakeClock()
    scheduler = FixedRateScheduler(0.001, spin_s=0.0, clock=clock, sleep=clock.sleep)
    scheduler.start()
    scheduler.wait()
    for expected in (1, 2, 3):
        clock.now += 0.0025
        scheduler.wait()
        assert scheduler.consecutive_skips == expected


def test_invalid_period_is_refused():
    with pytest.raises(ValueError, match="expected > 0"):
        FixedRateScheduler(0.0)
