"""Issue 33, item 3: every peak compared is taken over one window, the record plus a stated tail.

A dry run keeps running after its record (the loop's tail, then the force ramps down): a
base-mat acceleration peak there (1.94 m/s^2 at t = 31.02 s in the issue) must not be compared
with a simulated twin that ends with the record.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.recording.peaks import run_peaks
from harness.recording.reader import RunData
from harness.report.reference import reference_tables
from harness.report.tables import comparison_table, runs_table
from harness.signals.columns import BASE_ACCELERATION, SLIDING_DISPLACEMENT, TIME
from harness.signals.peaks import COMPARISON_TAIL_S, ComparisonWindow, peak_responses

RECORD_S = 30.0
START_S = 0.5  # loop time the record started (the settle before it)


def _dry_run(path: Path, spike_t_s: float) -> RunData:
    """A dry run's folder read back: steady 0.7 m/s^2 and 10 mm over the record, one spike at ``spike_t_s``."""
    t = np.arange(0.0, START_S + RECORD_S + 1.6, 0.002)
    acceleration = np.where(t >= START_S, 0.7 * np.sin(2 * np.pi * (t - START_S)), 0.0)
    acceleration[np.argmin(np.abs(t - spike_t_s))] = 1.94
    sliding = np.full_like(t, 0.010)
    twin = {"sliding_displacement_m": 0.010, "base_acceleration_m_s2": 0.715, "drift_m": [], "floor_acceleration_m_s2": [],
            "peak_force_pct_weight": 0.0}
    metadata = {"kind": "dry-run", "controller": "phi", "record": {"name": "synthetic", "duration_s": RECORD_S},
                "summary": {"record_start_t_s": START_S}, "reference": {"passive_peaks": twin, "twin_peaks": twin}}
    return RunData(path, metadata, {}, (TIME, BASE_ACCELERATION, SLIDING_DISPLACEMENT),
                   {TIME: t, BASE_ACCELERATION: acceleration, SLIDING_DISPLACEMENT: sliding}, [], None, False)


def test_a_peak_in_the_ramp_down_after_the_record_is_not_compared(tmp_path: Path) -> None:
    run = _dry_run(tmp_path, spike_t_s=START_S + RECORD_S + COMPARISON_TAIL_S + 0.52)
    peaks = run_peaks(run)
    assert peaks.base_acceleration_m_s2 == pytest.approx(0.7, rel=1e-3)  # not 1.94
    assert peaks.sliding_displacement_m == pytest.approx(0.010)


def test_a_peak_inside_the_record_is_compared(tmp_path: Path) -> None:
    run = _dry_run(tmp_path, spike_t_s=START_S + 12.0)
    assert run_peaks(run).base_acceleration_m_s2 == pytest.approx(1.94)


def test_a_simulated_case_from_zero_keeps_its_whole_record() -> None:
    t = np.linspace(0.0, RECORD_S, 3001)
    columns = {TIME: t, BASE_ACCELERATION: np.where(t == RECORD_S, 2.0, 0.5)}
    window = ComparisonWindow(0.0, RECORD_S)
    assert peak_responses(columns, None, window=window).base_acceleration_m_s2 == pytest.approx(2.0)
    assert window.end_s == RECORD_S + COMPARISON_TAIL_S


def test_every_peak_table_says_its_window(tmp_path: Path) -> None:
    run = _dry_run(tmp_path, spike_t_s=START_S + RECORD_S + 0.52)
    said = f"compared over the record ({RECORD_S:.2f} s) plus a {COMPARISON_TAIL_S:g} s tail"
    tables = [runs_table([run]), comparison_table(run, run), *reference_tables([run])]
    assert len(tables) == 4
    for table in tables:
        assert said in table.note, table.title
    twin = reference_tables([run])[1]
    row = next(row for row in twin.rows if row.key == "base_acceleration")
    assert row.values[1] == pytest.approx(0.7, rel=1e-3)  # the dry run's side, over the twin's window

