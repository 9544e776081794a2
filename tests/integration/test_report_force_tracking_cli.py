"""``harness report`` on a real lockstep dry run shows its force tracking; ``harness simulate`` prints the same measures."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import main
from harness.recording import load_run
from harness.report.force_tracking_table import TITLE, run_tracking
from harness.signals.columns import FORCE_RAW


def test_the_report_of_a_lockstep_dry_run_shows_its_force_tracking(tmp_path: Path, capsys) -> None:
    assert main(["dry-run", "--log-dir", str(tmp_path / "runs"), "--lockstep", "--quiet", "--duration", "2"]) == exit_codes.OK
    (folder,) = sorted(p for p in (tmp_path / "runs").iterdir() if p.is_dir())
    out = tmp_path / "report"
    assert main(["report", str(folder), "--out", str(out), "--quiet"]) == exit_codes.OK
    capsys.readouterr()
    assert TITLE in (out / "summary.txt").read_text()
    assert (out / "force_tracking.png").is_file()
    (table_file,) = out.glob("table_*_force_tracking_*.csv")
    with open(table_file, newline="") as handle:
        rows = list(csv.reader(handle))
    against = rows[0].index("Against")
    assert {row[against] for row in rows[1:]} == {"the controller's force", "the command sent"}
    # The numbers are the run's own: the load cell answered a force the controller asked for, late and not exactly.
    tracked = run_tracking(load_run(folder))[FORCE_RAW]
    assert tracked.samples > 500 and 0.0 < tracked.delay_s < 0.1 and tracked.rms_error_N > 0.0
    delay = rows[0].index("Delay (ms)")
    assert any(row[delay] == f"{tracked.delay_s * 1e3:+.2f}" for row in rows[1:])


def test_simulate_prints_and_reports_the_force_tracking_the_report_computes_from_its_case(tmp_path: Path, capsys) -> None:
    # One piece of code: the figures `harness simulate --rig-effects` prints and writes are the report's for its case.
    args = ["simulate", "--duration", "3", "--rig-effects", "--set", "control.compensation=model",
            "--json", str(tmp_path / "study.json"), "--out", str(tmp_path / "study")]
    assert main(args) == exit_codes.OK
    printed = capsys.readouterr().out
    document = json.loads((tmp_path / "study.json").read_text())
    written = document["force_tracking"]["controller_force"]
    assert written["rms_error_N"] == document["force_tracking_rms_N"]["controller_force"]
    case = run_tracking(load_run(tmp_path / "study" / "controlled"))[FORCE_RAW]
    assert case.rms_error_N == pytest.approx(written["rms_error_N"], rel=1e-6)
    assert case.delay_s == pytest.approx(written["delay_s"], rel=1e-6)
    assert f"RMS error {written['rms_error_N'] / 1e3:.3f} kN ({written['rms_error_percent']:.1f} % of its RMS)" in printed
    assert f"delay {written['delay_s'] * 1e3:+.1f} ms" in printed
