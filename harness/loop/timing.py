"""Per-tick timing of the loop: wake-up lateness, compute time, and where a long gap went (preallocated).

The counts of missed periods and stalls are :mod:`harness.signals.timing_counts`'s.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from harness.realtime.memory import float_view, prefaulted_zeros


class TimingStats:
    """Preallocated per-tick timing arrays and their summary.

    Parameters
    ----------
    capacity : int
        Most ticks recorded; later ticks only update the counters.
    """

    __slots__ = ("lateness_s", "compute_s", "cpu_s", "count", "_capacity", "_views")

    def __init__(self, capacity: int):
        self._capacity = int(capacity)
        self.lateness_s = prefaulted_zeros(self._capacity)
        self.compute_s = prefaulted_zeros(self._capacity)
        self.cpu_s = prefaulted_zeros(self._capacity)
        self._views = (float_view(self.lateness_s), float_view(self.compute_s), float_view(self.cpu_s))
        self.count = 0

    def add(self, lateness_s: float, compute_s: float, cpu_s: float = 0.0) -> None:
        """Record one tick (no allocation).

        Parameters
        ----------
        lateness_s : float
            Wake-up lateness against the deadline (s).
        compute_s : float
            Wall-clock time of the tick's work (s), including any wait for the interpreter lock
            (:attr:`harness.loop.tick.ControlTick.compute_s`, the row's ``compute_s`` too).
        cpu_s : float
            CPU time the loop thread itself spent on it (s).
        """
        k = self.count
        if k < self._capacity:
            lateness, compute, cpu = self._views  # memoryviews: a third of a numpy item store
            lateness[k] = lateness_s
            compute[k] = compute_s
            cpu[k] = cpu_s
        self.count = k + 1

    def recent_percentiles(self, window: int = 500) -> tuple[float, float]:
        """Lateness p50 and p99 over the last ``window`` ticks (s); for the console, not the tick."""
        n = min(self.count, self._capacity)
        if n == 0:
            return 0.0, 0.0
        recent = self.lateness_s[max(0, n - window) : n]
        p50, p99 = np.percentile(recent, [50, 99])
        return float(p50), float(p99)

    def summary(self) -> dict:
        """Median, p99, p99.9 and max of lateness, compute (wall-clock) and CPU time per tick (s), and the tick count."""
        n = min(self.count, self._capacity)
        if n == 0:
            return {"ticks": 0}
        result: dict = {"ticks": self.count}
        for name, values in (("lateness", self.lateness_s[:n]), ("compute", self.compute_s[:n]), ("cpu", self.cpu_s[:n])):
            p50, p99, p999 = np.percentile(values, [50, 99, 99.9])
            result[f"{name}_median_s"] = float(p50)
            result[f"{name}_p99_s"] = float(p99)
            result[f"{name}_p999_s"] = float(p999)
            result[f"{name}_max_s"] = float(values.max())
        return result


#: The parts of the time between the starts of two ticks, in the order the loop spends it: the tick's
#: own parts (:meth:`harness.loop.tick.ControlTick.run`), the loop's bookkeeping after it (phases, console
#: status, timing), then the wait for the next deadline (sleep and spin). A gap past the stall budget is
#: told by the part that took longest (docs/SAFETY.md, "Stall attribution").
GAP_PARTS: tuple[str, ...] = ("read", "control", "supervise", "write", "record", "phase", "wait")
#: What each part of :data:`GAP_PARTS` is, for the event that names it.
GAP_PART_WORDS: dict[str, str] = {
    "read": "polling the bus and reading the frames",
    "control": "the estimator, the controller and the compensation",
    "supervise": "the safety supervisor",
    "write": "sending the command and the heartbeat",
    "record": "handing the row and the events to the recorder and the console",
    "phase": "the loop's phases, console status and timing",
    "wait": "waiting for the next deadline (sleep and spin)",
}
READ, CONTROL, SUPERVISE, WRITE, RECORD, PHASE, WAIT = range(len(GAP_PARTS))


class GapTrace:
    """When each part of the latest tick ended, on the loop's clock: where a long gap went (preallocated).

    ``marks[0]`` is the time the tick began (the end of the wait before it); ``marks[i + 1]`` the time
    part ``i`` of :data:`GAP_PARTS` ended. The loop calls :meth:`woke` on waking; the parts of the
    gap that just ended are then ``marks[i + 1] - marks[i]`` (0 for a part a tick skipped, such as
    an exception's path), the last one the wait. Nothing is allocated per tick but the clock's floats.

    Parameters
    ----------
    clock : callable
        The loop's monotonic clock (s); the scheduler's, so a fake clock's stall shows here too.
    """

    __slots__ = ("clock", "marks", "parts_s")

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self.clock = clock
        self.marks = [0.0] * (len(GAP_PARTS) + 1)
        #: The parts of the latest gap (s), filled by :meth:`woke`.
        self.parts_s = [0.0] * len(GAP_PARTS)

    def mark(self, part: int) -> None:
        """Part ``part`` (an index of :data:`GAP_PARTS`) of the current tick ends now."""
        self.marks[part + 1] = self.clock()

    def woke(self) -> None:
        """The wait ended: split the gap since the previous tick began into its parts, and begin this tick."""
        marks, parts = self.marks, self.parts_s
        marks[WAIT + 1] = now = self.clock()
        before = marks[0]
        for part in range(len(parts)):
            end = marks[part + 1]
            if end < before:  # a part this tick skipped (or the first tick): nothing spent in it
                parts[part] = 0.0
            else:
                parts[part] = end - before
                before = end
        marks[0] = now

    def longest_part(self) -> int:
        """The index of the part of the latest gap that took longest."""
        parts = self.parts_s
        longest = 0
        for part in range(1, len(parts)):
            if parts[part] > parts[longest]:
                longest = part
        return longest

    def describe(self) -> str:
        """The latest gap's parts in words (allocates: for the event of a gap past the budget only)."""
        longest = GAP_PARTS[self.longest_part()]
        listed = ", ".join(f"{name} {spent * 1e3:.1f}" for name, spent in zip(GAP_PARTS, self.parts_s, strict=True))
        return (f"the loop was {GAP_PART_WORDS[longest]} for {self.parts_s[self.longest_part()] * 1e3:.1f} ms "
                f"({longest}; parts in ms: {listed})")
