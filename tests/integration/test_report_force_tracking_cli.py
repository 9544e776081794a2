"""``harness report`` on a real lockstep dry-run folder: the force-tracking section is there, from the run's load cell."""

from __future__ import annotations

import csv
from pathlib import Path

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
