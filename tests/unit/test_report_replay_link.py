"""How ``harness report`` links a run to its replay (harness/report/replay_link.py), on hand-made run folders.

The run folders here are written by the recorder with made-up rows; what the link reads is the
metadata and whether ``ticks.bin`` and ``can.log`` are there. tests/integration/test_drive_from.py
checks it on a real dry run's folder and its replay.
"""

from __future__ import annotations

import json
from pathlib import Path

from harness.recording import RunFolder, canonical_columns, load_run
from harness.report.replay_link import replay_command, replay_links, replays_of

REPLAYABLE = {"replay": {"version": 1, "profile_controller": True}, "record_complete": True}


def _folder(parent: Path, name: str, kind: str = "dry-run", **metadata) -> Path:
    columns = canonical_columns(3)
    run = RunFolder.create(parent, "p", kind, {}, columns, with_can=False)
    run.start()
    for i in range(5):
        run.record_row([i * 0.002] + [0.0] * (len(columns) - 1))
    run.finish("completed")
    folder = run.path.rename(parent / name)
    data = json.loads((folder / "metadata.json").read_text())
    data.update(metadata)
    (folder / "metadata.json").write_text(json.dumps(data))
    return folder


def _replayable(parent: Path, name: str) -> Path:
    folder = _folder(parent, name, **REPLAYABLE)
    (folder / "ticks.bin").write_bytes(b"")
    (folder / "can.log").write_text("")
    data = json.loads((folder / "metadata.json").read_text())
    data["files"]["can"] = "can.log"
    (folder / "metadata.json").write_text(json.dumps(data))
    return folder


def test_a_replayable_run_gets_the_command_and_the_replays_beside_it(tmp_path):
    run = _replayable(tmp_path, "run one")
    replay = _folder(tmp_path / "whatif", "replay", replay_of=str(run.resolve()), what_if=["--set a=1"])
    _folder(tmp_path, "other_replay", replay_of=str(tmp_path / "another_run"))
    lines = replay_links([load_run(run)])
    assert lines[0] == "Replay:"
    assert f"    harness replay '{run}'" in lines  # quoted for the shell: the name has a space
    assert f"    replayed in {replay.resolve()}" in lines and len(lines) == 4
    assert replay_command(run) == f"harness replay '{run}'"


def test_a_replay_recorded_with_a_relative_path_is_found_by_the_run_folders_name(tmp_path):
    run = _replayable(tmp_path, "2026-01-01T00-00-00_p_dry-run")
    replay = _folder(tmp_path, "replay", replay_of=f"logs/{run.name}")
    assert replays_of(run) == [replay.resolve()]


def test_a_run_without_ticks_bin_cannot_be_replayed_and_the_report_says_why(tmp_path):
    old = _folder(tmp_path, "old", record_complete=True)
    (line,) = replay_links([load_run(old)])[1:]
    assert "replay is not possible: logged before replay existed" in line and "ticks.bin" in line


def test_a_replays_folder_is_named_as_the_replay_of_its_run_and_a_simulation_gets_no_line(tmp_path):
    replay = _folder(tmp_path, "replay", replay_of="/logs/run", what_if=[])
    simulation = _folder(tmp_path, "case", kind="simulation")
    lines = replay_links([load_run(replay), load_run(simulation)])
    assert lines == ["Replay:", f"  {load_run(replay).label}: an exact replay of /logs/run"]
    assert replay_links([load_run(simulation)]) == []
