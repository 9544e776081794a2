"""A fixed-rate scheduler against absolute deadlines (ros2_control style).

``next += period; sleep_until(next)``: lateness does not accumulate. The wait sleeps
until ``spin_s`` before the deadline and spins the rest, which on these machines turns
a median wake-up lateness of ~50 us (plain sleep) into well under 1 us (benchmarks/README.md,
"Timing facts the loop is built on").
When a tick runs so long that whole deadlines pass, those deadlines are skipped
(counted in ``skipped_deadlines``, the scheduler's own bookkeeping) and the loop runs at once
on the latest one that passed, late, instead of bursting through the missed ticks one after
another. What the harness shows as missed periods and stalls is measured from the gaps between
the ticks' starts instead (:mod:`harness.signals.timing_counts`), which a late wake-up lengthens too.

The clock and the sleep function are injectable so tests run on simulated time.
"""

from __future__ import annotations

import time
from collections.abc import Callable

#: Largest share of the period spent busy-waiting before a deadline: the spin holds at most a tenth
#: of a core at any rate (200 us at 500 Hz, 100 us at 1 kHz, 50 us at 2 kHz, with ``loop.spin_s``
#: 200 us). At 2 kHz a 200 us spin held 40 % of a core at real-time priority: with the tick's own
#: compute and the rig's thread the run's real-time threads came near the kernel's throttle (95 % of
#: the machine), which stops them all for 50 ms, and beside another real-time run they hit it.
MAX_SPIN_SHARE = 0.1


class FixedRateScheduler:
    """Wakes the loop at ``t0 + k * period``.

    Parameters
    ----------
    period_s : float
        Tick period (s).
    spin_s : float
        Busy-wait this long before each deadline (s), at most :data:`MAX_SPIN_SHARE` of the period;
        0 disables spinning.
    clock : callable
        Monotonic clock in seconds (default ``time.perf_counter``).
    sleep : callable
        Sleep function (default ``time.sleep``).

    Attributes
    ----------
    tick : int
        Index of the current tick (0 for the first).
    lateness_s : float
        How late the current tick woke, against its deadline (s).
    skipped_deadlines : int
        Deadlines skipped in total (whole deadlines passed before the wait began).
    consecutive_skips : int
        Waits in a row that skipped deadlines, reset by a wait that skipped none.
    """

    __slots__ = (
        "period_s", "spin_s", "_clock", "_sleep", "_start", "_deadline", "tick", "lateness_s", "skipped_deadlines",
        "consecutive_skips",
    )

    def __init__(
        self,
        period_s: float,
        spin_s: float = 200e-6,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
    ):
        if period_s <= 0:
            raise ValueError(f"period {period_s} s; expected > 0")
        self.period_s = float(period_s)
        self.spin_s = max(0.0, min(float(spin_s), self.period_s * MAX_SPIN_SHARE))
        self._clock = clock
        self._sleep = sleep
        self._start = 0.0
        self._deadline = 0.0
        self.tick = -1
        self.lateness_s = 0.0
        self.skipped_deadlines = 0
        self.consecutive_skips = 0

    def start(self) -> float:
        """Set tick 0's deadline to now; return it (the loop's time origin, s)."""
        self._start = self._clock()
        self._deadline = self._start
        self.tick = -1
        self.skipped_deadlines = 0
        self.consecutive_skips = 0
        return self._start

    @property
    def elapsed_s(self) -> float:
        """Scheduled time of the current tick since :meth:`start` (s)."""
        return self._deadline - self._start

    def wait(self) -> float:
        """Block until the next tick's deadline; return its scheduled time since start (s).

        Counts a skipped deadline for every deadline that passed entirely while the tick
        before ran long, skips those, and returns at once on the latest one.
        """
        self.tick += 1
        if self.tick > 0:
            self._deadline += self.period_s
        now = self._clock()
        if now - self._deadline >= self.period_s:
            missed = int((now - self._deadline) / self.period_s)
            self._deadline += missed * self.period_s
            self.tick += missed
            self.skipped_deadlines += missed
            self.consecutive_skips += 1
        else:
            self.consecutive_skips = 0
        remaining = self._deadline - now - self.spin_s
        if remaining > 0:
            self._sleep(remaining)
        while self._clock() < self._deadline:
            pass
        self.lateness_s = self._clock() - self._deadline
        return self._deadline - self._start
