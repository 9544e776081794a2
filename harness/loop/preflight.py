"""Pre-flight timing check: can this host hold the loop's rate within the stall budget?

Before arming, the loop's own scheduler (sleep, then spin to the deadline) runs empty at
the run's rate for about a second while the rest of the test set-up (the rig, the
recorder) is already running, and the wake-up lateness is measured. The verdict:

- **ok**: p99 lateness within one period and the largest within half the stall budget.
- **marginal**: worse than that but p99 within the stall budget: stalls will happen and
  be ridden through (counted, shown, recorded); an occasional one may exceed the budget.
- **refused**: a wake-up later than the stall budget within the second measured: the run would
  have tripped ``loop_stall`` there, and a 30 s run holds thirty such seconds, so it is refused
  before anything moves (exit status 2), with the remedies. (It was the p99 before; with every
  core busy and no real-time priority, 7 of 10 runs the p99 passed tripped within seconds.)

Over the same second it also watches the rig (``frame_counts``): at each wake-up, after the
poll, how long ago each control measurement message (table, base mat) last arrived. That age is
what ``sensor_stale`` judges against ``safety.sensors.max_sensor_age_s``, and a rig process the
host does not schedule in time shows there, not in the loop's own lateness (the issue's case: a
rig not scheduled for 22 ms while the loop's p99 lateness was 3.2 ms). The verdict takes the
worse of the two: refused when the largest age exceeds the limit (a tick in the second measured
would have tripped; a rig that sends nothing has an infinite age), marginal when it exceeds half
of it.

Without real-time priority it also measures how much of the machine was idle over that second
(``/proc/stat``). With every core busy with other work, the loop and the rig wait for time slices
of the machine's scheduler; a second can look clean and the run still trip within seconds (with
two busy processes on two cores and normal scheduling, 3 of the 7 runs the other criteria let
through tripped ``sensor_stale``: benchmarks/README.md). Less than :data:`MIN_IDLE_CORES` of a
core idle is refused, with how to get real-time priority; at real-time priority the machine's
load does not matter and is not judged.

The clock and the sleep are injectable, as for the scheduler, so tests run on a fake clock.
"""

from __future__ import annotations

import dataclasses
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from harness.errors import SafetyError
from harness.realtime.scheduler import FixedRateScheduler
from harness.safety.operator_detectors import HOST_TIMING_REMEDIES

#: Idle CPU (in cores) below which a loop without real-time priority is refused: the machine's
#: other work holds every core, so the loop and the rig wait for time slices.
MIN_IDLE_CORES = 0.25


def idle_cores(before: tuple[int, int] | None, after: tuple[int, int] | None, cores: int) -> float | None:
    """Idle CPU between two :func:`cpu_times` readings, in cores; None where they are not available."""
    if before is None or after is None or after[1] <= before[1]:
        return None
    return cores * (after[0] - before[0]) / (after[1] - before[1])


def cpu_times() -> tuple[int, int] | None:
    """(idle + iowait, total) jiffies of the machine from ``/proc/stat``; None where it cannot be read."""
    try:
        with open("/proc/stat", encoding="ascii") as handle:
            fields = [int(value) for value in handle.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    if len(fields) < 5:
        return None
    return fields[3] + fields[4], sum(fields[:8])


class HostTimingRefused(SafetyError):
    """The host cannot hold the loop's rate within the stall budget (checked before arming)."""


@dataclass(frozen=True)
class HostTiming:
    """Wake-up lateness of an empty loop at the run's rate, and the verdict.

    Attributes
    ----------
    rate_hz : float
        The rate measured at (Hz).
    wakeups : int
        Wake-ups measured.
    p50_s, p99_s, max_s : float
        Lateness against the deadline (s).
    stall_budget_s : float
        The run's stall budget (s), ``safety.run.max_stall_s``.
    """

    rate_hz: float
    wakeups: int
    p50_s: float
    p99_s: float
    max_s: float
    stall_budget_s: float
    rig_age_p99_s: float | None = None
    rig_age_max_s: float | None = None
    max_sensor_age_s: float | None = None
    idle_cores: float | None = None

    @property
    def watched_rig(self) -> bool:
        """True when the rig's frames were watched too."""
        return self.rig_age_p99_s is not None and self.rig_age_max_s is not None and self.max_sensor_age_s is not None

    @property
    def verdict(self) -> str:
        """``"ok"``, ``"marginal"`` or ``"refused"`` (see the module docstring)."""
        rig_max = self.rig_age_max_s if self.rig_age_max_s is not None else 0.0
        limit = self.max_sensor_age_s if self.max_sensor_age_s is not None else math.inf
        if self.max_s > self.stall_budget_s or not rig_max <= limit:
            return "refused"  # the one second measured already held a wake-up the run would trip on
        if self.idle_cores is not None and self.idle_cores < MIN_IDLE_CORES:
            return "refused"  # no real-time priority and no core to spare
        if self.p99_s > 1.0 / self.rate_hz or self.max_s > self.stall_budget_s / 2 or rig_max > limit / 2:
            return "marginal"
        return "ok"

    def summary(self) -> str:
        """One line for the console and the run's metadata."""
        rig = ""
        if self.watched_rig:
            assert self.rig_age_p99_s is not None and self.rig_age_max_s is not None and self.max_sensor_age_s is not None
            if math.isinf(self.rig_age_p99_s):
                rig = "; the rig's sensor frames: none arrived (a rig that is silent or not serving this bus)"
            else:
                rig = (f"; the rig's sensor frames: age p99 {self.rig_age_p99_s * 1e3:.2f} ms, max "
                       f"{self.rig_age_max_s * 1e3:.2f} ms against a limit of {self.max_sensor_age_s * 1e3:.1f} ms")
        if self.idle_cores is not None:
            rig += f"; idle CPU {self.idle_cores:.2f} cores at normal scheduling (at least {MIN_IDLE_CORES:g} needed)"
        return (
            f"host timing at {self.rate_hz:g} Hz over {self.wakeups} wake-ups: lateness p50 {self.p50_s * 1e6:.0f} us, "
            f"p99 {self.p99_s * 1e6:.0f} us, max {self.max_s * 1e3:.2f} ms against a stall budget of "
            f"{self.stall_budget_s * 1e3:.1f} ms{rig}: {self.verdict}"
        )

    def check(self) -> None:
        """Raise :class:`HostTimingRefused` when the verdict is ``refused``."""
        if self.verdict == "refused":
            raise HostTimingRefused(
                f"{self.summary()}; this host cannot run the loop within its stall budget, nothing was moved; "
                + HOST_TIMING_REMEDIES
            )

    def as_dict(self) -> dict:
        """Plain data for metadata.json."""
        return {
            "rate_hz": self.rate_hz, "wakeups": self.wakeups, "lateness_p50_s": self.p50_s,
            "lateness_p99_s": self.p99_s, "lateness_max_s": self.max_s, "stall_budget_s": self.stall_budget_s,
            "rig_frame_age_p99_s": self.rig_age_p99_s, "rig_frame_age_max_s": self.rig_age_max_s,
            "max_sensor_age_s": self.max_sensor_age_s, "idle_cores": self.idle_cores, "verdict": self.verdict,
        }


def measure_host_timing(
    rate_hz: float,
    stall_budget_s: float,
    spin_s: float,
    duration_s: float = 1.0,
    clock: Callable[[], float] = time.perf_counter,
    sleep: Callable[[float], None] = time.sleep,
    poll: Callable[[], object] | None = None,
    frame_counts: Callable[[], tuple[int, ...]] | None = None,
    max_sensor_age_s: float | None = None,
    judge_idle: bool = False,
    read_cpu_times: Callable[[], tuple[int, int] | None] = cpu_times,
) -> HostTiming:
    """Run the loop's scheduler empty for ``duration_s`` and measure its wake-up lateness.

    Parameters
    ----------
    rate_hz : float
        The run's tick rate (Hz).
    stall_budget_s : float
        The run's stall budget (s).
    spin_s : float
        The loop's spin before each deadline (s), ``loop.spin_s``.
    duration_s : float
        How long to measure (s).
    clock, sleep : callable
        As for :class:`~harness.realtime.scheduler.FixedRateScheduler`.
    poll : callable, optional
        Called at every wake-up: drain the bus as the loop would, so frames do not pile up.
    frame_counts : callable, optional
        After the poll, the accepted frames so far of each control measurement message (the
        reader's counts): the rig is watched when given, with ``max_sensor_age_s``.
    max_sensor_age_s : float, optional
        ``safety.sensors.max_sensor_age_s`` (s).
    judge_idle : bool
        Measure the machine's idle CPU over the second (the loop has no real-time priority).
    read_cpu_times : callable
        :func:`cpu_times`, injectable for tests.
    """
    period_s = 1.0 / rate_hz
    wakeups = max(10, int(round(duration_s / period_s)))
    lateness = np.empty(wakeups)
    ages = np.empty(wakeups)
    watch = frame_counts is not None and max_sensor_age_s is not None
    counts = frame_counts() if frame_counts is not None and watch else ()
    started = clock()
    last_seen = [started if count else -math.inf for count in counts]  # frames before the check count from its start
    scheduler = FixedRateScheduler(period_s, spin_s, clock=clock, sleep=sleep)
    cpu_before = read_cpu_times() if judge_idle else None
    scheduler.start()
    previous = None
    for k in range(wakeups):
        scheduler.wait()
        woke = clock()
        # a wake-up that skipped deadlines is late by the whole gap since the previous one
        gap = 0.0 if previous is None else woke - previous - period_s
        lateness[k] = max(scheduler.lateness_s, gap)
        previous = woke
        if poll is not None:
            poll()
        if watch and frame_counts is not None:
            now_counts = frame_counts()
            for i, (before, after) in enumerate(zip(counts, now_counts, strict=True)):
                if after != before:
                    last_seen[i] = woke
            counts = now_counts
            ages[k] = woke - min(last_seen)  # the oldest of the messages: what sensor_stale would judge
    p50, p99 = np.percentile(lateness, [50, 99])
    idle = idle_cores(cpu_before, read_cpu_times(), os.cpu_count() or 1) if judge_idle else None
    timing = HostTiming(float(rate_hz), wakeups, float(p50), float(p99), float(lateness.max()), float(stall_budget_s),
                        idle_cores=idle)
    if not watch or max_sensor_age_s is None:
        return timing
    p99_age = float(np.percentile(ages, 99, method="higher"))  # a sample, never a mean with an infinite age
    return dataclasses.replace(timing, rig_age_p99_s=p99_age, rig_age_max_s=float(ages.max()),
                               max_sensor_age_s=float(max_sensor_age_s))
