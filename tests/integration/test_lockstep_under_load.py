"""Lockstep never trips on host timing: a lockstep dry run completes while both cores are busy.

Two processes spin on the two cores for the whole run, so the harness and the rig process
get the CPU only in slices. In lockstep the rig waits for each command; its drive watchdog
then uses the lockstep bound (``rig.drive.lockstep_watchdog_timeout_s``), and every check of
the harness runs on loop time. Before, a busy machine tripped ``drive_fault`` (the
real-time heartbeat watchdog counting wall-clock time) in lockstep.
"""

from __future__ import annotations

import json
import subprocess
import sys

from harness import exit_codes

SPIN = "import time\nend = time.monotonic() + 600\nwhile time.monotonic() < end: pass\n"


def test_a_lockstep_dry_run_completes_while_two_busy_processes_load_both_cores(tmp_path):
    spinners = [subprocess.Popen([sys.executable, "-c", SPIN]) for _ in range(2)]
    try:
        done = subprocess.run(
            [sys.executable, "-m", "harness.cli", "dry-run", "--lockstep", "--quiet", "--duration", "4",
             "--log-dir", str(tmp_path)],
            capture_output=True, text=True, timeout=600,
        )
    finally:
        for spinner in spinners:
            spinner.kill()
            spinner.wait()
    assert done.returncode == exit_codes.OK, done.stdout[-3000:] + done.stderr[-2000:]
    folder = next(p for p in tmp_path.iterdir() if p.is_dir())
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["outcome"] == "completed" and metadata["summary"]["timing"]["lockstep"] is True
