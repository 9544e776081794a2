"""The one definition of the loop's timing counts (harness/signals/timing_counts.py), at its edges."""

from __future__ import annotations

import numpy as np
import pytest

from harness.signals.timing_counts import TimingCounts, missed_periods, stall_words

PERIOD_S = 0.002


@pytest.mark.parametrize(("gap_periods", "missed"), [
    (0.0, 0), (1.0, 0), (1.999, 0), (2.0, 1), (2.4, 1), (3.0, 2), (3.4, 2), (22.5, 21),
])
def test_missed_periods_are_the_whole_periods_beyond_the_first_in_a_gap(gap_periods, missed) -> None:
    assert missed_periods(gap_periods * PERIOD_S, PERIOD_S) == missed


def test_a_gap_of_exactly_two_periods_in_floating_point_is_a_stall() -> None:
    gap_s = 0.6 - 0.4  # 0.19999999999999996: two periods of 0.1 s, as a difference of clock readings gives them
    assert gap_s < 0.2 and missed_periods(gap_s, 0.1) == 1


def test_the_counts_of_a_column_are_the_counts_tick_by_tick() -> None:
    column = np.array([0, 0, 2, 0, 1, 0, 0, 5, np.nan, 0], dtype=float)
    by_tick = TimingCounts()
    for missed in (0, 0, 2, 0, 1, 0, 0, 5, 0):
        by_tick.add(missed)
    assert TimingCounts.of_overrun_column(column) == by_tick == TimingCounts(missed_periods=8, stalls=3)


def test_the_words_every_display_prints() -> None:
    assert TimingCounts(62, 9).words() == "62 missed periods in 9 stalls"
    assert TimingCounts(1, 1).words() == "1 missed period in 1 stall"
    assert stall_words(TimingCounts(62, 9), 1, 0.0352) == (
        "62 missed periods in 9 stalls (ridden through 8, past the budget 1), longest 35.2 ms")
