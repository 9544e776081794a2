"""A report of a batch (records x controllers): time histories grouped by record, passive drawn once per record.

The issue's batch (``simulate --record el_centro,hachinohe,pacoima --controller phi,OF --out``)
drew the three records on one time axis, the passive case six times and a 12-entry legend.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from harness.recording import canonical_columns, load_runs, write_simulation_case
from harness.report import build_report, plots_control
from harness.report.figure import PASSIVE_SHADES, save
from harness.report.labels import with_labels
from harness.report.plot_common import PlotOptions
from harness.report.plots_control import stroke_plot
from harness.report.plots_response import drift_height_px
from harness.report.record_groups import record_groups

N_STORIES = 3
RECORDS = ("el_centro", "hachinohe", "pacoima")
CONTROLLERS = ("phi", "OF")


def _signals(record: int, scale: float) -> dict[str, np.ndarray]:
    t = np.arange(400) * 0.01
    data = {c: np.zeros(t.size) for c in canonical_columns(N_STORIES, timing=False)}
    data["t_s"] = t
    data["table_displacement_m"] = 0.02 * np.sin((1 + record) * t)
    data["sliding_displacement_m"] = scale * 0.01 * np.sin((1 + record) * 0.7 * t)
    data["friction_force_N"] = 2000 * np.tanh(np.cos((1 + record) * 0.7 * t))
    data["sliding_variable_m_s"] = scale * 0.01 * np.sin(3 * t)
    data["force_command_N"] = 3000 * scale * np.sin(t) if scale != 1.0 else np.zeros(t.size)
    for j in range(1, N_STORIES + 1):
        data[f"drift_{j}_m"] = scale * 1e-3 * j * np.sin((2 + record) * t)
        data[f"floor_acceleration_{j}_m_s2"] = scale * j * np.sin((2 + record) * t)
    return data


@pytest.fixture(scope="module")
def batch(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A batch's folders: one case set per record and controller, each with the record's (identical) passive case."""
    root = tmp_path_factory.mktemp("batch")
    columns = canonical_columns(N_STORIES, timing=False)
    for r, record in enumerate(RECORDS):
        for c, controller in enumerate(CONTROLLERS):
            meta = {"total_weight_N": 39855.0, "record": {"name": record, "pga_g": 0.34, "time_scale": 2.0},
                    "profile_name": "nceer_4dof", "stroke_soft_limit_m": 0.08, "stroke_hard_limit_m": 0.1}
            folder = root / f"{record}_{controller}"
            write_simulation_case(folder, "passive", columns, _signals(r, 1.0), {**meta, "controller": "passive"})
            write_simulation_case(folder, "controlled", columns, _signals(r, 0.1 * (c + 1)), {**meta, "controller": controller})
    return root


def _runs(batch: Path):
    folders = sorted(p for p in batch.iterdir() if p.is_dir() and p.name != "report")
    return with_labels(load_runs([case for folder in folders for case in (folder / "passive", folder / "controlled")]))


def test_one_group_per_record_with_the_passive_case_once(batch: Path) -> None:
    groups = record_groups(_runs(batch))
    assert [group.record for group in groups] == ["el_centro", "hachinohe", "pacoima"]
    for group in groups:
        assert group.grouped and group.title == f"record {group.record}"
        assert [run.record_name for run in group.runs] == [group.record] * 3
        assert sum(run.is_passive for run in group.runs) == 1  # was twice per record (once per controller)
        assert sorted(group.labels) == ["OF", "passive", "phi"]  # the record is the panel's title, not in the legend
    colours = [dict(zip(group.labels, group.colours, strict=True)) for group in groups]
    assert all(colour == colours[0] for colour in colours)  # OF is OF's colour on every record's panel
    assert colours[0]["passive"] == PASSIVE_SHADES[0] and colours[0]["OF"] != colours[0]["phi"]


def test_passive_runs_that_differ_are_both_kept(batch: Path) -> None:
    runs = _runs(batch)
    runs[2].signals["sliding_displacement_m"][5] += 1e-6  # el_centro's second passive case is not the first's
    groups = record_groups(runs)
    assert sum(run.is_passive for run in groups[0].runs) == 2
    assert sum(run.is_passive for run in groups[1].runs) == 1


def test_a_single_record_keeps_one_panel_and_the_full_labels(batch: Path) -> None:
    runs = [run for run in _runs(batch) if run.record_name == "el_centro"]
    (group,) = record_groups(runs)
    assert not group.grouped and group.title == ""
    assert [run.label for run in group.runs if not run.is_passive] == list(group.labels[1:])


def _png_height(path: Path) -> int:
    return struct.unpack(">II", path.read_bytes()[16:24])[1]


def test_the_batch_report_draws_a_panel_per_record(batch: Path, tmp_path: Path, monkeypatch) -> None:
    result = build_report([batch], tmp_path / "report")
    plots = {plot.name: plot for plot in result.plots}
    assert plots["drift"].height_px == drift_height_px(N_STORIES, len(RECORDS)) == _png_height(plots["drift"].path)
    assert plots["drift"].height_px > drift_height_px(N_STORIES)  # a block of story panels per record
    figures = []
    monkeypatch.setattr(plots_control, "save", lambda fig, *args: figures.append(fig) or save(fig, *args))
    assert stroke_plot(_runs(batch), tmp_path, PlotOptions()) is not None
    axes = figures[0].axes
    assert [ax.get_title(loc="left") for ax in axes] == [f"record {record}" for record in RECORDS]
    for ax in axes:  # passive once, each controller once, and the soft and hard limits: the legend fits
        assert [text.get_text() for text in ax.get_legend().get_texts()] == [
            "passive", "OF", "phi", "soft limit ±80 mm", "hard limit ±100 mm"]
        assert len(ax.get_lines()) == 3 + 4  # three runs, each limit drawn at + and -
