"""The table check's gate, its told record and its evaluations at their exact bounds (mutation survivors)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.safety.table_record import (
    MAX_LAG_S,
    MIN_HALF_CYCLES,
    MIN_RECORD_S,
    VELOCITY_FLOOR_M_S,
    TableRecordCheck,
    TableRecordMarginal,
    TableRecordMismatch,
    TableVerdict,
    gate_index,
    why,
)

DT = 0.002
FIRST = int(math.ceil(MIN_RECORD_S / DT - 1e-9))


def _sine(amplitude_m_s: float, seconds: float, frequency_hz: float = 4.0) -> np.ndarray:
    t = np.arange(0.0, seconds, DT)
    return amplitude_m_s * np.sin(2 * np.pi * frequency_hz * t)


def _first_loud(v: np.ndarray) -> int:
    """First sample whose RMS since the start reaches the floor, summed sample by sample."""
    total = 0.0
    for n, value in enumerate(v):
        total += value * value
        if total / (n + 1) >= VELOCITY_FLOOR_M_S**2:
            return n
    raise AssertionError("never loud")


# ---------------------------------------------------------------- the gate

def test_swings_beyond_the_floor_with_a_quiet_rms_never_open_the_gate() -> None:
    quiet = _sine(VELOCITY_FLOOR_M_S * 1.05, 6.0)  # RMS 0.74 of the floor: 24 swings, never loud
    assert np.sqrt(np.mean(quiet**2)) < VELOCITY_FLOOR_M_S
    assert gate_index(quiet, DT) is None


def test_the_rms_opens_the_gate_when_it_comes_last() -> None:
    v = np.concatenate((_sine(VELOCITY_FLOOR_M_S * 1.05, 3.0), _sine(0.1, 3.0)))  # swings early, loud after 3 s
    gate = gate_index(v, DT)
    assert gate == _first_loud(v) and gate * DT > 3.0


def test_the_swings_open_the_gate_when_they_come_last_and_exactly_the_count_is_enough() -> None:
    v = np.full(int(3.0 / DT), 0.2 * VELOCITY_FLOOR_M_S)
    v[: int(0.5 / DT)] = 0.05  # loud from the start (RMS stays above the floor), one swing
    starts = [int(1.5 / DT) + 40 * k for k in range(MIN_HALF_CYCLES - 1)]
    for k, n in enumerate(starts):
        v[n : n + 5] = -0.05 if k % 2 == 0 else 0.05
    assert gate_index(v, DT) == starts[-1], "the swing that completes the count opens the gate"
    v[starts[-1] : starts[-1] + 5] = 0.2 * VELOCITY_FLOOR_M_S  # one swing fewer than the count
    assert gate_index(v, DT) is None


def test_a_swing_exactly_at_the_floor_is_not_beyond_it() -> None:
    square = np.where((np.arange(int(4.0 / DT)) // 50) % 2 == 0, VELOCITY_FLOOR_M_S, -VELOCITY_FLOOR_M_S)
    assert gate_index(square, DT) is None
    assert gate_index(square * 1.001, DT) == FIRST


def test_an_rms_exactly_on_the_floor_is_loud_enough() -> None:
    v = np.zeros(int(3.0 / DT))
    v[0] = VELOCITY_FLOOR_M_S  # loud on its first sample, exactly on the floor, then quiet
    for k in range(MIN_HALF_CYCLES):
        v[int(1.2 / DT) + 30 * k] = 1.001 * VELOCITY_FLOOR_M_S * (-1) ** k
    assert gate_index(v, DT) == int(1.2 / DT) + 30 * (MIN_HALF_CYCLES - 1)


@pytest.mark.parametrize("samples", [FIRST - 1, FIRST])
def test_a_record_no_longer_than_the_least_record_time_is_never_judged(samples: int) -> None:
    v = _sine(0.1, samples * DT)[:samples]
    assert v.size == samples and gate_index(v, DT) is None
    assert gate_index(_sine(0.1, (FIRST + 1) * DT)[: FIRST + 1], DT) == FIRST


# ---------------------------------------------------------------- the told record

@pytest.mark.parametrize("period_s", [0.0, -0.002, math.inf, math.nan])
def test_the_check_refuses_a_period_that_is_not_positive_and_finite(period_s: float) -> None:
    with pytest.raises(ValueError, match=r"the table check needs the loop's period, got .* s"):
        TableRecordCheck(0.02).expect(_sine(0.1, 2.0), DT, 2.0, period_s)


def test_the_told_record_spans_the_run_and_a_stall_budgets_samples() -> None:
    check = TableRecordCheck(max_stall_s=0.02)
    check.expect(_sine(0.1, 8.0), DT, 8.0, DT)
    assert check.tracking is not None and check.tracking.length == 4001, "0 to 8 s inclusive on the 2 ms grid"
    assert check.max_catch_up == 11, "a 20 ms stall skips up to 10 ticks; the tick after it adds one more"
    check.expect(_sine(0.1, 8.0), DT, 8.0 - 1e-13, DT)
    assert check.tracking.length == 4001, "a duration a rounding short of a tick still reaches it"


def test_after_its_end_the_told_record_is_at_rest() -> None:
    told = _sine(0.1, 4.0, frequency_hz=4.0625)  # ends near its peak velocity
    assert abs(told[-1]) > 0.05
    table = np.concatenate((told, np.zeros(int(4.0 / DT))))  # the table stops with the record
    check = TableRecordCheck(0.02)
    check.expect(told, DT, 8.0, DT)
    for n, value in enumerate(table):
        check.update(n * DT, float(value))
    assert check.worst is TableVerdict.MATCH and check.tracking.correlation > 0.999


def test_ignoring_the_run_leaves_no_gate_and_says_why() -> None:
    check = TableRecordCheck(0.02)
    check.expect(_sine(0.1, 4.0), DT, 4.0, DT)
    check.ignore("record time is not the table's")
    assert check.gate is None and math.isnan(check.gate_s)
    assert check.summary() == {"verdict": "off", "signal": "table velocity xdot_0", "reason": "record time is not the table's"}


# ---------------------------------------------------------------- the evaluations

def _played(told: np.ndarray, table: np.ndarray) -> TableRecordCheck:
    check = TableRecordCheck(0.02)
    check.expect(told, DT, (told.size - 1) * DT, DT)
    for n, value in enumerate(table):
        check.update(n * DT, float(value))
    return check


def _random(seconds: float = 8.0, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, DT)
    v = sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 6.28)) for f in rng.uniform(0.5, 4.0, 20))
    return 0.1 * v / np.std(v)


def test_a_table_later_than_the_search_is_a_mismatch_at_the_edge() -> None:
    told = _random()
    late = np.interp(np.arange(told.size) * DT - (MAX_LAG_S + 0.02), np.arange(told.size) * DT, told, left=0.0)
    check = _played(told, late)
    assert check.worst is TableVerdict.MISMATCH and check.worst_measures[3] is True
    assert "no correlation peak within" in why(*check.worst_measures)
    correlation, delay_s, ratio, _ = check.worst_measures
    assert f"delay {delay_s * 1e3:+.1f} ms" in check.measures_text() and abs(delay_s) == pytest.approx(MAX_LAG_S)


def test_the_first_evaluation_is_judged_at_the_gate_to_the_tick() -> None:
    told = _random(seed=3)
    check = _played(told, _random(seed=11))
    assert check.evaluations == 1 and check.judged_at_s == pytest.approx(check.gate * DT, abs=1e-12)


def test_the_worst_of_equal_verdicts_is_the_latest() -> None:
    told = _random()
    check = _played(told, 0.6 * told)  # marginal at every evaluation
    assert check.worst is check.verdict is TableVerdict.MARGINAL and check.evaluations > 2
    assert check.worst_at_s == check.judged_at_s and check.worst_measures == check.latest_measures


def test_the_checks_detail_lines_name_the_evaluation_they_act_on() -> None:
    told = _random()
    table = 0.6 * told
    table[int(1.6 / DT):] = told[int(1.6 / DT):]  # marginal, then a match: the latest is not the worst
    check = _played(told, table)
    assert check.worst is TableVerdict.MARGINAL and check.verdict is TableVerdict.MATCH
    marginal, mismatch = TableRecordMarginal(check), TableRecordMismatch(check)
    assert marginal.detail(None) == (check.measures_text(latest=True)
                                     + "; the table follows the told record, but not as a healthy table does")
    assert mismatch.detail(None) == check.measures_text() + "; the table does not play the record the harness was told"


def test_ticks_before_the_first_update_are_held_at_rest() -> None:
    """A first update a few ticks into the record (the table reported late) fills the ticks before it at rest."""
    told = _random()
    table = _random(seed=11)
    table[:3] = 0.0
    from_start, late = TableRecordCheck(0.02), TableRecordCheck(0.02)
    for check in (from_start, late):
        check.expect(told, DT, (told.size - 1) * DT, DT)
    for n, value in enumerate(table):
        from_start.update(n * DT, float(value))
        if n >= 3:
            late.update(n * DT, float(value))
    assert late.evaluations == from_start.evaluations > 0
    assert late.worst_measures == from_start.worst_measures


def test_at_the_records_end_the_gates_own_sample_is_needed_for_a_verdict() -> None:
    told = _random()
    for samples, evaluations in ((None, 0), (1, 2)):
        check = TableRecordCheck(0.02)
        check.expect(told, DT, (told.size - 1) * DT, DT)
        assert check.gate is not None and check.tracking is not None
        for n in range(check.gate + (samples or 0)):
            check.update(n * DT, float(told[n]))
        check.update(check.tracking.length * DT, 0.0)  # past the record's end: the last judgement
        assert check.evaluations == evaluations, f"{check.gate + (samples or 0)} samples, the gate at {check.gate}"
        assert (check.verdict is TableVerdict.WAITING) == (evaluations == 0)


def test_a_loop_slower_than_the_evaluation_period_judges_on_every_tick_after_the_gate() -> None:
    """At 1 Hz (a tick longer than EVALUATE_EVERY_S, 0.5 s) each tick from the gate on is one evaluation."""
    record_dt, seconds = 0.01, 120.0
    told = 0.1 * np.sin(2 * np.pi * 0.13 * np.arange(0.0, seconds, record_dt))
    check = TableRecordCheck(0.0)
    check.expect(told, record_dt, seconds - record_dt, 1.0)
    assert check.gate is not None and check.tracking is not None
    ticks = check.tracking.length
    for n in range(ticks):
        check.update(float(n), float(told[min(int(n / record_dt), told.size - 1)]))
    assert check.evaluations == ticks - check.gate  # updates from the gate's own tick on
