"""The peak tables (runs side by side, passive/controlled, comparison, the consoles') against their data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.recording import (
    RunData,
    canonical_columns,
    load_run,
    load_runs,
    write_simulation_case,
)
from harness.recording.peaks import run_peaks
from harness.report import comparison_table, pair_table, reduction_table, runs_table
from harness.report.batch_summary import BatchCase, reduction_summary
from harness.report.peak_table import NO_REDUCTION, without_reductions
from harness.report.tables import peaks_pair_table
from harness.signals.peaks import Peaks

WEIGHT_N = 4 * 9.80665 * 1000.0
N_STORIES = 3


def _signals(scale: float, force_amplitude: float, n: int = 1500) -> dict[str, np.ndarray]:
    t = np.arange(n) * 0.004
    data = {c: np.zeros(n) for c in canonical_columns(N_STORIES, timing=False)}
    data["t_s"] = t
    data["table_acceleration_m_s2"] = 3.0 * np.sin(2 * np.pi * 1.3 * t)
    data["table_velocity_m_s"] = 0.2 * np.cos(2 * np.pi * 1.3 * t)
    data["table_displacement_m"] = -0.025 * np.sin(2 * np.pi * 1.3 * t)
    for j in range(1, N_STORIES + 1):
        data[f"drift_{j}_m"] = scale * 0.002 * (N_STORIES + 1 - j) * np.sin(2 * np.pi * 2.3 * t + j)
        data[f"floor_acceleration_{j}_m_s2"] = scale * (2.0 + j) * np.cos(2 * np.pi * 2.3 * t)
    data["base_acceleration_m_s2"] = scale * 1.7 * np.sin(2 * np.pi * 0.9 * t)
    data["sliding_displacement_m"] = scale * 0.04 * np.sin(2 * np.pi * 0.6 * t)
    data["force_command_N"] = force_amplitude * np.sin(2 * np.pi * 0.6 * t)
    return data


@pytest.fixture
def pair(tmp_path: Path) -> tuple[RunData, RunData, dict, dict]:
    passive = _signals(1.0, 0.0)
    controlled = _signals(0.4, 5000.0)
    columns = canonical_columns(N_STORIES, timing=False)
    meta = {"total_weight_N": WEIGHT_N, "record": {"name": "elcentro"}}
    write_simulation_case(tmp_path / "sim", "passive", columns, passive, {**meta, "controller": "passive"})
    write_simulation_case(tmp_path / "sim", "controlled", columns, controlled, {**meta, "controller": "eq23"})
    runs = load_runs([tmp_path / "sim"])
    return runs[0], runs[1], passive, controlled


def _peak(values: np.ndarray) -> float:
    return float(np.max(np.abs(values)))


def test_run_peaks_match_the_recorded_signals(pair) -> None:
    _, controlled_run, _, controlled = pair
    peaks = run_peaks(controlled_run)
    for j in range(1, N_STORIES + 1):
        assert peaks.drift_m[j - 1] == pytest.approx(_peak(controlled[f"drift_{j}_m"]), rel=1e-9)
        assert peaks.floor_acceleration_m_s2[j - 1] == pytest.approx(_peak(controlled[f"floor_acceleration_{j}_m_s2"]), rel=1e-9)
    assert peaks.sliding_displacement_m == pytest.approx(_peak(controlled["sliding_displacement_m"]), rel=1e-9)
    assert peaks.base_acceleration_m_s2 == pytest.approx(_peak(controlled["base_acceleration_m_s2"]), rel=1e-9)
    assert peaks.peak_force_pct_weight == pytest.approx(100 * _peak(controlled["force_command_N"]) / WEIGHT_N, rel=1e-9)
    assert peaks.table_acceleration_m_s2 == pytest.approx(_peak(controlled["table_acceleration_m_s2"]), rel=1e-9)


def test_pair_table_shows_peaks_in_display_units_and_reduction_beside_the_controlled_value(pair) -> None:
    passive_run, controlled_run, passive, controlled = pair
    table = pair_table(passive_run, controlled_run)
    assert table.columns[2] == "reduction (%)"
    row = table.row("drift_1")
    assert row.unit == "mm"
    assert row.values[0] == pytest.approx(1e3 * _peak(passive["drift_1_m"]), rel=1e-9)
    assert row.values[1] == pytest.approx(1e3 * _peak(controlled["drift_1_m"]), rel=1e-9)
    expected = 100 * (_peak(passive["drift_1_m"]) - _peak(controlled["drift_1_m"])) / _peak(passive["drift_1_m"])
    assert row.values[2] == pytest.approx(expected, rel=1e-9)
    assert row.values[2] == pytest.approx(60.0, abs=0.5)  # the controlled signals are 0.4 x the passive ones
    stroke = table.row("sliding_displacement")
    assert stroke.values[1] == pytest.approx(1e3 * _peak(controlled["sliding_displacement_m"]), rel=1e-9)
    force = table.row("force_percent_weight")
    assert force.values[0] == 0.0 and force.values[2] is None
    assert [r.key for r in table.rows][3:6] == ["drift_3", "drift_2", "drift_1"]


def test_comparison_table_gives_both_peaks_and_their_difference(pair) -> None:
    passive_run, controlled_run, passive, controlled = pair
    table = comparison_table(controlled_run, passive_run)
    row = table.row("floor_acceleration_3")
    a = _peak(controlled["floor_acceleration_3_m_s2"])
    b = _peak(passive["floor_acceleration_3_m_s2"])
    assert row.values[0] == pytest.approx(a, rel=1e-9)
    assert row.values[1] == pytest.approx(b, rel=1e-9)
    assert row.values[2] == pytest.approx(b - a, rel=1e-9)
    assert row.values[3] == pytest.approx(100 * (b - a) / a, rel=1e-9)


def test_runs_table_has_a_column_per_run_and_hides_absent_quantities(pair) -> None:
    passive_run, controlled_run, _, _ = pair
    table = runs_table([passive_run, controlled_run])
    assert table.columns == (passive_run.label, controlled_run.label)
    keys = [r.key for r in table.rows]
    assert "drift_3" in keys and "drift_4" not in keys


def test_force_percent_is_absent_without_total_weight(tmp_path: Path) -> None:
    columns = ("t_s", "force_command_N")
    signals = {"t_s": np.arange(3.0), "force_command_N": np.array([1.0, -4.0, 2.0])}
    folder = write_simulation_case(tmp_path, "controlled", columns, signals, {})
    run = load_run(folder)
    text = runs_table([run]).to_text()
    assert "Control force / weight" not in text


def test_table_text_lists_every_row_with_its_formatted_value(pair) -> None:
    passive_run, controlled_run, passive, _ = pair
    text = pair_table(passive_run, controlled_run).to_text()
    assert "Story 1 drift" in text and "reduction (%)" in text
    assert f"{1e3 * _peak(passive['drift_1_m']):.3f}" in text
    assert "60.0" in text


def test_html_and_csv_show_the_same_cells_as_the_text(pair) -> None:
    passive_run, controlled_run, passive, _ = pair
    table = pair_table(passive_run, controlled_run)
    html = table.to_html()
    assert "<th>Quantity</th><th>Unit</th>" in html and "<td>Story 1 drift</td>" in html
    assert f"<td class='num'>{1e3 * _peak(passive['drift_1_m']):.3f}</td>" in html
    lines = table.to_csv().splitlines()
    assert lines[0] == "quantity,key,unit," + ",".join(table.columns)
    assert len(lines) == 1 + len(table.rows)


def test_console_table_rows_labels_and_digits(pair) -> None:
    passive_run, controlled_run, passive, controlled = pair
    table = reduction_table(run_peaks(passive_run), run_peaks(controlled_run), "title", labels=("passive (sim.)", "dry run"))
    assert table.headings == ("response", "unit") and table.columns == ("passive (sim.)", "dry run", "reduction %")
    assert [row.label for row in table.rows] == [
        "story 3 drift", "story 2 drift", "story 1 drift",
        "floor 3 abs. acceleration", "floor 2 abs. acceleration", "floor 1 abs. acceleration",
        "base mat acceleration", "sliding displacement x_b", "peak force",
    ]
    drift = table.row("drift_1")
    assert table.cells(drift)[2:] == [f"{1e3 * _peak(passive['drift_1_m']):.3f}",
                                      f"{1e3 * _peak(controlled['drift_1_m']):.3f}", "60.0"]
    assert table.cells(table.row("floor_acceleration_1"))[1] == "m/s²"
    force_row = table.row("force_percent_weight")
    assert table.cells(force_row)[1:] == ["% weight", "0.00", f"{force_row.values[1]:.2f}", NO_REDUCTION]
    assert str(table.to_rich().renderables[0].title) == "title"


def test_console_table_of_a_passive_case_alone(pair) -> None:
    passive_run, _, _, _ = pair
    table = reduction_table(run_peaks(passive_run), None, "passive only")
    assert table.columns == ("passive",) and len(table.rows) == 3 * 2 + 3


#: Peaks of a run that tripped before its record started: the passive reference simulated over
#: no record at all is numerically zero (the values of the issue's dry run), the run's sensors read noise.
_NOTHING_RAN = Peaks(6.7e-10, 2.7e-8, (1.9e-15, 2.4e-15, 5.5e-13), (2.2e-14, 2.7e-14, 1.9e-11), 0.0)
_SENSOR_NOISE = Peaks(2e-5, 0.040, (1.0e-5, 1.6e-5, 1.0e-5), (0.056, 0.044, 0.036), 0.0)


def test_a_zero_reference_shows_no_reduction_in_every_table() -> None:
    console = reduction_table(_NOTHING_RAN, _SENSOR_NOISE, "tripped before the record")
    report = peaks_pair_table(_NOTHING_RAN, _SENSOR_NOISE, "report", ("passive", "dry run"))
    for table in (console, report):
        for row in table.rows:
            assert row.values[2] is None, row.key
            assert table.cells(row)[-1] == NO_REDUCTION
        assert table.to_text().count(NO_REDUCTION) == table.to_html().count(NO_REDUCTION) == len(table.rows)
        assert all(line.endswith(",") for line in table.to_csv().splitlines()[1:])  # an empty cell, no number
    batch = reduction_summary([BatchCase("a", "X", _NOTHING_RAN, _SENSOR_NOISE)])
    assert all(value is None for row in batch.rows for value in row.values)


def test_without_reductions_blanks_every_reduction_and_says_why(pair) -> None:
    passive_run, controlled_run, _, _ = pair
    table = pair_table(passive_run, controlled_run)
    blanked = without_reductions(table, "the table did not follow its record.")
    assert [row.values[:2] for row in blanked.rows] == [row.values[:2] for row in table.rows]
    assert all(blanked.cells(row)[-1] == NO_REDUCTION for row in blanked.rows)
    assert blanked.note.endswith("No reductions: the table did not follow its record.")
