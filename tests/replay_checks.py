"""What a test asserts of ``harness replay`` on a run folder: every tick identical, and the ending it names.

Shared by tests/integration/test_replay.py and the fault-injection dry runs
(tests/integration/test_fault_injection.py), which replay each of their tripped runs.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np

from harness import exit_codes
from harness.cli import main
from harness.loop.tick_log import TICK_COLUMNS
from harness.recording import load_run


def replay(capsys, folder: Path, *args: str) -> tuple[int, str]:
    """Run ``harness replay FOLDER ARGS``; its exit status and output."""
    capsys.readouterr()
    status = main(["replay", str(folder), *args])
    captured = capsys.readouterr()
    return status, captured.out + captured.err


def tick_records(folder: Path) -> np.ndarray:
    """The run's tick record, its start mark removed."""
    return np.fromfile(folder / "ticks.bin", dtype="<f8").reshape(-1, len(TICK_COLUMNS))[1:]


def assert_identical(capsys, folder: Path) -> str:
    """Replay ``folder`` and assert every one of its ticks identical; the replay's output."""
    status, out = replay(capsys, folder)
    n = len(tick_records(folder))
    assert n == len(load_run(folder)["t_s"]) > 0  # one record per row of the run
    assert status == exit_codes.OK, out
    assert f"replayed {n} ticks: {n} identical" in out, out
    return out


def ending(folder: Path) -> tuple[str, str, float]:
    """The run's outcome, reason and the time of the event that ended it (from its own files)."""
    metadata = json.loads((folder / "metadata.json").read_text())
    reason = metadata["trip_reason"] or ""
    t = next((float(e["t_s"]) for e in load_run(folder).events if e["name"] == reason), float("nan")) if reason else 0.0
    return metadata["outcome"], reason, t


def assert_trip_replayed(capsys, folder: Path, reason: str) -> None:
    """Replay a tripped run bit for bit, and assert the replay names the recorded trip, its reason and time."""
    outcome, recorded_reason, t = ending(folder)
    assert (outcome, recorded_reason) == ("tripped", reason)
    out = assert_identical(capsys, folder)
    for which in ("recorded", "replayed"):
        assert f"{which} outcome: tripped ({reason}) at t = {t:.3f} s: fault {reason}" in out, out


def logged_before_replay(folder: Path, into: Path) -> Path:
    """A copy of run ``folder`` in ``into`` as a run logged before replay existed: no tick record, nor its metadata."""
    old = into / folder.name
    shutil.copytree(folder, old)
    (old / "ticks.bin").unlink()
    metadata = json.loads((old / "metadata.json").read_text())
    for key in ("replay", "tick_columns"):
        metadata.pop(key)
    metadata["files"].pop("ticks")
    (old / "metadata.json").write_text(json.dumps(metadata))
    return old
