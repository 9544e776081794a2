"""The table against the record the harness was told, through the rig: one dry run per verdict.

As in issue 21's steps, the rig is an external one (``harness dry-run --external-rig``) with a
record of its own: here a virtual rig this test serves on python-can's in-process bus, in
lockstep, while the command under test is told its record on its command line; and once with
the issue's own steps, a `harness rig` process on the seqpacket bus. Short records (4-5 s of
El Centro and Pacoima at time scale 2); the table check decides from 2.1 s of El Centro, 4.1 s
of Pacoima.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.recording import load_run
from harness.report import build_report
from harness.report.peak_table import NO_REDUCTION
from harness.runs.dry_run import serving_virtual_rig
from harness.runs.options import StudyOptions, prepare_motion, resolve_profile
from tests.conftest import REPO

DURATION_S = 4.0
PGA_G = 0.34


@contextmanager
def external_rig(records_dir: Path, channel: str, record: str, pga_g: float = PGA_G) -> Iterator[None]:
    """A virtual rig playing ``record`` at ``pga_g`` on the in-process bus ``channel``, in lockstep."""
    study = StudyOptions(record=record, records_dir=str(records_dir), pga_g=pga_g, time_scale=2.0, duration_s=DURATION_S)
    profile = resolve_profile(load_profile(None), study)
    can = profile.can_settings("virtual", channel)
    with serving_virtual_rig(profile, can, True, prepare_motion(profile)):
        yield


def _dry_run(tmp_path: Path, records_dir: Path, channel: str, record: str) -> int:
    """``harness dry-run --external-rig`` on ``channel``, told ``record``."""
    return main([
        "dry-run", "--external-rig", "--lockstep", "--interface", "virtual", "--channel", channel,
        "--records-dir", str(records_dir), "--record", record, "--pga", str(PGA_G), "--time-scale", "2",
        "--duration", str(DURATION_S), "--log-dir", str(tmp_path),
    ])


def _run_folder(tmp_path: Path) -> Path:
    (folder,) = [path for path in tmp_path.iterdir() if path.is_dir()]
    return folder


def _table_summary(folder: Path) -> dict:
    return json.loads((folder / "metadata.json").read_text())["summary"]["table_record"]


def _reduction_cells(out: str) -> list[str]:
    """The last cell of each story-drift row of the console's peak table."""
    return [line.split()[-1] for line in out.splitlines() if line.strip().startswith("story ") and "drift" in line]


def _channel(name: str) -> str:
    return f"table-check-{name}-{os.getpid()}"


def test_a_table_playing_the_told_record_matches(tmp_path, records_dir, capsys) -> None:
    with external_rig(records_dir, _channel("match"), "el_centro"):
        status = _dry_run(tmp_path, records_dir, _channel("match"), "el_centro")
    out = capsys.readouterr().out
    assert status == exit_codes.OK, out
    summary = _table_summary(_run_folder(tmp_path))
    assert summary["verdict"] == "match", summary
    assert summary["evaluations"] >= 3  # judged from 2.1 s on, every 0.5 s, and at the end of the record
    final = summary["final"]
    assert final["correlation"] > 0.99 and 0.0 < final["delay_s"] < 0.02 and 0.9 < final["amplitude_ratio"] < 1.1
    assert "table check: match" in " ".join(out.split())
    cells = _reduction_cells(out)
    assert len(cells) == 3 and all(cell != "-" for cell in cells), out  # the reductions are printed
    events = load_run(_run_folder(tmp_path)).events
    assert not any(e["name"].startswith("table_record") for e in events)


def test_a_table_playing_the_told_record_at_six_tenths_of_its_size_is_marginal(tmp_path, records_dir, capsys) -> None:
    # The drive file at the wrong scale: the told record, correlated and on time, at 0.6 times its size
    # (between the match band's 0.75 and the mismatch bound's 0.5).
    with external_rig(records_dir, _channel("marginal"), "el_centro", pga_g=0.6 * PGA_G):
        status = _dry_run(tmp_path, records_dir, _channel("marginal"), "el_centro")
    out = " ".join(capsys.readouterr().out.split())
    assert status == exit_codes.OK, out  # a warning, not a stop
    folder = _run_folder(tmp_path)
    summary = _table_summary(folder)
    assert summary["verdict"] == "marginal", summary
    assert 0.5 < summary["amplitude_ratio"] < 0.75 and summary["correlation"] > 0.9
    assert "with a warning: the table check is marginal" in out
    assert "table check: marginal" in out and "amplitude ratio" in out
    assert "reduction %*" in out and "Doubtful" in out  # the reductions are flagged
    events = load_run(folder).events
    assert any(e["kind"] == "fault" and e["name"] == "table_record_marginal" for e in events)
    report = build_report([folder], tmp_path / "report")
    assert any("table check: marginal" in warning for warning in report.warnings)
    reference = next(table for table in report.tables if table.title.startswith("Against the simulated passive"))
    assert reference.columns[-1].endswith("*") and "Doubtful" in reference.note


def test_a_table_playing_another_record_is_stopped_and_prints_no_reductions(tmp_path, records_dir, capsys) -> None:
    # The rig plays Pacoima; the harness is told El Centro (issue 21's steps, the other way round: El Centro's
    # swings open the check's gate at 2.1 s, inside this short record).
    with external_rig(records_dir, _channel("mismatch"), "pacoima"):
        status = _dry_run(tmp_path, records_dir, _channel("mismatch"), "el_centro")
    printed = capsys.readouterr().out
    out = " ".join(printed.split())
    assert status == exit_codes.STOPPED, out
    folder = _run_folder(tmp_path)
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["outcome"] == "stopped" and metadata["trip_reason"] == "table_record_mismatch"
    summary = metadata["summary"]["table_record"]
    assert summary["verdict"] == "mismatch" and summary["judged_at_s"] < 2.7, summary  # at the first evaluation
    assert "outcome: stopped (table_record_mismatch)" in out
    assert "table check: MISMATCH" in out and "Reductions not shown" in out
    cells = _reduction_cells(printed)
    assert cells == [NO_REDUCTION] * 3, out
    run = load_run(folder)
    mismatch = [e for e in run.events if e["name"] == "table_record_mismatch"]
    assert mismatch and mismatch[0]["kind"] == "fault"
    assert any(e["kind"] == "state" and "table_record_mismatch" in e["detail"] for e in run.events)  # the safe stop
    # The force ramped to zero and the drive was disabled at the end.
    assert run["drive_enabled"][-1] == 0.0 and run["force_command_N"][-1] == 0.0
    report = build_report([folder], tmp_path / "report")
    assert any("table check: MISMATCH" in warning for warning in report.warnings)
    reference = next(table for table in report.tables if table.title.startswith("Against the simulated passive"))
    assert all(row.values[-1] is None for row in reference.rows), "the report withholds the reductions"



def test_issue_21_steps_a_rig_process_playing_el_centro_for_a_harness_told_pacoima(tmp_path, records_dir, capsys) -> None:
    # The issue's own steps: `harness rig --lockstep --record el_centro` in its own process on the seqpacket bus,
    # `harness dry-run --external-rig --lockstep --interface seqpacket --record pacoima` (5 s: Pacoima's gate is 4.1 s).
    channel = f"table-check-issue-{os.getpid()}"
    record = ["--records-dir", str(records_dir), "--duration", "5"]
    rig = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "rig", "--lockstep", "--interface", "seqpacket", "--channel", channel,
         "--record", "el_centro", "--parent-pid", str(os.getpid()), *record],
        cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    try:
        status = main(["dry-run", "--external-rig", "--lockstep", "--interface", "seqpacket", "--channel", channel,
                       "--record", "pacoima", "--log-dir", str(tmp_path), *record])
    finally:
        rig.send_signal(signal.SIGINT)
        rig.wait(timeout=60)
    out = " ".join(capsys.readouterr().out.split())
    assert status == exit_codes.STOPPED, out
    assert "outcome: stopped (table_record_mismatch)" in out and "Reductions not shown" in out
    summary = _table_summary(_run_folder(tmp_path))
    assert summary["verdict"] == "mismatch" and summary["judged_at_s"] < 4.7, summary
