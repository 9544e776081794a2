"""``harness replay``: every kind of dry-run outcome replays bit for bit from its own log (issue 34).

Completed, stopped by the operator, and a real-time run that rode through a stall: each replays
with every frame it sent identical (force, enable, counter, CRC) and the recorded outcome. A what-if
with a tighter stroke bound reports the earlier trip it would have caused; a run logged before
replay existed is refused; a run whose log was altered is not replayed as identical. Every injected
fault's tripped run replays in tests/integration/test_fault_injection.py, which makes those runs.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
import threading
from pathlib import Path

import numpy as np
import pytest

from harness import exit_codes
from harness.cli import main
from harness.loop.tick_log import MISSED, STALL, TICK_COLUMNS
from harness.recording import load_run
from tests.replay_checks import assert_identical, ending, logged_before_replay, replay, tick_records


def _dry_run(log_dir: Path, *args: str) -> tuple[int, Path]:
    status = main(["dry-run", "--log-dir", str(log_dir), "--quiet", *args])
    (folder,) = [p for p in log_dir.iterdir() if p.is_dir()]
    return status, folder


@pytest.fixture(scope="module")
def completed(tmp_path_factory) -> Path:
    status, folder = _dry_run(tmp_path_factory.mktemp("completed"), "--lockstep", "--duration", "2")
    assert status == exit_codes.OK
    return folder


def test_a_completed_lockstep_dry_run_replays_bit_for_bit(completed, capsys):
    out = assert_identical(capsys, completed)
    assert "recorded outcome: completed" in out and "replayed outcome: completed" in out


def _interrupt_once_running(log_dir: Path, after_s: float) -> threading.Thread:
    """SIGINT to this process ``after_s`` after the run's RUNNING event (the loop stops safely)."""
    def fire() -> None:
        for _ in range(2400):
            if any('"RUNNING"' in events.read_text() for events in log_dir.glob("*/events.jsonl")):
                break
            threading.Event().wait(0.05)
        threading.Event().wait(after_s)
        os.kill(os.getpid(), signal.SIGINT)

    thread = threading.Thread(target=fire, daemon=True)
    thread.start()
    return thread


def test_an_operator_stop_replays_bit_for_bit(tmp_path, capsys):
    _interrupt_once_running(tmp_path, 0.3)
    status, folder = _dry_run(tmp_path, "--lockstep", "--duration", "20")
    assert status == exit_codes.STOPPED
    assert tick_records(folder)[:, TICK_COLUMNS.index("operator_stop")].any()  # the request is in the record
    out = assert_identical(capsys, folder)
    assert "recorded outcome: stopped" in out and "replayed outcome: stopped" in out


def test_a_real_time_dry_run_that_rides_through_a_stall_replays_bit_for_bit(tmp_path, capsys, monkeypatch):
    """Real time (not lockstep): the loop's own clock gave each tick its t and lateness; one tick is held
    6 ms (three periods at 500 Hz, within the 20 ms stall budget) so that a stall is ridden through."""
    import time

    from harness.loop.runner import ControlLoop

    update_status = ControlLoop._update_status
    calls = [0]

    def held_once(self, *args, **kwargs):
        calls[0] += 1
        if calls[0] == 400:
            time.sleep(0.006)
        return update_status(self, *args, **kwargs)

    monkeypatch.setattr(ControlLoop, "_update_status", held_once)
    status, folder = _dry_run(tmp_path, "--duration", "2")
    monkeypatch.undo()
    if status == exit_codes.INPUT_ERROR and json.loads((folder / "metadata.json").read_text())["outcome"] == "refused":
        pytest.skip("the pre-flight check found this host unable to hold 500 Hz now (loaded): no real-time run to replay")
    ticks = tick_records(folder)
    assert (ticks[:, MISSED] >= 1).any() and (ticks[1:, STALL] > 0).all()  # real time: stalls measured, one ridden through
    out = assert_identical(capsys, folder)
    outcome, reason, _ = ending(folder)
    assert f"recorded outcome: {outcome}" in out and f"replayed outcome: {outcome}" in out


def test_a_tighter_stroke_bound_reports_the_earlier_trip_it_would_have_caused(completed, capsys, tmp_path):
    hard_m, stop_time_s = 0.012, 0.05
    status, out = replay(capsys, completed, "--set", "safety.stroke.soft_limit_m=0.008", "--set",
                          "safety.stroke.fade_band_m=0.002", "--set", f"safety.stroke.hard_limit_m={hard_m}",
                          "--set", f"safety.stroke.stop_time_s={stop_time_s}", "--out", str(tmp_path / "whatif"))
    assert status == exit_codes.OK, out
    assert "OPEN LOOP" in out and "the rig did not answer the changed commands" in out
    trip = re.search(r"what-if outcome: tripped \((stroke_\w+)\) at t = ([0-9.]+) s", out)
    assert trip is not None, out
    # open loop: the what-if sees the run's measurements, so it trips at the first tick whose recorded stroke or
    # predicted stroke reaches the tighter bound (the run itself went on to complete)
    run = load_run(completed)
    x, v, t = run["sliding_displacement_m"], run["sliding_velocity_m_s"], run["t_s"]
    running = run["state"] > 0
    reach = np.flatnonzero(running & ((np.abs(x) >= hard_m) | (np.abs(x + v * stop_time_s) >= hard_m)))
    assert len(reach), "the run's stroke never reached the tighter bound: the test needs a larger stroke"
    assert float(trip.group(2)) == pytest.approx(t[reach[0]], abs=0.0021)
    assert float(trip.group(2)) < t[-1]
    assert "recorded outcome: completed" in out
    assert f"would have tripped on {trip.group(1)} at t = {trip.group(2)} s, where the run did not" in out
    first = re.search(r"commands first differ at tick (\d+) \(t = ([0-9.]+) s\)", out)
    assert first is not None and float(first.group(2)) <= float(trip.group(2)), out
    # --out: the replayed ticks as a run folder that harness report reads beside the run
    (written,) = (tmp_path / "whatif").iterdir()
    replayed = load_run(written)
    ticks = int(re.search(r"replayed (\d+) ticks", out).group(1))
    assert len(replayed["t_s"]) == ticks and replayed.metadata["open_loop"] is True
    assert replayed.metadata["outcome"] == "tripped" and replayed.metadata["trip_reason"] == trip.group(1)
    np.testing.assert_array_equal(replayed["t_s"], t[:ticks])


def test_a_run_logged_before_replay_existed_is_refused(completed, tmp_path, capsys):
    old = logged_before_replay(completed, tmp_path)
    status, out = replay(capsys, old)
    assert status == exit_codes.INPUT_ERROR
    assert "logged before replay existed" in out


def test_a_run_whose_sent_frame_was_altered_is_not_replayed_as_identical(completed, tmp_path, capsys):
    """The comparison can fail: one force byte of one sent ACTUATOR_CMD in can.log changed, replay names that tick."""
    altered = tmp_path / completed.name
    shutil.copytree(completed, altered)
    lines = (altered / "can.log").read_text().splitlines(keepends=True)
    ticks = tick_records(altered)
    k = len(ticks) // 2
    start, end = int(ticks[k - 1, -1]), int(ticks[k, -1])
    at = next(i for i in range(start, end) if " 020#" in lines[i] and lines[i].rstrip().endswith("T"))
    head, data = lines[at].rsplit("#", 1)
    hex_data, direction = data.split()
    flipped = f"{int(hex_data[-2:], 16) ^ 0x01:02X}"
    lines[at] = f"{head}#{hex_data[:-2]}{flipped} {direction}\n"
    (altered / "can.log").write_text("".join(lines))
    status, out = replay(capsys, altered)
    assert status == exit_codes.INTERNAL_ERROR, out
    assert f"first differing tick: {k} " in out
    assert "run sent:    ACTUATOR_CMD" in out and "replay sent: ACTUATOR_CMD" in out
