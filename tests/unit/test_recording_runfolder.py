"""Recording a run folder: files, metadata lifecycle, rows/events/CAN round trips, drops, flushing."""

from __future__ import annotations

import errno
import json
import re
import threading
import time
from pathlib import Path

import can
import numpy as np
import pytest
import yaml

from harness.errors import HarnessError, SafetyError
from harness.recording import RunFolder, RunFolderError, canonical_columns, load_run

COLUMNS = ("t_s", "sliding_displacement_m", "force_command_N", "state", "interlock_flags")
PROFILE = {"name": "nceer_4dof", "structure": {"floor_masses_kg": [958.0, 958.0, 958.0]}, "loop": {"rate_Hz": 250.0}}


def _rows(n: int) -> np.ndarray:
    t = np.arange(n) * 0.004
    return np.column_stack([t, 0.03 * np.sin(2 * np.pi * t), 1234.5678 * np.cos(t), np.full(n, 2.0), np.arange(n) % 4])


def _wait_for(predicate, timeout_s: float = 10.0) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(0.01)
    return predicate()


@pytest.fixture
def folder(tmp_path: Path):
    run = RunFolder.create(tmp_path, "nceer_4dof", "dry-run", PROFILE, COLUMNS, metadata={"total_weight_N": 39855.0})
    yield run
    run.finish("error", trip_reason="test teardown")


def test_folder_is_named_by_start_time_profile_and_kind(folder: RunFolder, tmp_path: Path) -> None:
    assert folder.path.parent == tmp_path
    assert re.fullmatch(r"\d{4}-\d\d-\d\dT\d\d-\d\d-\d\d_nceer_4dof_dry-run", folder.path.name)
    assert sorted(p.name for p in folder.path.iterdir()) == [
        "can.log", "events.jsonl", "metadata.json", "profile.yaml", "signals.csv",
    ]


def test_two_runs_started_in_the_same_second_get_distinct_folders(tmp_path: Path) -> None:
    runs = [RunFolder.create(tmp_path, "p", "simulation", {}, ("t_s",)) for _ in range(3)]
    assert len({run.path for run in runs}) == 3
    for run in runs:
        run.finish("completed")


def test_profile_yaml_holds_the_resolved_profile(folder: RunFolder) -> None:
    assert yaml.safe_load((folder.path / "profile.yaml").read_text()) == PROFILE


def test_metadata_at_start_says_incomplete_and_names_the_software(folder: RunFolder) -> None:
    meta = json.loads((folder.path / "metadata.json").read_text())
    assert meta["outcome"] == "incomplete"
    assert meta["format_version"] == 1
    assert meta["kind"] == "dry-run" and meta["profile_name"] == "nceer_4dof"
    assert set(meta["packages"]) == {"shaketable-harness", "numpy", "scipy", "python-can", "cantools", "numba"}
    assert meta["packages"]["numpy"] == np.__version__
    assert meta["python"].count(".") == 2
    assert meta["host"]
    assert meta["total_weight_N"] == 39855.0
    assert meta["end_time"] is None


def test_rows_written_equal_rows_read_back(folder: RunFolder) -> None:
    rows = _rows(1000)
    rows[7, 2] = np.nan
    folder.start()
    for row in rows:
        assert folder.record_row(row)
    folder.record_row(tuple(float(v) for v in rows[-1]))
    folder.finish("completed")
    run = load_run(folder.path)
    assert run.n_rows == 1001
    assert run.columns == COLUMNS
    for i, name in enumerate(COLUMNS):
        np.testing.assert_allclose(run[name][:1000], rows[:, i], rtol=1e-11, atol=0, equal_nan=True)
    assert np.isnan(run["force_command_N"][7])
    assert run["interlock_flags"].tolist()[:8] == [0, 1, 2, 3, 0, 1, 2, 3]


def test_csv_header_is_one_line_of_unit_bearing_names_and_nan_is_spelled_for_matlab(folder: RunFolder) -> None:
    folder.start()
    folder.record_row((0.0, np.nan, np.inf, 1.0, 0.0))
    folder.finish("completed")
    lines = (folder.path / "signals.csv").read_text().splitlines()
    assert lines[0] == ",".join(COLUMNS)
    assert lines[1] == "0,NaN,Inf,1,0"


def test_events_round_trip_in_order(folder: RunFolder) -> None:
    folder.start()
    folder.record_event(0.0, "lifecycle", "armed")
    folder.record_event(0.5, "lifecycle", "started", {"record": "elcentro"})
    folder.record_event(2.25, "trip", "stroke_hard_limit", {"x_b_m": np.float64(0.051), "tick": np.int64(562)})
    folder.finish("tripped", trip_reason="stroke_hard_limit")
    events = load_run(folder.path).events
    assert [(e["t_s"], e["kind"], e["name"]) for e in events] == [
        (0.0, "lifecycle", "armed"),
        (0.5, "lifecycle", "started"),
        (2.25, "trip", "stroke_hard_limit"),
    ]
    assert events[1]["detail"] == {"record": "elcentro"}
    assert events[2]["detail"] == {"x_b_m": 0.051, "tick": 562}
    assert isinstance(events[0]["wall_time"], float)


def _traffic() -> list[can.Message]:
    frames = []
    for i in range(200):
        frames.append(
            can.Message(
                timestamp=1700000000.0 + i * 0.004,
                arbitration_id=0x100 + i % 5,
                data=bytes([(i * 7 + k) % 256 for k in range(1 + i % 8)]),
                is_extended_id=bool(i % 3 == 0),
                is_rx=bool(i % 2),
                channel="vcan0",
            )
        )
    return frames


def test_can_log_replays_through_log_reader_with_identical_frames(folder: RunFolder) -> None:
    sent = _traffic()
    folder.start()
    for msg in sent:
        assert folder.record_frame(msg)
    folder.finish("completed")
    run = load_run(folder.path)
    assert run.can_log is not None and run.can_log.suffix == ".log"
    with can.LogReader(run.can_log) as reader:
        replayed = list(reader)
    assert len(replayed) == len(sent)
    for original, back in zip(sent, replayed, strict=True):
        assert back.arbitration_id == original.arbitration_id
        assert back.data == original.data
        assert back.is_extended_id == original.is_extended_id
        assert back.is_rx == original.is_rx
        assert back.channel == original.channel
        assert back.timestamp == pytest.approx(original.timestamp, abs=1e-6)


def test_finish_rewrites_metadata_with_outcome_times_summary_and_counts(folder: RunFolder) -> None:
    folder.start()
    for row in _rows(10):
        folder.record_row(row)
    folder.finish("tripped", trip_reason="stroke_hard_limit", summary={"peak_stroke_m": 0.051})
    folder.finish("completed")  # second call is ignored
    meta = json.loads((folder.path / "metadata.json").read_text())
    assert meta["outcome"] == "tripped"
    assert meta["trip_reason"] == "stroke_hard_limit"
    assert meta["summary"] == {"peak_stroke_m": 0.051}
    assert meta["end_time"] >= meta["start_time"]
    assert meta["recorder"]["rows_written"] == 10
    assert meta["recorder"]["dropped"] == {"rows": 0, "frames": 0, "events": 0}
    assert not any(p.name.endswith(".tmp") for p in folder.path.iterdir())


def test_producer_never_blocks_when_the_queue_is_full_and_drops_are_reported(tmp_path: Path) -> None:
    run = RunFolder.create(tmp_path, "p", "dry-run", {}, ("t_s", "x_m"), row_capacity=16, frame_capacity=4)
    results: list[bool] = []

    def produce() -> None:  # the writer thread is not started: nothing drains
        results.extend(run.record_row((float(i), 0.0)) for i in range(100))
        results.extend(run.record_frame(can.Message(arbitration_id=1, data=b"\x00")) for _ in range(10))

    producer = threading.Thread(target=produce)
    producer.start()
    producer.join(timeout=30)
    assert not producer.is_alive(), "record_row blocked on a full queue"
    assert results.count(True) == 16 + 4
    assert run.drops() == {"rows": 84, "frames": 6, "events": 0}
    run.finish("completed")
    data = load_run(run.path)
    assert data.n_rows == 16
    assert data.metadata["recorder"]["dropped"] == {"rows": 84, "frames": 6, "events": 0}
    drop_events = [e for e in data.events if e["name"] == "recorder_dropped"]
    assert drop_events and drop_events[-1]["detail"]["total"]["rows"] == 84


def test_rows_reach_the_file_without_finish(tmp_path: Path) -> None:
    run = RunFolder.create(tmp_path, "p", "dry-run", {}, ("t_s", "x_m"), flush_interval_s=0.05)
    run.start()
    for i in range(50):
        run.record_row((i * 0.001, float(i)))
    signals = run.path / "signals.csv"
    assert _wait_for(lambda: len(signals.read_text().splitlines()) == 51), "rows were not flushed within 10 s"
    data = load_run(run.path)
    assert data.incomplete and data.n_rows == 50
    run.finish("completed")


def test_flush_interval_above_100_ms_is_refused(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="flush_interval_s"):
        RunFolder.create(tmp_path, "p", "dry-run", {}, ("t_s",), flush_interval_s=0.5)


def test_context_manager_records_completed_and_error(tmp_path: Path) -> None:
    with RunFolder.create(tmp_path / "a", "p", "run", {}, ("t_s",)) as ok:
        ok.record_row((0.0,))
    with pytest.raises(RuntimeError), RunFolder.create(tmp_path / "b", "p", "run", {}, ("t_s",)) as bad:
        raise RuntimeError("drive fault")
    with pytest.raises(SafetyError), RunFolder.create(tmp_path / "c", "p", "run", {}, ("t_s",)) as refused:
        raise SafetyError("arm refused: stroke_hard_limit")
    assert load_run(ok.path).outcome == "completed"
    assert load_run(bad.path).metadata["trip_reason"] == "RuntimeError: drive fault"
    assert load_run(bad.path).outcome == "error"
    assert load_run(refused.path).metadata["trip_reason"] == "SafetyError: arm refused: stroke_hard_limit"
    assert load_run(refused.path).outcome == "error"  # a trip is finished by the session, not raised


def test_simulation_kind_has_no_can_log(tmp_path: Path) -> None:
    run = RunFolder.create(tmp_path, "p", "simulation", {}, canonical_columns(2))
    run.start()
    run.finish("completed")
    data = load_run(run.path)
    assert data.can_log is None and not (run.path / "can.log").exists()
    assert data.n_stories == 2


@pytest.mark.parametrize(
    ("kind", "columns", "metadata", "message"),
    [
        ("practice", ("t_s",), {}, "expected one of dry-run, run, simulation"),
        ("run", ("time",), {}, "expected 't_s'"),
        ("run", ("t_s", "x m"), {}, "MATLAB identifier"),
        ("run", ("t_s", "x_m", "x_m"), {}, "twice"),
        ("run", ("t_s",), {"outcome": "completed"}, "reserved metadata keys"),
    ],
)
def test_bad_requests_raise_run_folder_error(tmp_path: Path, kind: str, columns: tuple, metadata: dict, message: str) -> None:
    with pytest.raises(RunFolderError, match=message) as info:
        RunFolder.create(tmp_path, "p", kind, {}, columns, metadata=metadata)
    assert isinstance(info.value, HarnessError) and isinstance(info.value, ValueError)


def test_unknown_outcome_is_refused(folder: RunFolder) -> None:
    with pytest.raises(RunFolderError, match="expected one of completed, stopped, tripped, refused, error, incomplete"):
        folder.finish("aborted")


def test_a_failing_disk_stops_the_writer_not_the_tick(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import harness.recording.writer as writer_module

    def disk_full(line: str, block: np.ndarray) -> str:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(writer_module, "format_rows", disk_full)
    run = RunFolder.create(tmp_path, "p", "dry-run", {}, ("t_s",), row_capacity=8)
    run.start()
    run.record_row((0.0,))
    assert _wait_for(lambda: run.writer_error is not None)
    accepted = [run.record_row((float(i),)) for i in range(20)]
    assert accepted.count(True) == 8 and run.drops()["rows"] == 12
    run.finish("completed")
    meta = load_run(run.path).metadata
    assert "No space left on device" in meta["recorder"]["error"]
    assert meta["recorder"]["dropped"]["rows"] == 12


def test_can_player_replays_the_log(folder: RunFolder) -> None:
    import subprocess
    import sys

    folder.start()
    for msg in _traffic()[:20]:
        folder.record_frame(msg)
    folder.finish("completed")
    done = subprocess.run(
        [
            sys.executable, "-m", "can.player", "-i", "virtual", "-c", "replay-test", "--ignore-timestamps",
            str(folder.path / "can.log"),
        ],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr


def test_interrupt_flushes_the_data_but_leaves_the_run_incomplete(tmp_path: Path) -> None:
    with pytest.raises(KeyboardInterrupt), RunFolder.create(tmp_path, "p", "run", {}, ("t_s",)) as run:
        run.record_row((0.5,))
        raise KeyboardInterrupt
    data = load_run(run.path)
    assert data.incomplete and data.metadata["trip_reason"] == "KeyboardInterrupt"
    assert data["t_s"].tolist() == [0.5]


def test_git_commit_is_a_hash_or_absent(folder: RunFolder) -> None:
    commit = json.loads((folder.path / "metadata.json").read_text())["git_commit"]
    assert commit is None or re.fullmatch(r"[0-9a-f]{40}", commit)


class _FileTooLarge:
    """Stands in for ``signals.csv``: takes ``limit`` rows, then fails as a file-size limit does (EFBIG)."""

    def __init__(self, real, limit: int):
        self.real, self.limit, self.rows = real, limit, 0

    def write(self, text: str) -> int:
        self.rows += text.count("\n")
        if self.rows > self.limit:
            raise OSError(errno.EFBIG, "File too large")
        return self.real.write(text)

    def __getattr__(self, name: str):
        return getattr(self.real, name)


def test_a_file_size_limit_is_counted_as_lost_rows_frames_and_events(tmp_path: Path) -> None:
    """Rows the queue accepted but the writer could not write count as lost, as well as queue drops."""
    run = RunFolder.create(tmp_path, "p", "dry-run", {}, ("t_s", "x_m"), row_capacity=64)
    run._writer._signals = _FileTooLarge(run._writer._signals, limit=32)
    run.start()
    for i in range(32):
        run.record_row((i * 0.002, 0.0))
    assert _wait_for(lambda: run.rows_written == 32)
    run.record_event(0.1, "lifecycle", "armed")
    assert _wait_for(lambda: run._writer.events_written == 1)
    for i in range(32, 52):  # the next drain writes past the limit
        run.record_row((i * 0.002, 0.0))
    assert _wait_for(lambda: run.writer_error is not None)
    for i in range(52, 132):  # the tick carries on: the ring fills up, then drops
        run.record_row((i * 0.002, 0.0))
    for _ in range(3):
        run.record_frame(can.Message(arbitration_id=0x10, data=b"\x01"))
    run.record_event(0.3, "lifecycle", "done")
    run.record_event(0.3, "lifecycle", "disabled")
    run.finish("completed")

    meta = json.loads((run.path / "metadata.json").read_text())
    assert meta["outcome"] == "completed" and meta["record_complete"] is False
    recorder = meta["recorder"]
    assert recorder["rows_written"] == 32
    assert recorder["lost"] == {"rows": 100, "frames": 3, "events": 2}  # 132 handed over, 32 confirmed
    assert recorder["dropped"]["rows"] > 0  # part of the 100: the ring filled once the writer stopped
    assert "File too large" in recorder["error"]
    assert not run.record_complete
    assert run.record_problem().startswith("lost 100 of 132 rows, 3 frames, 2 events (OSError: [Errno 27] File too large")
    data = load_run(run.path)
    assert data.n_rows >= 32 and data["t_s"][:32].tolist() == pytest.approx([i * 0.002 for i in range(32)])
    assert any("the record is incomplete: 100 rows, 3 frames, 2 events lost" in note for note in data.warnings)
    failed = [e for e in data.events if e["name"] == "recorder_failed"]
    assert failed and failed[0]["kind"] == "fault" and "File too large" in failed[0]["detail"]["error"]


def test_a_whole_record_is_marked_complete(folder: RunFolder) -> None:
    folder.start()
    for row in _rows(10):
        folder.record_row(row)
    folder.record_frame(can.Message(arbitration_id=0x10, data=b"\x01"))
    folder.finish("completed")
    meta = json.loads((folder.path / "metadata.json").read_text())
    assert meta["record_complete"] is True
    assert meta["recorder"]["lost"] == {"rows": 0, "frames": 0, "events": 0}
    assert folder.record_complete and folder.record_problem() == ""


def test_metadata_that_cannot_be_rewritten_leaves_the_run_incomplete_not_a_crash(
    folder: RunFolder, monkeypatch: pytest.MonkeyPatch
) -> None:
    import harness.recording.runfolder as runfolder_module

    def disk_full(path: Path, data: dict) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    folder.start()
    monkeypatch.setattr(runfolder_module, "write_json_atomic", disk_full)
    monkeypatch.setattr(runfolder_module, "write_json_in_place", lambda path, data: False)  # not even in place
    folder.finish("completed")
    assert not folder.record_complete
    assert "metadata.json not rewritten" in folder.record_problem()
    assert "it still says incomplete" in folder.record_problem()
    assert load_run(folder.path).incomplete  # the file keeps the outcome written at the start, whole
