"""Plots of the building's response: peak profiles over height, drift histories, bearing hysteresis.

Where some runs' peaks are far smaller than others' (a controlled eight-story building
against its passive case), those runs would vanish into the zero line at the common scale:
the peak profile then uses a logarithmic axis, and the drift plot adds a column with the
small runs alone, at their own scale. Drift histories and hysteresis loops of several records
get one block of panels (one panel) per record (:mod:`harness.report.record_groups`).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes

from harness.recording.peaks import run_peaks
from harness.recording.reader import RunData
from harness.report.figure import PlotFile, colours, figure, save, style
from harness.report.plot_common import PlotOptions, legend, peak_of, record_time, small_runs
from harness.report.plots_control import head_panels, record_panels, title_panel, usable_groups
from harness.report.record_groups import RecordGroup
from harness.report.reference import passive_reference, passive_reference_drifts
from harness.signals.columns import drift


def drift_height_px(n_stories: int, n_records: int = 1) -> int:
    """Pixel height of the drift plot for ``n_stories`` panels (per record, for ``n_records`` records)."""
    if n_records == 1:
        return max(420, 190 * n_stories + 90)
    return 150 * n_stories * n_records + 40 * n_records + 90


#: How the simulated passive reference of a dry run is drawn beside the run (its own colour, dashed).
REFERENCE_LINE = "--"


def peak_profile_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Peak drift per story and peak absolute acceleration per floor (m/s^2, floor 0 = base mat) over height.

    A dry run's simulated passive reference (the one its console and tables compare it with)
    is drawn beside it, dashed in the run's colour.
    """
    stories = max((run.n_stories for run in runs), default=0)
    if stories == 0:
        return None
    scale, unit = options.drift_scale()
    profiles = []
    for run, colour in zip(runs, colours(runs), strict=True):
        named = [(run_peaks(run), run.label, "-")]
        reference = passive_reference(run)
        if reference is not None:
            named.append((reference, f"passive (sim.): {run.label}", REFERENCE_LINE))
        for peaks, label, line in named:
            accelerations = np.array((peaks.base_acceleration_m_s2, *peaks.floor_acceleration_m_s2))
            profiles.append((label, colour, line, np.array(peaks.drift_m) * scale, accelerations))
    logarithmic = bool(small_runs([float(np.nanmax(p[3], initial=0.0)) for p in profiles]))
    with matplotlib.rc_context(style()):
        fig = figure(520)
        left, right = fig.subplots(1, 2)
        for label, colour, line, drifts, accelerations in profiles:
            if drifts.size == stories and np.isfinite(drifts).all():
                left.plot(drifts, range(1, stories + 1), "o" + line, color=colour, label=label)
            if accelerations.size == stories + 1 and np.isfinite(accelerations).all():
                right.plot(accelerations, range(0, stories + 1), "s" + line, color=colour, label=label)
        left.set(xlabel=f"Peak interstory {unit}", ylabel="Story", title="Peak drift per story")
        left.set_yticks(range(1, stories + 1))
        right.set(xlabel="Peak absolute acceleration (m/s²)", ylabel="Floor (0 = base mat)")
        right.set_title("Peak acceleration per floor")
        right.set_yticks(range(0, stories + 1))
        for ax in (left, right):
            if logarithmic:
                ax.set_xscale("log")
            else:
                ax.set_xlim(left=0)
        if logarithmic:
            fig.suptitle("Peaks over height (logarithmic axes: the runs' peaks differ by more than a factor of 5)")
        legend(right)
        return save(fig, "peak_profile", "Peak drift and absolute acceleration over height", out_dir)


def _drift_panels(axes: Sequence[Axes], group: RecordGroup, stories: int, scale: float, references: bool = True) -> None:
    """One panel per story; with ``references``, a dry run's simulated passive reference dashed in its colour."""
    for panel, story in zip(axes, range(stories, 0, -1), strict=True):
        for run, colour, text in group.members():
            if drift(story) in run.signals:
                panel.plot(record_time(run), run[drift(story)] * scale, color=colour, lw=1.0, label=text)
            passive = passive_reference_drifts(run) if references else None
            if passive is not None and drift(story) in passive:
                panel.plot(passive["t_s"], passive[drift(story)] * scale, REFERENCE_LINE, color=colour, lw=0.9,
                           alpha=0.8, label=f"passive (sim.): {text}")
        panel.text(0.005, 0.96, f"story {story}", transform=panel.transAxes, va="top", ha="left",
                   fontweight="bold", bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1.5})


def drift_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Interstory drift histories, one panel per story (top story at the top), runs overlaid; a block per record.

    A dry run's simulated passive reference (``passive_reference.csv``) is drawn dashed in the
    run's colour, so a single dry run is seen against its passive case.

    Runs whose peak drift is more than 5 times below the largest of their record get a second
    column at their own scale.
    """
    stories = max((run.n_stories for run in runs), default=0)
    if stories == 0:
        return None
    scale, unit = options.drift_scale()
    groups = usable_groups(runs, lambda run: True)
    smalls = [small_runs([peak_of(run, [drift(j) for j in range(1, stories + 1)]) for run in group.runs])
              for group in groups]
    columns = 2 if any(smalls) else 1
    with matplotlib.rc_context(style()):
        fig = figure(drift_height_px(stories, len(groups)))
        grid = fig.subplots(stories * len(groups), columns, sharex=True, squeeze=False)
        for block, (group, small) in enumerate(zip(groups, smalls, strict=True)):
            rows = grid[block * stories : (block + 1) * stories]
            _drift_panels(list(rows[:, 0]), group, stories, scale)
            if small:
                _drift_panels(list(rows[:, 1]), group.having([i in small for i in range(len(group.runs))]), stories, scale,
                              references=False)
            elif columns == 2:
                for ax in rows[:, 1]:
                    ax.set_axis_off()
            title_panel(rows[0, 0], group)
            legend(rows[0, -1], source=rows[0, 0])
        if columns == 2:
            grid[0, 0].set_title("All runs, one scale", loc="center" if len(groups) == 1 else "right")  # left: the record
            grid[0, 1].set_title("Runs with small drifts, their own scale")
        for ax in grid[-1, :]:
            ax.set_xlabel("Time (s)")
        fig.supylabel(f"Interstory {unit}")
        fig.suptitle("Interstory drift (story j: floor j minus floor j-1)" + ("" if len(groups) == 1 else
                                                                              ", a block of panels per record"))
        return save(fig, "drift", "Interstory drift time histories per story", out_dir)


def _hysteresis_source(run: RunData) -> tuple[str, str] | None:
    """(column, legend text) of the bearing friction force: the model's, else the online estimate."""
    for column, text in (("friction_force_N", "model friction"), ("friction_estimate_N", "estimated friction")):
        if run.has(column) and np.isfinite(run[column]).any():
            return column, text
    return None


def _weight(run: RunData) -> float | None:
    weight = run.metadata.get("total_weight_N")
    return float(weight) if isinstance(weight, (int, float)) and weight > 0 else None


def hysteresis_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Bearing hysteresis: friction force over the weight (F/W), or in kN without a weight, against x_b (mm)."""
    del options
    groups = usable_groups(runs, lambda run: _hysteresis_source(run) is not None and run.has("sliding_displacement_m"))
    if not groups:
        return None
    normalised = all(_weight(run) for group in groups for run in group.runs)
    with matplotlib.rc_context(style()):
        fig, axes = record_panels(groups, 640, 360, sharey=True)
        for ax, group in zip(axes, groups, strict=True):
            for run, colour, label in group.members():
                source = _hysteresis_source(run)
                assert source is not None  # usable_groups kept the runs with a friction column
                column, text = source
                weight = _weight(run)
                force = run[column] / weight if normalised and weight else run[column] * 1e-3
                ax.plot(run["sliding_displacement_m"] * 1e3, force, color=colour, lw=0.8, label=f"{label} ({text})")
            ax.set_ylabel("Friction force / weight, F/W (-)" if normalised else "Friction force (kN)")
            ax.axhline(0.0, color="k", lw=0.5)
            ax.axvline(0.0, color="k", lw=0.5)
            title_panel(ax, group)
            legend(ax)
        axes[-1].set_xlabel("Sliding displacement x_b (mm)")
        head_panels(fig, axes, "Bearing hysteresis" + (" (F/W: the friction coefficient mobilised)" if normalised else ""))
        return save(fig, "hysteresis", "Bearing hysteresis against sliding displacement", out_dir)
