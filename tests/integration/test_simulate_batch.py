"""``harness simulate --record a,b --controller X,Y``: a folder per combination and the summary tables."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.recording import strict_json
from harness.recording.peaks import run_peaks
from harness.recording.reader import load_runs
from harness.report.batch_summary import BatchCase, peaks_per_record, reduction_summary
from harness.runs.simulate_batch import split_list
from harness.signals.peaks import Peaks, reduction_pct

RECORDS = ("synthetic:1", "synthetic:2")
CONTROLLERS = ("FSF-I", "OF-I")


def _peaks(drift_mm: float, sliding_mm: float) -> Peaks:
    return Peaks(sliding_mm * 1e-3, 1.0, (drift_mm * 1e-3,), (2.0,), 0.0)


def test_the_summary_gives_mean_worst_and_largest_reduction_per_controller() -> None:
    cases = [
        BatchCase("a", "X", _peaks(10.0, 50.0), _peaks(1.0, 60.0)),
        BatchCase("b", "X", _peaks(20.0, 40.0), _peaks(10.0, 40.0)),
        BatchCase("a", "Y", _peaks(10.0, 50.0), _peaks(5.0, 50.0)),
        BatchCase("b", "Y", _peaks(20.0, 40.0), _peaks(5.0, 40.0)),
    ]
    summary = reduction_summary(cases)
    assert summary.columns == ("X mean", "X min", "X max", "Y mean", "Y min", "Y max")
    assert summary.row("drift_1").values == pytest.approx((70.0, 50.0, 90.0, 62.5, 50.0, 75.0))
    # X's sliding displacement grew by 20 % on record a: the worst case shows it where "max" (0 %) hid it
    assert summary.row("sliding_displacement").values == pytest.approx((-10.0, -20.0, 0.0, 0.0, 0.0, 0.0))
    assert summary.cells(summary.row("sliding_displacement"))[3] == "-20.0"
    assert "force_percent_weight" not in [row.key for row in summary.rows]  # no reduction of a force
    peaks = peaks_per_record(cases)
    assert peaks.columns == ("a passive", "a X", "a Y", "b passive", "b X", "b Y")
    assert peaks.row("drift_1").values == pytest.approx((10.0, 1.0, 5.0, 20.0, 10.0, 5.0))


def test_split_list_reads_comma_separated_names() -> None:
    assert split_list("el_centro, pacoima,") == ["el_centro", "pacoima"]
    assert split_list(None) == [None]


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory):
    out = tmp_path_factory.mktemp("batch")
    status = main(["simulate", "eight_story", "--record", ",".join(RECORDS), "--controller", ",".join(CONTROLLERS),
                   "--duration", "2", "--out", str(out / "study"), "--json", str(out / "batch.json"), "--quiet"])
    return status, out


def test_a_batch_writes_one_case_set_per_record_and_controller(batch) -> None:
    status, out = batch
    assert status == 0
    folders = sorted(p.name for p in (out / "study").iterdir() if p.is_dir())
    assert folders == ["synthetic-1_FSF-I", "synthetic-1_OF-I", "synthetic-2_FSF-I", "synthetic-2_OF-I"]
    runs = load_runs([out / "study" / folders[0]])
    assert [run.case for run in runs] == ["passive", "controlled"]
    assert runs[1].metadata["controller"] == "FSF-I" and runs[1].record_name == "synthetic:1"
    documents = strict_json.loads((out / "batch.json").read_text())["runs"]
    assert [(d["record"]["name"], d["controller"]) for d in documents] == [
        (record, controller) for record in RECORDS for controller in CONTROLLERS]


def test_the_batch_summary_matches_the_case_folders(batch) -> None:
    _, out = batch
    with open(out / "study" / "summary_reduction.csv", newline="") as handle:
        rows = {row["key"]: row for row in csv.DictReader(handle)}
    for controller in CONTROLLERS:
        reductions = []
        for record in RECORDS:
            passive, controlled = load_runs([out / "study" / f"{record.replace(':', '-')}_{controller}"])
            reductions.append(reduction_pct(run_peaks(passive).drift_m[7], run_peaks(controlled).drift_m[7]))
        assert float(rows["drift_8"][f"{controller} mean"]) == pytest.approx(np.mean(reductions), rel=1e-9)
        assert float(rows["drift_8"][f"{controller} min"]) == pytest.approx(np.min(reductions), rel=1e-9)
        assert float(rows["drift_8"][f"{controller} max"]) == pytest.approx(np.max(reductions), rel=1e-9)
    assert (out / "study" / "summary_peaks.csv").is_file() and (out / "study" / "summary.txt").is_file()


def test_a_report_of_the_batch_folder_reads_every_case_set(batch, tmp_path: Path) -> None:
    from harness.report import build_report

    _, out = batch
    result = build_report([out / "study"], tmp_path / "report")
    assert len(result.runs) == 8
    assert len({run.label for run in result.runs}) == 8


def test_none_in_a_list_of_controllers_is_refused(tmp_path: Path, capsys) -> None:
    assert main(["simulate", "eight_story", "--controller", "FSF-I,none", "--duration", "1", "--quiet"]) == 2
    assert "cannot be part of a list" in capsys.readouterr().out
