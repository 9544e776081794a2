"""The safety review's reproductions, through the command line, each now ending safely."""

from __future__ import annotations

import json
from pathlib import Path

from harness import exit_codes
from harness.cli import main


def _dry_run(tmp_path: Path, *args: str) -> tuple[int, dict]:
    status = main(["dry-run", "--lockstep", "--quiet", "--log-dir", str(tmp_path), *args])
    folder = sorted(p for p in tmp_path.iterdir() if p.is_dir())[-1]
    return status, json.loads((folder / "metadata.json").read_text())


def test_staleness_is_judged_with_message_timestamps_too(tmp_path, capsys):
    # The review: with timestamp_source=message the ages came out near -1.8e9 s and passed every
    # check; frozen table sensors ran 1,500 ticks with the drive enabled. Now they trip.
    status, metadata = _dry_run(
        tmp_path, "--duration", "3", "--set", "can.timestamp_source=message",
        "--set", "rig.faults=[{kind: dropout, target: TABLE_SENSORS, start_s: 1.0}]",
    )
    capsys.readouterr()
    assert status == exit_codes.TRIPPED
    assert metadata["trip_reason"] == "sensor_stale"


def test_message_timestamps_on_a_healthy_rig_complete(tmp_path, capsys):
    status, metadata = _dry_run(tmp_path, "--duration", "1", "--set", "can.timestamp_source=message")
    capsys.readouterr()
    assert status == exit_codes.OK, metadata.get("trip_reason")
