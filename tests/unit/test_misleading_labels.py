"""Issue 33, item 6: labels and plots that mislead, each fixed."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from harness.console.live import record_time_text, run_title
from harness.recording.reader import RunData
from harness.report import plots_response
from harness.report.labels import distinct_labels
from harness.report.plot_common import PlotOptions
from harness.runs.run_context import write_dry_run_context
from harness.signals.columns import TIME, drift
from harness.signals.peaks import Peaks
from harness.simulation.case import CaseResult


def _run(path: Path, metadata: dict, profile: dict | None = None, n: int = 200) -> RunData:
    t = np.linspace(0.0, 2.0, n)
    signals = {TIME: t, drift(1): 1e-4 * np.sin(5 * t)}
    return RunData(path, metadata, profile or {}, tuple(signals), signals, [], None, False)


def test_a_passive_case_is_not_labelled_with_a_controller_delay(tmp_path: Path) -> None:
    dry_run = _run(tmp_path / "dry", {"kind": "dry-run", "controller": "phi", "record": {"name": "el_centro"}},
                   {"name": "nceer_4dof", "control": {"rate_hz": 500, "transport_delay_s": 0.0}})
    passive = _run(tmp_path / "sim" / "passive", {"kind": "simulation", "case": "passive", "controller": "phi",
                                                   "record": {"name": "el_centro"},
                                                   "sampling": {"rate_hz": 500, "transport_delay_s": 0.002}})
    labels = distinct_labels([dry_run, passive])
    assert not any("delay" in label for label in labels), labels  # was: "dry run phi delay 0 ms", "sim passive delay 2 ms"
    assert labels == ["dry run phi", "sim passive"]


def test_two_controlled_runs_still_differ_by_their_delay(tmp_path: Path) -> None:
    runs = [_run(tmp_path / str(delay), {"kind": "simulation", "case": "controlled", "controller": "phi",
                                         "sampling": {"rate_hz": 500, "transport_delay_s": delay}})
            for delay in (0.0, 0.002)]
    assert distinct_labels(runs) == ["delay 0 ms", "delay 2 ms"]


def test_a_single_dry_run_drift_plot_overlays_its_passive_reference(tmp_path: Path, monkeypatch) -> None:
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "metadata.json").write_text(json.dumps({"kind": "dry-run", "controller": "phi"}))
    t = np.linspace(0.0, 2.0, 101)
    passive = CaseResult("passive", {TIME: t, drift(1): 3e-3 * np.sin(4 * t)}, Peaks(0.0, 0.0, (3e-3,), (0.0,), 0.0), 0, 0.0)
    motion = SimpleNamespace(t_s=t, accel_m_s2=0 * t, velocity_m_s=0 * t, displacement_m=0 * t)
    write_dry_run_context(folder, motion, passive, None, None, lockstep=True)
    metadata = json.loads((folder / "metadata.json").read_text())
    run = _run(folder, metadata)
    drawn = {}

    def keep(fig, name, title, out_dir):
        drawn["lines"] = [line for ax in fig.axes for line in ax.get_lines()]

    monkeypatch.setattr(plots_response, "save", keep)
    plots_response.drift_plot([run], tmp_path, PlotOptions())
    passive_lines = [line for line in drawn["lines"] if str(line.get_label()).startswith("passive (sim.)")]
    assert len(passive_lines) == 1
    assert np.max(np.abs(passive_lines[0].get_ydata())) == pytest.approx(3.0, rel=1e-3)  # mm


def test_the_identify_console_titles_an_identification_not_a_dry_run() -> None:
    metadata = {"controller": "excitation (chirp)", "identification": {"kind": "actuator", "condition": "blocked"}}
    title = run_title("nceer_4dof", "dry-run", metadata, "excitation (chirp)", 500.0, True)
    assert "dry-run" not in title
    assert title == "nceer_4dof: identify actuator (blocked) on the virtual rig, excitation (chirp) at 500 Hz (lockstep)"
    assert run_title("nceer_4dof", "dry-run", {}, "phi", 500.0, False) == "nceer_4dof: dry-run, phi at 500 Hz"


def test_the_console_never_shows_record_time_past_the_record() -> None:
    assert record_time_text(41.6, 40.0).startswith("  40.0 / 40.0 s  (100.0 %), then 1.6 s after it")  # was 41.6 / 40.0
    assert record_time_text(12.0, 30.0) == "  12.0 / 30.0 s  ( 40.0 %)"


def test_white_noise_under_a_time_scale_says_it_plays_its_band_not_compressed() -> None:
    from harness.motions.config import RecordConfig
    from harness.motions.loading import load_raw_and_motion

    _, motion = load_raw_and_motion(RecordConfig(), base_dir=".", name="white_noise:0.5-5", time_scale=2.0, duration_s=10.0,
                                    env={})
    assert not any("compressed by" in note for note in motion.notes), motion.notes
    assert any("still plays 0.5-5 Hz" in note for note in motion.notes)
    _, record = load_raw_and_motion(RecordConfig(), base_dir=".", name="synthetic", time_scale=2.0, duration_s=10.0, env={})
    assert any(note.startswith("time compressed by 2") for note in record.notes)  # a real record's time is compressed


def test_harness_rig_says_why_it_stopped_on_ctrl_c() -> None:
    import os
    import signal
    import subprocess
    import sys

    from harness import exit_codes
    from harness.commands.rig import SERVING
    from tests.conftest import REPO

    channel = f"rig-ctrl-c-{os.getpid()}"
    rig = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "rig", "--lockstep", "--interface", "seqpacket", "--channel", channel,
         "--record", "synthetic", "--duration", "2", "--parent-pid", str(os.getpid())],
        cwd=REPO, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
    )
    try:
        assert rig.stdout is not None
        for line in rig.stdout:  # Ctrl-C while it serves (before, the command's own "interrupted" says it)
            if SERVING in line:
                break
        rig.send_signal(signal.SIGINT)
        rest = rig.communicate(timeout=60)[0]
    finally:
        if rig.poll() is None:
            rig.kill()
            rig.wait()
    assert rig.returncode == exit_codes.STOPPED
    assert "virtual rig stopped by the operator (Ctrl-C): drive disabled, bus closed (exit status 4)" in rest, rest
