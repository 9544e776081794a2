"""Issue 33, item 6: labels and plots that mislead, each fixed."""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

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
