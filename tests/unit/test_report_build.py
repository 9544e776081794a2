"""Whole reports from small run folders made here: plots exist as valid PNGs of the stated size, HTML embeds them."""

from __future__ import annotations

import base64
import json
import struct
import time
from pathlib import Path

import numpy as np
import pytest

from harness.recording import (
    RunFolder,
    RunFolderError,
    canonical_columns,
    write_simulation_case,
)
from harness.report import build_report, summary_text
from harness.report.figure import WIDTH_PX
from harness.report.plots import drift_height_px

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
N_STORIES = 3
META = {
    "total_weight_N": 39855.0, "record": {"name": "elcentro"}, "stroke_soft_limit_m": 0.04, "stroke_hard_limit_m": 0.05,
    "force_limit_N": 6000.0,
}


def _signals(scale: float, n: int = 750, controlled: bool = True) -> dict[str, np.ndarray]:
    t = np.arange(n) * 0.004
    data = {c: np.full(n, np.nan) for c in canonical_columns(N_STORIES, timing=False)}
    data.update(
        t_s=t,
        table_acceleration_m_s2=2.0 * np.sin(2 * np.pi * t),
        table_velocity_m_s=0.3 * np.cos(2 * np.pi * t),
        table_displacement_m=0.02 * np.sin(2 * np.pi * t),
        base_acceleration_m_s2=scale * np.sin(2 * np.pi * t),
        sliding_displacement_m=scale * 0.03 * np.sin(2 * np.pi * 0.7 * t),
        hysteretic_nu=np.tanh(4 * np.cos(2 * np.pi * 0.7 * t)),
        friction_force_N=2300 * np.tanh(4 * np.cos(2 * np.pi * 0.7 * t)),
        sliding_variable_m_s=0.01 * scale * np.sin(3 * t),
        force_command_N=(4000.0 if controlled else 0.0) * np.sin(2 * np.pi * 0.7 * t),
    )
    for j in range(1, N_STORIES + 1):
        data[f"drift_{j}_m"] = scale * 0.001 * j * np.sin(2 * np.pi * 2.3 * t)
        data[f"floor_acceleration_{j}_m_s2"] = scale * (1 + j) * np.sin(2 * np.pi * 2.3 * t)
    return data


def _simulation(root: Path) -> Path:
    columns = canonical_columns(N_STORIES, timing=False)
    passive = {**META, "controller": "passive", "profile_name": "nceer_4dof"}
    controlled = {**META, "controller": "eq23", "profile_name": "nceer_4dof"}
    write_simulation_case(root / "sim", "passive", columns, _signals(1.0, controlled=False), passive)
    write_simulation_case(root / "sim", "controlled", columns, _signals(0.5), controlled)
    return root / "sim"


def _dry_run(root: Path, finish: bool = True) -> Path:
    columns = canonical_columns(N_STORIES)
    run = RunFolder.create(root, "nceer_4dof", "dry-run", {}, columns, metadata={**META, "controller": "eq23"})
    run.start()
    data = _signals(0.55)
    rng = np.random.default_rng(7)
    row = np.zeros(len(columns))
    for i in range(len(data["t_s"])):
        for k, name in enumerate(columns):
            row[k] = data[name][i] if name in data else 0.0
        row[columns.index("lateness_s")] = abs(rng.normal(60e-6, 20e-6))
        row[columns.index("compute_s")] = abs(rng.normal(200e-6, 40e-6))
        run.record_row(row)
    run.record_event(1.2, "warning", "stroke_soft_limit", {"x_b_m": 0.041})
    run.record_event(2.5, "trip", "stroke_hard_limit")
    if finish:
        run.finish("tripped", trip_reason="stroke_hard_limit")
    else:  # leave it running, as a crashed loop would, once every row is on disk
        end = time.monotonic() + 10
        while run.rows_written < len(data["t_s"]) and time.monotonic() < end:
            time.sleep(0.01)
    return run.path


def _png_size(path: Path) -> tuple[int, int]:
    head = path.read_bytes()[:24]
    assert head[:8] == PNG_SIGNATURE, f"{path.name} is not a PNG"
    assert head[12:16] == b"IHDR"
    width, height = struct.unpack(">II", head[16:24])
    return width, height


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory):
    root = tmp_path_factory.mktemp("runs")
    calls: list[tuple[str, int, int]] = []
    result = build_report([_simulation(root), _dry_run(root)], root / "report", progress=lambda m, d, t: calls.append((m, d, t)))
    return result, calls


def test_every_plot_is_a_png_of_the_stated_size(report) -> None:
    result, _ = report
    names = [p.name for p in result.plots]
    assert names == ["peak_profile", "drift", "table_motion", "hysteresis", "stroke", "force", "sliding_variable", "timing"]
    for plot in result.plots:
        assert plot.path.is_file() and plot.path.parent == result.out_dir
        assert _png_size(plot.path) == (plot.width_px, plot.height_px)
        assert plot.width_px == WIDTH_PX
    drift = result.plots[1]
    assert drift.height_px == drift_height_px(N_STORIES)


def test_html_is_self_contained_and_embeds_every_plot(report) -> None:
    result, _ = report
    page = result.html_path.read_text()
    assert page.startswith("<!DOCTYPE html>") and page.rstrip().endswith("</html>")
    for plot in result.plots:
        assert "data:image/png;base64," + base64.b64encode(plot.path.read_bytes()).decode() in page
    assert "src='http" not in page and 'src="http' not in page and "<link" not in page
    assert "Passive against controlled" in page and "reduction (%)" in page


def test_tables_include_the_pair_and_the_run_against_simulation_comparison(report) -> None:
    result, _ = report
    titles = [t.title for t in result.tables]
    assert titles[0] == "Peak responses"
    pairs = [title for title in titles if title.startswith("Passive against controlled: ")]
    assert len(pairs) == 2  # sim controlled and the dry run, each against the sim passive
    comparison = [t for t in result.tables if t.title.startswith("Comparison")]
    assert len(comparison) == 1
    row = comparison[0].row("drift_1")
    peak_sine = np.max(np.abs(np.sin(2 * np.pi * 2.3 * np.arange(750) * 0.004)))
    assert row.values[0] == pytest.approx(0.5 * 1e3 * 0.001 * peak_sine, rel=1e-9)
    assert row.values[3] == pytest.approx(10.0, rel=1e-6)  # 0.55 against 0.5


def test_summary_text_lists_runs_warnings_and_tables(report) -> None:
    result, _ = report
    text = summary_text(result)
    assert text == result.summary == (result.out_dir / "summary.txt").read_text().rstrip("\n")
    assert "tripped (stroke_hard_limit)" in text
    assert "Story 3 drift" in text and str(result.html_path) in text


def test_progress_reports_each_step_and_ends_complete(report) -> None:
    _, calls = report
    done = [d for _, d, _ in calls]
    assert done == sorted(done) and len(calls) >= 9
    assert calls[-1][1] == calls[-1][2]
    assert any("plotting drift" in m for m, _, _ in calls)


def test_incomplete_run_warns_and_continues(tmp_path: Path) -> None:
    path = _dry_run(tmp_path, finish=False)
    result = build_report([path], tmp_path / "out")
    assert any("did not finish cleanly" in w for w in result.warnings)
    assert "did not finish cleanly" in result.summary
    assert result.html_path.is_file() and result.plots


def test_unknown_format_version_is_an_error(tmp_path: Path) -> None:
    path = _dry_run(tmp_path)
    meta = json.loads((path / "metadata.json").read_text())
    meta["format_version"] = 99
    (path / "metadata.json").write_text(json.dumps(meta))
    with pytest.raises(RunFolderError, match="found format_version 99"):
        build_report([path], tmp_path / "out")


def test_plots_whose_columns_are_absent_are_skipped(tmp_path: Path) -> None:
    t = np.arange(100) * 0.01
    folder = write_simulation_case(tmp_path, "controlled", ("t_s", "drift_1_m"), {"t_s": t, "drift_1_m": 0.001 * np.sin(t)}, {})
    result = build_report([folder], tmp_path / "out")
    assert [p.name for p in result.plots] == ["peak_profile", "drift"]
    assert _png_size(result.plots[1].path) == (WIDTH_PX, drift_height_px(1))
    assert sorted(p.name for p in (tmp_path / "out").glob("*.png")) == ["drift.png", "peak_profile.png"]


def test_no_runs_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="expected at least one"):
        build_report([], tmp_path)


def test_each_table_is_also_written_as_csv_with_the_same_numbers(report) -> None:
    import csv

    result, _ = report
    assert len(result.table_files) == len(result.tables) + len(result.context)  # peak tables, then the context
    assert result.table_files[0].name == "table_1_peak_responses.csv"
    with open(result.table_files[1], newline="") as handle:
        rows = list(csv.reader(handle))
    table = result.tables[1]
    assert rows[0] == ["quantity", "key", "unit", *table.columns]
    by_key = {row[1]: row for row in rows[1:]}
    for table_row in table.rows:
        cells = by_key[table_row.key][3:]
        for cell, value in zip(cells, table_row.values, strict=True):
            assert (cell == "") if value is None else float(cell) == value
