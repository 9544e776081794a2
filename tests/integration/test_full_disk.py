"""A full disk ends a run safely, says so, and exits 3; a disk without room refuses the run before it starts.

The review (issue 30, item 4): ``harness dry-run --lockstep --duration 20 --quiet`` on a 2 MB tmpfs
recorded ``recorder_failed`` at 7.7 s, ran about 8 s more, and ended in a traceback (exit 1,
``OSError: [Errno 28]`` in ``write_target_motion``) with metadata.json still ``incomplete``; with the
disk already full, a traceback from ``write_profile`` after the rig process had started.

The full disk is made three ways: a small tmpfs (as root, where ``mount`` works; skipped with the
reason elsewhere), a tmpfs filled by another writer while the run goes on, and writes made to
raise ``OSError(ENOSPC)`` at chosen points.
"""

from __future__ import annotations

import errno
import json
import subprocess
import sys
import time
from pathlib import Path

import can
import pytest

from harness import exit_codes
from harness.cli import main
from harness.recording.writer import RunWriter
from tests.conftest import REPO

DISK_FULL = OSError(errno.ENOSPC, "No space left on device")


def _outcome(out: str) -> str:
    return " ".join(out.split())  # rich wraps long lines


@pytest.fixture
def tmpfs(tmp_path: Path):
    """A factory of small tmpfs mounts under ``tmp_path`` (unmounted afterwards); skips where mounting is not allowed."""
    mounted: list[Path] = []

    def mount(size: str) -> Path:
        point = tmp_path / f"tmpfs{len(mounted)}"
        point.mkdir()
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(point)],
                              capture_output=True, text=True)
        if done.returncode != 0:
            pytest.skip(f"cannot mount a tmpfs here (needs root and mount rights): {done.stderr.strip()}")
        mounted.append(point)
        return point

    yield mount
    for point in mounted:
        subprocess.run(["umount", "-l", str(point)], check=False)


def _dry_run_process(log_dir: Path, duration_s: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "dry-run", "--lockstep", "--duration", duration_s, "--quiet",
         "--log-dir", str(log_dir)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
    )


def _fill(path: Path) -> None:
    """Write zeros into ``path`` until its file system is full (ENOSPC).

    Unbuffered: a buffered file keeps the bytes the full disk refused and raises ENOSPC again when
    it is closed (CI saw exactly that, reported at the ``with open`` line).
    """
    with open(path, "wb", buffering=0) as filler:
        try:
            while True:
                filler.write(b"\0" * 65536)
        except OSError as error:
            if error.errno != errno.ENOSPC:
                raise


def test_the_reviews_2_mb_disk_is_refused_before_the_rig_starts_with_the_estimate(tmpfs) -> None:
    log_dir = tmpfs("2m")
    process = _dry_run_process(log_dir, "20")
    out, err = process.communicate(timeout=120)
    text = _outcome(out + err)
    assert process.returncode == exit_codes.INPUT_ERROR, text
    assert "Traceback" not in text
    assert "MB free, expected room for this run's record, about" in text and "kB/s" in text, text
    assert list(log_dir.iterdir()) == [], "nothing written: refused before the run folder, the bus and the rig"


def test_a_disk_already_full_is_refused_before_the_rig_starts(tmpfs, monkeypatch, capsys) -> None:
    log_dir = tmpfs("2m")
    _fill(log_dir / "filler")
    import harness.runs.dry_run as dry_run

    started = []
    monkeypatch.setattr(dry_run, "_rig_process", lambda *args: started.append(args))
    status = main(["dry-run", "--lockstep", "--duration", "2", "--quiet", "--log-dir", str(log_dir)])
    captured = capsys.readouterr()
    assert status == exit_codes.INPUT_ERROR, captured.out + captured.err
    assert "MB free" in _outcome(captured.err)
    assert started == [], "the rig process was never started"


@pytest.mark.slow
def test_a_disk_filling_mid_run_stops_the_run_safely_marks_it_and_exits_3(tmpfs) -> None:
    log_dir = tmpfs("16m")
    process = _dry_run_process(log_dir, "8")
    deadline = time.monotonic() + 120
    while not list(log_dir.glob("*/signals.csv")) and process.poll() is None and time.monotonic() < deadline:
        time.sleep(0.02)
    (folder,) = [p for p in log_dir.iterdir() if p.is_dir()]
    while (folder / "signals.csv").stat().st_size < 300_000 and process.poll() is None:  # well into the run
        time.sleep(0.02)
    _fill(log_dir / "filler")  # another writer fills the disk
    out, err = process.communicate(timeout=300)
    text = _outcome(out + err)
    assert "Traceback" not in text
    assert process.returncode == exit_codes.TRIPPED, text
    assert "outcome: stopped (record_lost), record lost: lost" in text and "No space left on device" in text
    meta = json.loads((folder / "metadata.json").read_text())  # marked, in place: there was no room for a new file
    assert meta["outcome"] == "stopped" and meta["trip_reason"] == "record_lost" and meta["record_complete"] is False
    recorder = meta["recorder"]
    ticks = recorder["rows_written"] + recorder["lost"]["rows"]
    assert ticks < 500 * 8, "stopped before the end of the record"
    events = [json.loads(line) for line in (folder / "events.jsonl").read_text().splitlines() if line.strip()]
    assert any(event["name"] == "recorder_failed" for event in events)


def _fail_writes_after(monkeypatch, rows: int) -> None:
    """The recorder's writes raise ENOSPC once ``rows`` rows are written (the disk filled then)."""
    real = RunWriter.drain

    def drain(self: RunWriter) -> None:
        if self.rows_written >= rows:
            raise DISK_FULL
        real(self)

    monkeypatch.setattr(RunWriter, "drain", drain)


def test_a_lost_record_stops_safely_and_the_final_zero_command_reaches_the_bus(tmp_path, monkeypatch, capsys) -> None:
    from drivers.protocol.codec import load_protocol

    protocol = load_protocol()
    command_id = protocol.messages["ACTUATOR_CMD"].frame_id
    _fail_writes_after(monkeypatch, 800)
    channel = f"full-disk-{id(tmp_path)}"
    listener = can.Bus(interface="virtual", channel=channel)
    try:
        status = main(["dry-run", "--lockstep", "--duration", "20", "--quiet", "--interface", "virtual",
                       "--channel", channel, "--log-dir", str(tmp_path)])
        out = _outcome(capsys.readouterr().out)
        commands = []
        while (message := listener.recv(0.0)) is not None:
            if message.arbitration_id == command_id:
                commands.append(message)
    finally:
        listener.shutdown()
    assert status == exit_codes.TRIPPED, out
    assert "outcome: stopped (record_lost), record lost" in out
    database = protocol.database
    last = database.decode_message(commands[-1].arbitration_id, commands[-1].data)
    assert last["enable"] == 0 and last["force"] == 0, "the last command on the bus: drive off, zero force"
    enabled = [k for k, m in enumerate(commands) if database.decode_message(m.arbitration_id, m.data)["enable"]]
    assert enabled, "the run armed before the disk filled"
    assert len(commands) - enabled[-1] < 500 * 3, "the run stopped within a few seconds of the loss, not 20 s later"
    (folder,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    meta = json.loads((folder / "metadata.json").read_text())
    assert meta["outcome"] == "stopped" and meta["trip_reason"] == "record_lost"


def test_a_disk_error_after_the_loop_is_a_lost_record_not_a_traceback(tmp_path, monkeypatch, capsys) -> None:
    import harness.runs.run_context as run_context

    def full(*args, **kwargs):
        raise DISK_FULL

    monkeypatch.setattr(run_context, "write_target_motion", full)
    status = main(["dry-run", "--lockstep", "--duration", "1", "--quiet", "--log-dir", str(tmp_path)])
    out = _outcome(capsys.readouterr().out)
    assert status == exit_codes.TRIPPED, out
    assert "outcome: completed, record lost: target_motion.csv and the simulated references not written" in out
    assert "No space left on device" in out


def test_the_final_metadata_marks_the_outcome_in_place_when_no_new_file_fits(tmp_path, monkeypatch) -> None:
    import harness.recording.runfolder as runfolder
    from harness.recording import RunFolder

    folder = RunFolder.create(tmp_path, "p", "dry-run", {"a": 1}, ["t_s", "x"]).start()
    folder.record_row([0.0, 1.0])

    def full(*args, **kwargs):
        raise DISK_FULL

    monkeypatch.setattr(runfolder, "write_json_atomic", full)
    folder.finish("stopped", trip_reason="record_lost", summary={"big": "x" * 20_000})  # too big for the file's blocks
    meta = json.loads((folder.path / "metadata.json").read_text())
    assert meta["outcome"] == "stopped" and meta["trip_reason"] == "record_lost"
    assert "summary" not in meta, "the slim version: the outcome without the summary"
    assert "outcome written in place, without the summary" in folder.record_problem()


def test_the_size_estimate_bounds_a_real_run_folder_without_being_absurd(tmp_path, capsys) -> None:
    """The refusal's estimate (harness/recording/space.py) holds a real run's folder, within a factor of four."""
    from harness.profile import load_profile
    from harness.runs.dry_run import private_bus
    from harness.runs.options import prepare_motion
    from harness.runs.session import SessionSettings, expected_run_size

    assert main(["dry-run", "--lockstep", "--duration", "3", "--quiet", "--log-dir", str(tmp_path)]) == exit_codes.OK
    capsys.readouterr()
    (folder,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    written = sum(path.stat().st_size for path in folder.iterdir())
    profile = load_profile(REPO / "profiles" / "nceer_4dof.yaml")
    motion = prepare_motion(profile)  # the default record: --duration 3 cuts it to 3 s
    settings = SessionSettings(kind="dry-run", can=private_bus(profile.can_settings(None, None), False), duration_s=3.0,
                               log_dir=tmp_path, lockstep=True, table_record=motion)
    needed = expected_run_size(profile, settings).needed_bytes
    assert written <= needed < 4 * written + (2 << 20), (written, needed)
