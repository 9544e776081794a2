"""The loop's timing counts, each defined once: missed periods (overruns) and stalls.

Every place that shows a count takes it from here: the loop counts tick by tick with
:func:`missed_periods` and :meth:`TimingCounts.add`; the console, the printed timing summary
and ``metadata.json`` show the loop's :class:`TimingCounts`; the timing plot and the report
count the same way from the ``overrun`` column of ``signals.csv``
(:meth:`TimingCounts.of_overrun_column`). docs/ARCHITECTURE.md, "Timing counts", says the same
in words.

- **Missed periods** of a tick: the whole periods beyond the first in the gap between the
  start of the previous tick and its own start (``floor(gap / period) - 1``, at least 0). A
  tick on time has 0; a tick that began 2.4 periods after the one before has 1. The gap is
  what the safety checks judge (the stall budget, ``loop_stall``): the time the loop was away
  from the actuator, whether a long tick or a late wake-up took it.
- **Overrun**: the ``overrun`` column of ``signals.csv`` holds each tick's missed periods. A
  run's overruns *are* its missed periods (the column's sum); there is no other overrun count.
- **Stall**: a tick with at least one missed period (a gap of two periods or more). Within the
  stall budget it is ridden through; beyond it, it is past the budget (and trips ``loop_stall``
  where the drive may be enabled). A run's stalls are the rows whose ``overrun`` is at least 1.

In lockstep the rig waits for the loop: no gap is measured, and every count is 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

#: Slack on the ratio gap / period, so that a gap of exactly two periods, computed in floating point, is a stall.
_RATIO_SLACK = 1e-9


def missed_periods(gap_s: float, period_s: float) -> int:
    """Whole periods missed in the gap between the starts of two consecutive ticks.

    Parameters
    ----------
    gap_s : float
        Time between the start of the previous tick and the start of this one (s); 0 for the
        first tick and in lockstep.
    period_s : float
        The loop's period (s).

    Returns
    -------
    int
        ``floor(gap_s / period_s) - 1``, at least 0.
    """
    return max(0, int(gap_s / period_s + _RATIO_SLACK) - 1)


@dataclass
class TimingCounts:
    """A run's missed periods and stalls, counted tick by tick.

    Attributes
    ----------
    missed_periods : int
        Missed periods over every tick (the sum of the ``overrun`` column): the run's overruns.
    stalls : int
        Ticks with at least one missed period, ridden through or past the stall budget.
    """

    missed_periods: int = 0
    stalls: int = 0

    def add(self, missed: int) -> None:
        """Count one tick that came after ``missed`` missed periods (no allocation beyond the ints)."""
        if missed > 0:
            self.missed_periods += missed
            self.stalls += 1

    @classmethod
    def of_overrun_column(cls, overrun: np.ndarray) -> TimingCounts:
        """The counts of a recorded run, from its ``overrun`` column (NaN rows, if any, skipped)."""
        counts = cls()
        import numpy as np  # here: the command line's parser imports this module, and numpy costs it 0.16 s

        values = np.asarray(overrun, dtype=float)
        for missed in values[np.isfinite(values)]:
            counts.add(int(missed))
        return counts

    def words(self) -> str:
        """The counts as every display prints them, e.g. ``62 missed periods in 9 stalls``."""
        return (f"{self.missed_periods} missed period{'' if self.missed_periods == 1 else 's'} in "
                f"{self.stalls} stall{'' if self.stalls == 1 else 's'}")


def stall_words(counts: TimingCounts, past_budget: int, longest_stall_s: float) -> str:
    """The line the console and the printed timing summary show, e.g.
    ``62 missed periods in 9 stalls (ridden through 8, past the budget 1), longest 35.2 ms``.

    Parameters
    ----------
    counts : TimingCounts
    past_budget : int
        Stalls longer than the stall budget (the rest were ridden through).
    longest_stall_s : float
        Longest gap between the starts of two ticks in a stall (s).
    """
    return (f"{counts.words()} (ridden through {counts.stalls - past_budget}, past the budget {past_budget}), "
            f"longest {longest_stall_s * 1e3:.1f} ms")
