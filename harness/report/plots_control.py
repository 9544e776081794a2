"""Plots of the table, the bearing stroke and the control: table motion (target against achieved), stroke, force, S.

Time histories of several records get one panel (or block of panels) per record
(:mod:`harness.report.record_groups`), each with its own legend.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from harness.recording.reader import RunData
from harness.report.figure import PlotFile, colours, figure, save, style
from harness.report.plot_common import PlotOptions, legend, mark_events, record_time, shade_interlocks
from harness.report.record_groups import RecordGroup, record_groups
from harness.report.reference import target_motion

#: Height of one record's panel when a plot has one per record (px).
PANEL_PX = 300


def grouped_height(single_px: int, groups: Sequence[RecordGroup], panel_px: int = PANEL_PX) -> int:
    """Pixel height of a plot: ``single_px`` for one record, ``panel_px`` per record (and titles) for several."""
    return single_px if len(groups) == 1 else max(single_px, panel_px * len(groups) + 100)


def usable_groups(runs: Sequence[RunData], usable) -> list[RecordGroup]:
    """The record groups holding only the runs ``usable(run)`` accepts; groups left empty are dropped."""
    groups = [group.having([bool(usable(run)) for run in group.runs]) for group in record_groups(runs)]
    return [group for group in groups if group.runs]


def record_panels(groups: Sequence[RecordGroup], single_px: int, panel_px: int = PANEL_PX,
                  sharey: bool = False) -> tuple[Figure, list[Axes]]:
    """A figure with one panel per record group, stacked on a shared x axis."""
    fig = figure(grouped_height(single_px, groups, panel_px))
    return fig, list(fig.subplots(len(groups), 1, sharex=True, sharey=sharey, squeeze=False)[:, 0])


def head_panels(fig: Figure, axes: Sequence[Axes], heading: str) -> None:
    """``heading`` over the one panel, or over the figure with ", one panel per record"."""
    if len(axes) == 1:
        axes[0].set_title(heading)
    else:
        fig.suptitle(heading + ", one panel per record")


def title_panel(ax: Axes, group: RecordGroup) -> None:
    """The record's name above its panel (nothing for a report of one record)."""
    if group.title:
        ax.set_title(group.title, loc="left", fontweight="bold")

TARGET_COLOUR = "#000000"


def table_motion_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Table acceleration (m/s^2), velocity (mm/s) and displacement (mm) against time; the target dashed where known."""
    del options
    panels = (
        ("table_acceleration_m_s2", 1.0, "Acceleration (m/s²)", "acceleration_m_s2"),
        ("table_velocity_m_s", 1e3, "Velocity (mm/s)", "velocity_m_s"),
        ("table_displacement_m", 1e3, "Displacement (mm)", "displacement_m"),
    )
    groups = usable_groups(runs, lambda run: any(run.has(column) for column, *_ in panels))
    if not groups:
        return None
    targets = {id(run): target_motion(run) for group in groups for run in group.runs}
    with matplotlib.rc_context(style()):
        fig = figure(grouped_height(720, groups, 3 * 200))
        grid = fig.subplots(3 * len(groups), 1, sharex=True, squeeze=False)[:, 0]
        for block, group in enumerate(groups):
            axes = grid[3 * block : 3 * block + 3]
            for ax, (column, scale, label, target_field) in zip(axes, panels, strict=True):
                for run, colour, text in group.members():
                    if column in run.signals:
                        ax.plot(record_time(run), run[column] * scale, color=colour, lw=1.0, label=f"{text} (sensors)")
                for run, _, text in group.members():
                    target = targets[id(run)]
                    if target is not None:
                        ax.plot(target.t_s, getattr(target, target_field) * scale, color=TARGET_COLOUR, ls="--", lw=0.9,
                                label=f"{text}: target (processed record)")
                ax.set_ylabel(label)
            title_panel(axes[0], group)
            legend(axes[0])
        grid[-1].set_xlabel("Record time (s)")
        fig.suptitle("Shaking-table motion" + (": target against achieved" if any(targets.values()) else ""))
        return save(fig, "table_motion", "Table acceleration, velocity and displacement", out_dir)


def _limit_lines(ax: Axes, runs: Sequence[RunData]) -> bool:
    """The soft and hard stroke limits of the runs' metadata as dashed lines; True if any was drawn."""
    drawn = False
    for key, colour, label in (("stroke_soft_limit_m", "#ff7f0e", "soft limit"),
                               ("stroke_hard_limit_m", "#d62728", "hard limit")):
        value = next((run.metadata[key] for run in runs if isinstance(run.metadata.get(key), (int, float))), None)
        if value is not None:
            ax.axhline(value * 1e3, color=colour, ls="--", lw=1.2, label=f"{label} ±{value * 1e3:.0f} mm")
            ax.axhline(-value * 1e3, color=colour, ls="--", lw=1.2)
            drawn = True
    return drawn


def stroke_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Sliding stroke x_b (mm) against time, with the stroke limits where the runs have them, and interlock events."""
    del options
    groups = usable_groups(runs, lambda run: run.has("sliding_displacement_m"))
    if not groups:
        return None
    with matplotlib.rc_context(style()):
        fig, axes = record_panels(groups, 520, sharey=True)
        shaded = limits = False
        for ax, group in zip(axes, groups, strict=True):
            for run, colour, text in group.members():
                ax.plot(record_time(run), run["sliding_displacement_m"] * 1e3, color=colour, lw=1.0, label=text)
                shaded |= shade_interlocks(ax, run, colour)
                mark_events(ax, run, colour)
            limits |= _limit_lines(ax, list(group.runs))
            ax.set_ylabel("Sliding displacement x_b (mm)")
            title_panel(ax, group)
            legend(ax)
        axes[-1].set_xlabel("Record time (s)")
        extras = [text for text, present in (("dotted lines: events", any(run.events for g in groups for run in g.runs)),
                                             ("shading: interlock active", shaded)) if present]
        title = "Bearing stroke" + (" against its limits" if limits else "")
        head_panels(fig, axes, title + (f" ({'; '.join(extras)})" if extras else ""))
        return save(fig, "stroke", title, out_dir)


FORCE_LINES = (
    ("force_raw_N", ":", "raw (controller)", "#7f7f7f"),
    ("force_command_N", "-", "command (supervised)", None),
    ("force_measured_N", "--", "measured", "#000000"),
)


def force_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Actuator force (kN): raw controller output, supervised command, measured; a panel per controlled run, one scale."""
    del options
    usable = [(run, c) for run, c in zip(runs, colours(runs), strict=True)
              if not run.is_passive and any(run.has(line[0]) for line in FORCE_LINES)]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(max(420, 260 * len(usable) + 80))
        axes = fig.subplots(len(usable), 1, sharex=True, sharey=True, squeeze=False)[:, 0]
        for ax, (run, colour) in zip(axes, usable, strict=True):
            for column, dash, label, line_colour in FORCE_LINES:
                if column in run.signals:
                    ax.plot(record_time(run), run[column] * 1e-3, ls=dash, lw=1.0, label=label, color=line_colour or colour)
            limit = run.metadata.get("force_limit_N")
            if isinstance(limit, (int, float)):
                ax.axhline(limit * 1e-3, color="#d62728", ls="--", lw=1.0, label=f"limit ±{limit * 1e-3:.1f} kN")
                ax.axhline(-limit * 1e-3, color="#d62728", ls="--", lw=1.0)
            mark_events(ax, run, colour)
            ax.set_ylabel("Force (kN)")
            ax.set_title(run.label)
            legend(ax)
        axes[-1].set_xlabel("Record time (s)")
        fig.suptitle("Actuator force" + (" (one force scale for every panel)" if len(usable) > 1 else ""))
        return save(fig, "force", "Actuator force: controller, supervised command and measured", out_dir)


def sliding_variable_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """The sliding variable S (mm/s) against time."""
    del options
    groups = usable_groups(runs, lambda run: run.has("sliding_variable_m_s"))
    if not groups:
        return None
    with matplotlib.rc_context(style()):
        fig, axes = record_panels(groups, 440, 260)
        for ax, group in zip(axes, groups, strict=True):
            for run, colour, text in group.members():
                ax.plot(record_time(run), run["sliding_variable_m_s"] * 1e3, color=colour, lw=1.0, label=text)
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_ylabel("Sliding variable S (mm/s)")
            title_panel(ax, group)
            legend(ax)
        axes[-1].set_xlabel("Record time (s)")
        head_panels(fig, axes, "Sliding variable S of each run's controller")
        return save(fig, "sliding_variable", "Sliding variable", out_dir)


def tracking_error_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Table displacement achieved minus target (mm) for the runs that keep their target motion."""
    del options
    targets = {id(run): target_motion(run) for run in runs}
    groups = usable_groups(runs, lambda run: targets.get(id(run)) is not None and run.has("table_displacement_m"))
    if not groups:
        return None
    with matplotlib.rc_context(style()):
        fig, axes = record_panels(groups, 400, 260)
        for ax, group in zip(axes, groups, strict=True):
            for run, colour, text in group.members():
                target = targets[id(run)]
                assert target is not None  # usable_groups kept the runs with a target
                t = record_time(run)
                inside = (t >= target.t_s[0]) & (t <= target.t_s[-1])
                error = run["table_displacement_m"][inside] - np.interp(t[inside], target.t_s, target.displacement_m)
                ax.plot(t[inside], error * 1e3, color=colour, lw=0.9, label=text)
            ax.axhline(0.0, color="k", lw=0.5)
            ax.set_ylabel("Achieved - target (mm)")
            title_panel(ax, group)
            legend(ax)
        axes[-1].set_xlabel("Record time (s)")
        heading = "Table displacement tracking error (sensor minus processed record)"
        if len(groups) == 1:
            axes[0].set_title(heading)
        else:
            fig.suptitle(heading)
        return save(fig, "table_tracking", "Table displacement: achieved minus target", out_dir)
