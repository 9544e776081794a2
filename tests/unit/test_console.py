"""The loop status in shared memory and the live console drawn by a child process."""

from __future__ import annotations

import fcntl
import io
import json
import os
import select
import signal
import struct
import subprocess
import sys
import termios
import threading
import time
import tracemalloc
from pathlib import Path

import pytest
from rich.console import Console

import harness.console.live
from harness.console.live import LiveConsole, view_command, view_environment
from harness.loop.status import STATE_NAMES, LoopStatus
from harness.loop.status_block import truncate_utf8
from harness.safety.lifecycle import State

#: Generous: a cold child start on a loaded two-core VM can take seconds.
DEADLINE_S = 60.0


def _full_status() -> LoopStatus:
    status = LoopStatus(state="STOPPING", phase="tail", t_s=41.5, run_t_s=30.25, duration_s=30.0, stroke_m=-0.0421,
                        force_N=-2500.0, sliding_variable=0.0123, e2e_rejects=3, error_frames=2, send_failures=1,
                        stalls=5, gaps_past_budget=1, longest_stall_s=0.0072,
                        missed_periods=6, last_event="41.500 s  fault x: é ✓",
                        trip_reason="")
    for k in range(700):
        status.add_lateness(k * 1e-6)
    return status


def _wait_for(predicate, what: str) -> None:
    deadline = time.monotonic() + DEADLINE_S
    while not predicate():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.02)


def _process_gone(pid: int) -> bool:
    """True once ``pid`` has exited (a zombie nobody reaps counts as exited)."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii") as file:
            return file.read().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def test_state_codes_are_the_lifecycle_states():
    assert STATE_NAMES == tuple(state.name for state in State)
    assert all(STATE_NAMES[state.value] == state.name for state in State)


def test_keyword_construction_sets_fields_and_refuses_unknown_ones():
    with LoopStatus(state="TRIPPED", trip_reason="stroke_hard", run_t_s=12.0, missed_periods=2) as status:
        assert (status.state, status.trip_reason, status.run_t_s, status.missed_periods) == ("TRIPPED", "stroke_hard", 12.0, 2)
        assert isinstance(status.missed_periods, int) and status.phase == "starting" and status.last_event == ""
        status.state = State.RUNNING
        assert status.state == "RUNNING"
        with pytest.raises(ValueError, match="unknown run state"):
            status.state = "FLYING"
    with pytest.raises(TypeError, match="bogus"):
        LoopStatus(bogus=1)


def test_status_round_trips_through_a_second_process():
    with _full_status() as status:
        script = ("import json, sys; from harness.loop.status import LoopStatus; s = LoopStatus.attach(sys.argv[1]); "
                  "print(json.dumps({**s.as_dict(), 'percentiles': s.lateness_percentiles(), 'count': s.lateness_count}))")
        result = subprocess.run([sys.executable, "-c", script, status.path], capture_output=True, text=True,
                                env=view_environment(), timeout=DEADLINE_S, check=True)
        seen = json.loads(result.stdout)
        assert seen.pop("count") == 700
        assert seen.pop("percentiles") == pytest.approx(list(status.lateness_percentiles()))
        assert seen == status.as_dict()
        assert status.lateness_percentiles()[0] == pytest.approx(443.5e-6)  # the last 512 of 0..699 us


def test_a_reader_sees_every_change_and_cannot_write():
    with _full_status() as status:
        reader = LoopStatus.attach(status.path)
        status.last_event, status.force_N, status.finished = "next event", -1.0, True
        assert (reader.last_event, reader.force_N, reader.finished) == ("next event", -1.0, True)
        with pytest.raises(TypeError):
            reader.force_N = 3.0
        reader.close()


@pytest.mark.parametrize("text", ["é" * 200, "a" + "é" * 200, "€" * 100, "🙂" * 80, "plain " * 60])
def test_text_is_truncated_at_a_character_boundary(text):
    capacity = LoopStatus.last_event.capacity
    with LoopStatus() as status:
        status.last_event = text
        kept = status.last_event
        assert text.startswith(kept) and len(kept.encode()) <= capacity
        assert len(kept.encode()) > capacity - 4  # nothing more than the split character is dropped
        status.last_event = "short"
        assert status.last_event == "short"


def test_truncate_utf8_never_splits_a_character():
    encoded = "aé€🙂".encode()
    for capacity in range(len(encoded) + 2):
        kept = truncate_utf8(encoded, capacity)
        assert len(kept) <= capacity and encoded.startswith(kept)
        kept.decode("utf-8")  # strict: raises on a split character


def test_writing_fields_every_tick_allocates_nothing():
    event = "12.000 s  fault stroke_hard: stroke 95 mm"
    with LoopStatus() as status:

        def write(k: int, t: float) -> None:
            status.state = State.RUNNING
            status.t_s = t
            status.run_t_s = t
            status.stroke_m = t
            status.force_N = t
            status.stalls = k
            status.longest_stall_s = t
            status.missed_periods = k
            status.last_event = event
            status.trip_reason = ""
            status.add_lateness(t)

        for k in range(100):  # warm up
            write(k, 0.5)
        tracemalloc.start()
        try:
            before = tracemalloc.get_traced_memory()[0]
            for k in range(10_000):
                write(k, 0.5)
            growth = tracemalloc.get_traced_memory()[0] - before
        finally:
            tracemalloc.stop()
        assert growth < 1024, growth  # any allocation kept per write would be >= 10 000 x 24 bytes


def test_close_removes_the_block_and_keeps_the_values():
    status = _full_status()
    path = Path(status.path)
    assert path.exists()
    status.close()
    status.close()  # idempotent
    assert not path.exists() and status.closed and status.finished
    assert status.stroke_m == -0.0421 and status.last_event.endswith("✓")
    status.t_s = 1.0  # still writable, in private memory
    assert status.t_s == 1.0


def test_attach_refuses_a_file_that_is_not_a_status_block(tmp_path):
    short = tmp_path / "short.bin"
    short.write_bytes(b"x" * 10)
    with pytest.raises(ValueError, match="not a loop status block"):
        LoopStatus.attach(short)
    zeros = tmp_path / "zeros.bin"
    zeros.write_bytes(bytes(8192))
    with pytest.raises(ValueError, match="magic"):
        LoopStatus.attach(zeros)


def test_the_panel_shows_stalls_and_lateness_from_the_ring():
    with _full_status() as status:
        console = Console(record=True, width=140)
        console.print(LiveConsole(status, 0.08, 0.1, 10_000.0, "panel title", enabled=False))
        text = console.export_text()
    for expected in ("STOPPING", "panel title",
                     "6 missed periods in 5 stalls (ridden through 4, past the budget 1), longest 7.2 ms",
                     "p50   443.5 us", "-42.10 mm", "-2.500 kN", "fault x: é ✓"):
        assert expected in text, expected


def _read_until(stream, needles: tuple[bytes, ...]) -> bytes:
    """Read a pipe until every one of ``needles`` has appeared."""
    seen = b""
    deadline = time.monotonic() + DEADLINE_S
    while not all(needle in seen for needle in needles):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out; got {seen[-500:]!r}")
        ready, _, _ = select.select([stream], [], [], 0.5)
        if ready:
            chunk = os.read(stream.fileno(), 65536)
            if not chunk:
                raise AssertionError(f"the child closed its output; got {seen[-500:]!r}")
            seen += chunk
    return seen


def test_the_child_draws_frames_ignores_ctrl_c_and_exits_when_finished(tmp_path):
    timing = tmp_path / "timing.json"
    with LoopStatus(state="RUNNING", duration_s=30.0, run_t_s=1.0) as status:
        command = view_command(status.path, 0.08, 0.1, 10_000.0, "child title", parent_pid=os.getpid(), width=100,
                               color_system=None, force_terminal=True, timing_out=str(timing))
        child = subprocess.Popen(command, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, env=view_environment())
        try:
            _read_until(child.stdout, (b"child title", b"RUNNING"))
            child.send_signal(signal.SIGINT)  # Ctrl-C is the loop's: the child ignores it
            status.run_t_s = 2.0
            _read_until(child.stdout, (b"2.0 / 30.0 s",))
            assert child.poll() is None
            status.state, status.finished = "DONE", True
            rest, _ = child.communicate(timeout=DEADLINE_S)
        finally:
            if child.poll() is None:
                child.kill()
                child.wait()
        assert child.returncode == 0
        assert b"DONE" in rest
        assert Path(status.path).exists()  # the owner removes it, not the child
    report = json.loads(timing.read_text())
    assert report["renders"] >= 2 and report["render_cpu_max_s"] >= report["render_cpu_median_s"] > 0


def test_the_child_draws_a_last_frame_and_exits_when_its_parent_dies(tmp_path):
    output = tmp_path / "frames.txt"
    parent_script = (
        "import os, subprocess, sys\n"
        "from harness.console.live import view_command, view_environment\n"
        "from harness.loop.status import LoopStatus\n"
        "status = LoopStatus(state='ARMED')\n"
        "command = view_command(status.path, 0.08, 0.1, 1e4, 'orphan title', parent_pid=os.getpid(), width=100,"
        " force_terminal=False)\n"
        "child = subprocess.Popen(command, stdout=open(sys.argv[1], 'w'), stdin=subprocess.DEVNULL, env=view_environment())\n"
        "print(child.pid, status.path, flush=True)\n"
        "sys.stdin.readline()\n"
        "os._exit(0)  # dies without closing the status block\n"
    )
    parent = subprocess.Popen([sys.executable, "-c", parent_script, str(output)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True, env=view_environment())
    pid_text, block_path = parent.stdout.readline().split()
    child_pid = int(pid_text)
    try:
        time.sleep(0.5)
        parent.stdin.write("\n")
        parent.stdin.flush()
        parent.wait(timeout=DEADLINE_S)
        _wait_for(lambda: _process_gone(child_pid), "the orphaned child to exit")
    finally:
        if not _process_gone(child_pid):
            os.kill(child_pid, signal.SIGKILL)
    text = output.read_text()
    assert "orphan title" in text and "ARMED" in text
    assert not Path(block_path).exists()  # removed by the child, since its owner could not


def test_live_console_on_a_string_console_spawns_nothing_and_prints_the_final_panel(monkeypatch):
    def no_spawn(*args, **kwargs):
        raise AssertionError("spawned a process")

    monkeypatch.setattr(harness.console.live.subprocess, "Popen", no_spawn)
    output = io.StringIO()
    status = LoopStatus(state="RUNNING")
    with LiveConsole(status, 0.08, 0.1, 1e4, "quiet title", console=Console(file=output, width=120)) as live:
        assert live.child is None
        status.state = "DONE"
        assert output.getvalue() == ""  # nothing while the loop runs
    assert "quiet title" in output.getvalue() and "DONE" in output.getvalue()
    assert status.closed and not Path(status.path).exists()


def test_a_disabled_live_console_prints_nothing_and_closes_the_block():
    output = io.StringIO()
    status = LoopStatus()
    with LiveConsole(status, 0.08, 0.1, 1e4, "t", console=Console(file=output), enabled=False):
        pass
    assert output.getvalue() == "" and status.closed


class _Terminal:
    """A pseudo-terminal of 100 x 40 whose output is drained by a thread."""

    def __init__(self):
        self.master, self.slave = os.openpty()
        fcntl.ioctl(self.slave, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 100, 0, 0))
        self.file = os.fdopen(self.slave, "w", encoding="utf-8", closefd=False)
        self.output = bytearray()
        self._reader = threading.Thread(target=self._drain, daemon=True)
        self._reader.start()

    def _drain(self) -> None:
        while True:
            try:
                chunk = os.read(self.master, 65536)
            except OSError:  # EIO: every slave side is closed
                return
            if not chunk:
                return
            self.output += chunk

    def close(self) -> str:
        self.file.close()
        os.close(self.slave)
        self._reader.join(timeout=DEADLINE_S)
        os.close(self.master)
        return self.output.decode("utf-8", "replace")


def test_live_console_on_a_terminal_draws_from_a_child_process():
    terminal = _Terminal()
    status = LoopStatus(state="RUNNING", duration_s=10.0)
    threads = threading.active_count()
    try:
        with LiveConsole(status, 0.08, 0.1, 1e4, "terminal title", console=Console(file=terminal.file)) as live:
            assert live.child is not None and live.child.pid != os.getpid()
            assert threading.active_count() == threads  # no drawing thread in the loop's process
            child = live.child
            # Ctrl-C reaches the whole foreground group; the child ignores it, even while still starting
            child.send_signal(signal.SIGINT)
            _wait_for(lambda: b"terminal title" in terminal.output, "a frame on the terminal")
            assert child.poll() is None
            status.state = "DONE"
        assert child.returncode == 0 and live.child is None
    finally:
        text = terminal.close()
    assert "DONE" in text and status.closed


def test_live_console_says_so_in_one_line_when_the_child_cannot_start(monkeypatch):
    def cannot_start(*args, **kwargs):
        raise OSError("no processes left")

    monkeypatch.setattr(harness.console.live.subprocess, "Popen", cannot_start)
    terminal = _Terminal()
    status = LoopStatus(state="RUNNING")
    try:
        with LiveConsole(status, 0.08, 0.1, 1e4, "terminal title", console=Console(file=terminal.file)) as live:
            assert live.child is None
    finally:
        text = terminal.close()
    assert "live console unavailable (no processes left)" in text
    assert "terminal title" not in text  # never drawn in process
    assert status.closed
