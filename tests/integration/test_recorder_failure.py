"""A recorder that cannot write is never silent: counted, marked in metadata.json, said, and exit status 3.

The field report: under ``ulimit -f 150`` the recorder stopped after 480 of 2,402 rows, yet the
dry run printed its peaks, said "completed", exited 0 and its metadata said 0 rows were dropped.
"""

from __future__ import annotations

import json
import resource
import signal
import subprocess
import sys
from pathlib import Path

from harness import exit_codes
from harness.runs.session import SessionResult
from tests.conftest import REPO

#: Bytes any one file may grow to: the run's profile.yaml and metadata.json fit (a few kB),
#: can.log and signals.csv of a 2 s lockstep dry run (about 400 kB each) do not.
FILE_SIZE_LIMIT = 150 * 1024


def _limit_file_size() -> None:
    """In the child: the shell's ``ulimit -f 150``; a write past it fails with EFBIG instead of a signal."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (FILE_SIZE_LIMIT, FILE_SIZE_LIMIT))


def test_a_file_size_limit_during_a_dry_run_stops_it_safely_is_reported_and_exits_3(tmp_path: Path) -> None:
    done = subprocess.run(
        [sys.executable, "-m", "harness.cli", "dry-run", "--lockstep", "--duration", "2", "--quiet",
         "--log-dir", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, timeout=600, preexec_fn=_limit_file_size,
    )
    out = " ".join((done.stdout + done.stderr).split())  # rich wraps long lines
    assert "Traceback" not in out
    assert done.returncode == exit_codes.TRIPPED, out
    assert "outcome: stopped (record_lost), record lost: lost" in out  # a safe stop (docs/SAFETY.md, "A lost record")
    assert "File too large" in out and "repeat the test" in out
    (folder,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    meta = json.loads((folder / "metadata.json").read_text())
    recorder = meta["recorder"]
    assert meta["outcome"] == "stopped" and meta["trip_reason"] == "record_lost" and meta["record_complete"] is False
    assert "[Errno 27] File too large" in recorder["error"]
    assert recorder["lost"]["rows"] > 0 and recorder["lost"]["frames"] > 0
    # every tick handed the recorder one row: each is either confirmed written or counted lost
    assert recorder["rows_written"] + recorder["lost"]["rows"] == meta["summary"]["timing"]["ticks"]
    events = [json.loads(line) for line in (folder / "events.jsonl").read_text().splitlines() if line.strip()]
    assert any(event["name"] == "recorder_failed" for event in events)


def test_exit_status_of_a_lost_record() -> None:
    """A lost record turns "completed" (0) and a stop (4) into 3; a trip stays 3."""

    def status(outcome: str, problem: str) -> int:
        return SessionResult(outcome, "", Path("."), None, record_problem=problem).exit_code

    lost = "lost 10 of 20 rows (OSError: [Errno 27] File too large)"
    assert status("completed", "") == exit_codes.OK
    assert status("completed", lost) == exit_codes.TRIPPED
    assert status("tripped", lost) == exit_codes.TRIPPED
    assert status("stopped", lost) == exit_codes.TRIPPED
    assert status("stopped", "") == exit_codes.STOPPED
