"""Per-tick timing of the loop: wake-up lateness, compute time, overruns (preallocated)."""

from __future__ import annotations

import numpy as np

from harness.realtime.memory import float_view, prefaulted_zeros


class TimingStats:
    """Preallocated per-tick timing arrays and their summary.

    Parameters
    ----------
    capacity : int
        Most ticks recorded; later ticks only update the counters.
    """

    __slots__ = ("lateness_s", "compute_s", "cpu_s", "count", "overruns", "_capacity", "_views")

    def __init__(self, capacity: int):
        self._capacity = int(capacity)
        self.lateness_s = prefaulted_zeros(self._capacity)
        self.compute_s = prefaulted_zeros(self._capacity)
        self.cpu_s = prefaulted_zeros(self._capacity)
        self._views = (float_view(self.lateness_s), float_view(self.compute_s), float_view(self.cpu_s))
        self.count = 0
        self.overruns = 0

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
        """Median, p99, p99.9 and max of lateness, compute (wall-clock) and CPU time per tick (s), and counts."""
        n = min(self.count, self._capacity)
        if n == 0:
            return {"ticks": 0, "overruns": self.overruns}
        result: dict = {"ticks": self.count, "overruns": self.overruns}
        for name, values in (("lateness", self.lateness_s[:n]), ("compute", self.compute_s[:n]), ("cpu", self.cpu_s[:n])):
            p50, p99, p999 = np.percentile(values, [50, 99, 99.9])
            result[f"{name}_median_s"] = float(p50)
            result[f"{name}_p99_s"] = float(p99)
            result[f"{name}_p999_s"] = float(p999)
            result[f"{name}_max_s"] = float(values.max())
        return result
