"""The base-mat sensor's sign after a run (harness/report/sensor_signs.py) and the table check's words for a sign fault."""

from __future__ import annotations

import math

import numpy as np

from harness.report.sensor_signs import MIN_TABLE_RMS_M_S, base_sensor_sign
from harness.report.table_check import NOT_JUDGED_WARNING, table_check

RUNNING, ARMED = 2, 1
N = 5000
T = np.arange(N) * 0.002


def _table(amplitude_m_s: float) -> np.ndarray:
    return amplitude_m_s * (np.sin(2 * np.pi * 1.3 * T) + 0.5 * np.sin(2 * np.pi * 3.1 * T + 0.4))


def _noise(seed: int) -> np.ndarray:
    return np.random.default_rng(seed).normal(0.0, 2e-4, N)  # the shipped profile's velocity noise


def test_a_base_mat_following_the_table_is_sound_and_one_reversed_warns() -> None:
    state = np.full(N, RUNNING)
    table = _table(0.004) + _noise(1)
    base = 0.7 * _table(0.004) + _noise(2)  # rides on the table, partly isolated
    sound = base_sensor_sign(state, table, base)
    assert sound.verdict == "with_table" and not sound.warns and sound.correlation > 0.9
    reversed_ = base_sensor_sign(state, table, -base)
    assert reversed_.verdict == "against_table" and reversed_.warns and reversed_.correlation < -0.9
    assert "WARNING: the base mat moved against the table" in reversed_.line and "reversed polarity" in reversed_.line


def test_a_table_that_barely_moved_is_not_judged_and_says_so() -> None:
    state = np.full(N, RUNNING)
    table = _table(0.5 * MIN_TABLE_RMS_M_S) + _noise(3)
    verdict = base_sensor_sign(state, table, table)
    assert verdict.verdict == "not_judged" and verdict.warns and math.isnan(verdict.correlation)
    assert "WARNING: the base-mat sensor's polarity was not checked" in verdict.line


def test_only_the_record_rows_are_judged() -> None:
    state = np.where(T < 5.0, ARMED, RUNNING)
    table = _table(0.004) + _noise(4)
    base = np.where(state == RUNNING, 0.8 * table, -table)  # against the table only outside the record
    assert base_sensor_sign(state, table, base).verdict == "with_table"
    assert base_sensor_sign(np.full(N, ARMED), table, base).verdict == "not_judged"  # no record rows at all


def test_a_table_playing_its_record_reversed_is_named_and_another_record_is_not() -> None:
    reversed_ = table_check({"verdict": "mismatch", "reason": "r", "correlation": -0.68, "amplitude_ratio": -0.68})
    assert "a table sensor of reversed polarity" in reversed_.line and reversed_.withheld
    other = table_check({"verdict": "mismatch", "reason": "r", "correlation": -0.13, "amplitude_ratio": 0.05})
    assert "reversed" not in other.line and other.withheld


def test_a_check_that_never_judged_warns() -> None:
    check = table_check({"verdict": "waiting", "reason": "not judged: too little motion"})
    assert check.line == f"table check: not judged: too little motion. {NOT_JUDGED_WARNING}"
    assert NOT_JUDGED_WARNING.startswith("WARNING:")
