"""``harness dry-run`` end to end on the in-process virtual bus (lockstep: deterministic, no timing)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import can
import numpy as np
import pytest

from harness import exit_codes
from harness.cli import main
from harness.recording import load_run
from harness.safety.lifecycle import State

LOCKSTEP = ["--lockstep", "--quiet"]


def _dry_run(tmp_path: Path, *args: str) -> tuple[int, Path]:
    status = main(["dry-run", "--log-dir", str(tmp_path), *LOCKSTEP, *args])
    folders = sorted(p for p in tmp_path.iterdir() if p.is_dir())
    return status, folders[-1] if folders else tmp_path


def _states(run) -> np.ndarray:
    return run["state"].astype(int)


def test_dry_run_writes_a_complete_run_folder(tmp_path, capsys):
    status, folder = _dry_run(tmp_path, "--duration", "2")
    out = capsys.readouterr().out
    assert status == exit_codes.OK
    (line,) = out.strip().splitlines()  # --quiet: the outcome line only, not the tables nor the timing
    assert line.startswith("outcome: completed") and str(folder) in line
    for name in ("profile.yaml", "metadata.json", "signals.csv", "can.log", "events.jsonl"):
        assert (folder / name).is_file(), name


def test_the_peak_profile_plot_draws_the_dry_runs_simulated_passive_reference(tmp_path, monkeypatch, capsys):
    from harness.report import plots_response
    from harness.report.plot_common import PlotOptions

    status, folder = _dry_run(tmp_path, "--duration", "1")
    capsys.readouterr()
    assert status == exit_codes.OK
    drawn: dict[str, list] = {}
    real_save = plots_response.save

    def save(fig, name, title, out_dir):
        for ax in fig.axes:
            for line in ax.get_lines():
                drawn.setdefault(line.get_label(), []).append(tuple(line.get_xdata()))
        return real_save(fig, name, title, out_dir)

    monkeypatch.setattr(plots_response, "save", save)
    run = load_run(folder)
    assert plots_response.peak_profile_plot([run], tmp_path, PlotOptions()) is not None
    reference = json.loads((folder / "metadata.json").read_text())["reference"]["passive_peaks"]
    drifts_mm, accelerations = drawn[f"passive (sim.): {run.label}"]
    assert drifts_mm == pytest.approx([1e3 * d for d in reference["drift_m"]])
    assert accelerations == pytest.approx([reference["base_acceleration_m_s2"], *reference["floor_acceleration_m_s2"]])
    assert run.label in drawn  # beside the run itself
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["outcome"] == "completed" and metadata["kind"] == "dry-run"
    assert metadata["summary"]["bus"]["frames_received"] > 1000
    run = load_run(folder)
    states = _states(run)
    assert {int(State.ARMED), int(State.RUNNING), int(State.STOPPING), int(State.DONE)} <= set(states)
    running = states == int(State.RUNNING)
    assert running.sum() >= 2.0 * 500  # the whole record at 500 Hz
    assert np.abs(run["force_command_N"][running]).max() > 100.0  # the controller acted
    assert run["drive_enabled"][-1] == 0 and run["force_command_N"][-1] == 0
    names = [event["name"] for event in run.events]
    assert names.index("ARMED") < names.index("RUNNING") < names.index("DONE")


def test_can_log_holds_both_sides_and_replays(tmp_path, capsys):
    status, folder = _dry_run(tmp_path, "--duration", "1")
    capsys.readouterr()
    assert status == exit_codes.OK
    frames = list(can.LogReader(str(folder / "can.log")))
    sent = {m.arbitration_id for m in frames if not m.is_rx}
    received = {m.arbitration_id for m in frames if m.is_rx}
    assert {0x20, 0x50, 0x300} <= sent  # actuator command, heartbeat, rig control
    assert {0x30, 0x31, 0x40, 0x301} <= received  # table, base, actuator status, rig status
    replay = subprocess.run(
        [sys.executable, "-m", "can.player", "-i", "virtual", "-c", "replay", "--ignore-timestamps", str(folder / "can.log")],
        capture_output=True, text=True, timeout=120,
    )
    assert replay.returncode == 0, replay.stderr


def test_stroke_trip_zeroes_force_and_disables_the_drive_in_the_same_tick(tmp_path, capsys):
    limits = ["--set", "safety.stroke.soft_limit_m=0.006", "--set", "safety.stroke.fade_band_m=0.002",
              "--set", "safety.stroke.hard_limit_m=0.01", "--set", "safety.stroke.arm_tolerance_m=0.003"]
    # The force-source rig: its stroke follows the table (the servo-hydraulic one drags the base mat along).
    status, folder = _dry_run(tmp_path, "--duration", "6", "--variant", "force_source", *limits)
    out = capsys.readouterr().out
    assert status == exit_codes.TRIPPED
    assert "tripped" in out
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["outcome"] == "tripped"
    assert metadata["trip_reason"] in ("stroke_hard", "stroke_predictive")
    run = load_run(folder)
    states = _states(run)
    first_trip = int(np.argmax(states == int(State.TRIPPED)))
    assert states[first_trip - 1] == int(State.RUNNING)
    assert run["force_command_N"][first_trip] == 0.0
    assert run["drive_enabled"][first_trip] == 0.0
    assert np.all(run["force_command_N"][first_trip:] == 0.0) and np.all(run["drive_enabled"][first_trip:] == 0.0)
    assert any(e["kind"] == "fault" and e["name"] == metadata["trip_reason"] for e in run.events)


def _signal_later(delays_s, signum=signal.SIGINT, log_dir: Path | None = None):
    """Send ``signum`` to this process after each delay; the first delay counts from RUNNING when ``log_dir`` is given.

    The rig starts in its own process first, so the loop's RUNNING phase begins a
    machine-dependent time after the command: wait for it in the run's events.
    """
    def running() -> bool:
        return any('"RUNNING"' in events.read_text() for events in log_dir.glob("*/events.jsonl"))

    def fire():
        if log_dir is not None:
            for _ in range(1200):
                if running():
                    break
                threading.Event().wait(0.05)
        for delay in delays_s:
            threading.Event().wait(delay)
            os.kill(os.getpid(), signum)

    thread = threading.Thread(target=fire, daemon=True)
    thread.start()
    return thread


def test_ctrl_c_stops_safely(tmp_path, capsys):
    _signal_later([0.5], log_dir=tmp_path)
    status, folder = _dry_run(tmp_path, "--duration", "20")
    capsys.readouterr()
    assert status == exit_codes.STOPPED
    run = load_run(folder)
    states = _states(run)
    assert int(State.STOPPING) in states and states[-1] == int(State.DONE)
    assert int(State.TRIPPED) not in states
    stopping = np.flatnonzero(states == int(State.STOPPING))
    force = np.abs(run["force_command_N"][stopping])
    assert force[-1] <= force[: len(force) // 4].max()  # ramps down
    assert run["drive_enabled"][-1] == 0.0
    assert json.loads((folder / "metadata.json").read_text())["outcome"] == "stopped"


def test_second_ctrl_c_trips(tmp_path, capsys):
    _signal_later([0.5, 0.05], log_dir=tmp_path)
    status, folder = _dry_run(tmp_path, "--duration", "20")
    capsys.readouterr()
    assert status == exit_codes.TRIPPED
    assert json.loads((folder / "metadata.json").read_text())["trip_reason"] == "operator_trip"


def test_sigterm_trips(tmp_path, capsys):
    _signal_later([0.5], signal.SIGTERM, log_dir=tmp_path)
    status, folder = _dry_run(tmp_path, "--duration", "20")
    capsys.readouterr()
    assert status == exit_codes.TRIPPED
    assert json.loads((folder / "metadata.json").read_text())["trip_reason"] == "operator_trip"


def test_a_raising_controller_trips_and_never_kills_the_process(tmp_path, capsys, monkeypatch):
    import harness.runs.session as session

    real = session.build_controller_for_rig

    class Exploding:
        def __init__(self, inner):
            self.inner, self.calls = inner, 0

        def __getattr__(self, name):
            return getattr(self.inner, name)

        def update(self, *args):
            self.calls += 1
            if self.calls > 600:
                raise ZeroDivisionError("bad gain")
            return self.inner.update(*args)

    monkeypatch.setattr(session, "build_controller_for_rig", lambda profile, name: Exploding(real(profile, name)))
    status, folder = _dry_run(tmp_path, "--duration", "4")
    capsys.readouterr()
    assert status == exit_codes.TRIPPED
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["trip_reason"] == "tick_exception"
    run = load_run(folder)
    assert run["drive_enabled"][-1] == 0.0 and run["force_command_N"][-1] == 0.0
    assert any("ZeroDivisionError" in str(e.get("detail")) for e in run.events)


def test_bus_load_too_high_is_refused_before_anything_moves(tmp_path, capsys):
    status = main(["dry-run", "--log-dir", str(tmp_path), "--quiet", "--set", "can.bitrate_bps=500000", "--duration", "1"])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert "%" in err and "bus" in err.lower()
    assert not any(tmp_path.iterdir())  # nothing written, nothing sent


def test_nothing_compiles_inside_a_run(tmp_path, capsys):
    """The kernels are compiled before the loop starts: a compilation inside a run stalls it for seconds."""
    import numba

    import harness.model.bearing as bearing
    import harness.model.integrator as integrator
    from harness.model.warmup import warm_up

    warm_up()
    kernels = {name: f for module in (bearing, integrator) for name, f in vars(module).items()
               if isinstance(f, numba.core.registry.CPUDispatcher)}
    before = {name: set(f.signatures) for name, f in kernels.items()}
    status, _ = _dry_run(tmp_path, "--duration", "1")
    capsys.readouterr()
    assert status == exit_codes.OK
    compiled = {name: set(f.signatures) - before[name] for name, f in kernels.items() if set(f.signatures) - before[name]}
    assert not compiled, f"compiled during the run: {compiled}"
