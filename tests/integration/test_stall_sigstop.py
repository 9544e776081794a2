"""A loop stall in real time is named as the stall, end to end: the harness process is stopped (SIGSTOP).

The default real-time dry run, the virtual rig in its own process: once the run is RUNNING the
test stops the harness process (not the rig) for 150 ms, three times the drive's 50 ms watchdog,
then lets it go on. The rig's drive latches HEARTBEAT_WATCHDOG meanwhile. The run must trip
``loop_stall`` (before issue 30 it tripped ``drive_fault``, "actuator drive reports a fault"),
its detail must give the gap and name the drive's watchdog fault as its consequence, and
events.jsonl must hold the gap: a ``stall_past_budget`` event with its start, end, phase and
what the loop was doing, whose length is the "longest gap" the summary reports. A run the pre-flight
refuses before it arms is run again (tests/realtime_runs.py); marked ``realtime``: the serial pass.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from harness import exit_codes
from tests.integration.test_realtime_dry_run import PROFILE_RATE_HZ, STALL_BUDGET_S
from tests.realtime_runs import end, pause, run_real_time, running_folder

pytestmark = pytest.mark.realtime

STOP_S = 0.15
DURATION_S = 8.0


def _stopped_once_while_running(log_dir: Path, seen: dict[str, Path]) -> subprocess.CompletedProcess:
    """One real-time dry run, stopped for STOP_S once it is RUNNING; its folder in ``seen["folder"]``."""
    command = [sys.executable, "-m", "harness.cli", "dry-run", "--duration", str(DURATION_S), "--quiet", "--log-dir",
               str(log_dir)]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               env={**os.environ, "COLUMNS": "120"})
    try:
        folder = running_folder(log_dir, process)
        if folder is None:  # ended before RUNNING: refused by the pre-flight (run again) or a failure the test reports
            out, err = process.communicate(timeout=60)
            return subprocess.CompletedProcess(command, process.returncode, out, err)
        seen["folder"] = folder
        pause(process, STOP_S, after_s=0.3)
        out, err = process.communicate(timeout=120)
    finally:
        end(process)
    return subprocess.CompletedProcess(command, process.returncode, out, err)


def test_a_harness_stopped_longer_than_the_drive_watchdog_trips_loop_stall_with_its_gap(tmp_path) -> None:
    seen: dict[str, Path] = {}
    done = run_real_time(lambda: _stopped_once_while_running(tmp_path, seen), log_dir=tmp_path, rate_hz=PROFILE_RATE_HZ,
                         stall_budget_s=STALL_BUDGET_S, what="harness dry-run, stopped for 150 ms once RUNNING")
    out, err = done.stdout, done.stderr
    assert "folder" in seen, "the run never reached RUNNING: " + out[-2000:] + err[-2000:]
    folder = seen["folder"]
    assert done.returncode == exit_codes.TRIPPED, out + err
    assert "tripped (loop_stall)" in out, out
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["trip_reason"] == "loop_stall"
    events = [json.loads(line) for line in (folder / "events.jsonl").read_text().splitlines()]
    trip = next(e["detail"] for e in events if e["kind"] == "fault" and e["name"] == "loop_stall")
    gap_ms = float(re.search(r"the loop went (\S+) ms without a command", trip).group(1))
    assert gap_ms >= STOP_S * 1e3
    assert "(HEARTBEAT_WATCHDOG) after it, a consequence of the stall" in trip  # the drive's fault, named as the stall's
    assert not any(e["name"] == "drive_fault" for e in events)
    gaps = [e for e in events if e["name"] == "stall_past_budget"]
    assert gaps, [e["name"] for e in events]
    longest = metadata["summary"]["timing"]["longest_stall_s"]
    logged = [float(re.match(r"(\S+) ms between two ticks", e["detail"]).group(1)) for e in gaps]
    assert max(logged) == pytest.approx(longest * 1e3, abs=0.06)  # the longest gap counted is a logged one
    stall = gaps[logged.index(max(logged))]["detail"]
    assert "begun in RUNNING" in stall and re.search(r"from \S+ s to \S+ s \(loop time\)", stall)
    assert re.search(r"the loop was .* for \S+ ms \((read|control|supervise|write|record|phase|wait); parts in ms:", stall)
