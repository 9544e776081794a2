"""The report's plots, one function each; a plot whose columns no run has is skipped (None).

Every function takes the runs (drawn in the same colour everywhere, passive in grey)
and the output folder and returns a :class:`~harness.report.figure.PlotFile`.
Display units: displacements and drifts in mm, accelerations in m/s^2, velocities
in mm/s, forces in kN, loop timing in microseconds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes

from harness.peaks import run_peaks
from harness.recording.reader import RunData
from harness.report.figure import PlotFile, colours, figure, save, style
from harness.rowlayout import drift

EVENT_KINDS = ("trip", "interlock", "warning")
_MAX_EVENT_LABELS = 12

PlotFunction = Callable[[Sequence[RunData], Path], "PlotFile | None"]


def drift_height_px(n_stories: int) -> int:
    """Pixel height of the drift plot for ``n_stories`` panels."""
    return max(420, 190 * n_stories + 90)


def _record_start(run: RunData) -> float:
    """Loop time at which the run's record (the table motion) started; 0 for simulations."""
    summary = run.metadata.get("summary") or {}
    start = summary.get("record_start_t_s") if isinstance(summary, dict) else None
    return float(start) if isinstance(start, (int, float)) else 0.0


def _time(run: RunData) -> np.ndarray:
    """Time axis in record time, so runs of one record line up (a dry run arms and settles first)."""
    return run.signals["t_s"] - _record_start(run)


def _legend(ax: Axes, where: str = "right") -> None:
    """Legend outside the axes (``"right"`` of it or ``"below"`` it) so it never hides data."""
    if not ax.get_legend_handles_labels()[0]:
        return
    if where == "below":
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), framealpha=0.9)
    else:
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)


def drift_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Interstory drift time histories, one panel per story (top story at the top), runs overlaid."""
    stories = max((run.n_stories for run in runs), default=0)
    if stories == 0:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(drift_height_px(stories))
        axes = fig.subplots(stories, 1, sharex=True, squeeze=False)[:, 0]
        for panel, story in zip(axes, range(stories, 0, -1)):
            for run, colour in zip(runs, colours(runs)):
                if drift(story) in run.signals:
                    panel.plot(_time(run), run[drift(story)] * 1e3, color=colour, lw=1.0, label=run.label)
            panel.text(0.005, 0.96, f"story {story}", transform=panel.transAxes, va="top", ha="left",
                       fontweight="bold", bbox={"fc": "white", "ec": "none", "alpha": 0.8, "pad": 1.5})
        _legend(axes[0])
        axes[-1].set_xlabel("Time (s)")
        fig.supylabel("Interstory drift (mm)")
        fig.suptitle("Interstory drift (story j: floor j minus floor j-1)")
        return save(fig, "drift", "Interstory drift time histories per story", out_dir)


def table_motion_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Table acceleration (m/s^2), velocity (mm/s) and displacement (mm) against time."""
    panels = (
        ("table_acceleration_m_s2", 1.0, "Acceleration (m/s²)"),
        ("table_velocity_m_s", 1e3, "Velocity (mm/s)"),
        ("table_displacement_m", 1e3, "Displacement (mm)"),
    )
    if not any(run.has(column) for run in runs for column, _, _ in panels):
        return None
    with matplotlib.rc_context(style()):
        fig = figure(720)
        axes = fig.subplots(3, 1, sharex=True)
        for ax, (column, scale, label) in zip(axes, panels):
            for run, colour in zip(runs, colours(runs)):
                if column in run.signals:
                    ax.plot(_time(run), run[column] * scale, color=colour, lw=1.0, label=run.label)
            ax.set_ylabel(label)
        _legend(axes[0])
        axes[-1].set_xlabel("Time (s)")
        fig.suptitle("Shaking-table motion")
        return save(fig, "table_motion", "Table acceleration, velocity and displacement", out_dir)


def _hysteresis_source(run: RunData) -> tuple[str, float, str] | None:
    for column, scale, label in (
        ("friction_force_N", 1e-3, "Friction force (kN)"),
        ("friction_estimate_N", 1e-3, "Friction force estimate (kN)"),
        ("hysteretic_nu", 1.0, "Hysteretic variable ν (-)"),
    ):
        if column in run.signals:
            return column, scale, label
    return None


def hysteresis_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Bearing hysteresis: friction force (or its estimate, or nu) against sliding displacement (mm)."""
    usable = [(run, c, _hysteresis_source(run)) for run, c in zip(runs, colours(runs))]
    usable = [(run, c, src) for run, c, src in usable if src is not None and run.has("sliding_displacement_m")]
    if not usable:
        return None
    labels = {src[2] for _, _, src in usable}
    with matplotlib.rc_context(style()):
        fig = figure(640)
        ax = fig.subplots()
        for run, colour, (column, scale, _) in usable:
            label = f"{run.label} ({column})"
            ax.plot(run["sliding_displacement_m"] * 1e3, run[column] * scale, color=colour, lw=0.8, label=label)
        ax.set_xlabel("Sliding displacement x_b (mm)")
        ax.set_ylabel(labels.pop() if len(labels) == 1 else "Friction force (kN) / ν (-)")
        ax.axhline(0.0, color="k", lw=0.5)
        ax.axvline(0.0, color="k", lw=0.5)
        _legend(ax)
        ax.set_title("Bearing hysteresis")
        return save(fig, "hysteresis", "Bearing hysteresis against sliding displacement", out_dir)


def _limit_lines(ax: Axes, runs: Sequence[RunData]) -> None:
    limits = (("stroke_soft_limit_m", "#ff7f0e", "soft limit"), ("stroke_hard_limit_m", "#d62728", "hard limit"))
    for key, colour, label in limits:
        value = next((run.metadata[key] for run in runs if isinstance(run.metadata.get(key), (int, float))), None)
        if value is not None:
            ax.axhline(value * 1e3, color=colour, ls="--", lw=1.2, label=f"{label} ±{value * 1e3:.0f} mm")
            ax.axhline(-value * 1e3, color=colour, ls="--", lw=1.2)


def _mark_events(ax: Axes, run: RunData, colour: str) -> None:
    """A dotted line at every event; a label at the first event of each name only, so labels never pile up."""
    marked = [e for e in run.events if e.get("kind") in EVENT_KINDS and isinstance(e.get("t_s"), (int, float))]
    start = _record_start(run)
    labelled: set[str] = set()
    for event in marked:
        t = event["t_s"] - start
        ax.axvline(t, color=colour, ls=":", lw=1.2)
        name = f"{event.get('kind')}: {event.get('name')}"
        if name not in labelled and len(labelled) < _MAX_EVENT_LABELS:
            labelled.add(name)
            ax.annotate(
                name,
                xy=(t, 1.0),
                xycoords=("data", "axes fraction"),
                rotation=90,
                va="top",
                ha="right",
                fontsize=9,
                color=colour,
                bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": colour, "alpha": 0.85},
            )


def _shade_interlocks(ax: Axes, run: RunData, colour: str) -> None:
    """Shade the ticks where any interlock flag is set."""
    if not run.has("interlock_flags"):
        return
    active = np.nan_to_num(run["interlock_flags"]) != 0
    if active.any():
        label = f"{run.label}: interlock active"
        band = ax.get_xaxis_transform()
        ax.fill_between(_time(run), 0, 1, where=active, transform=band, color=colour, alpha=0.12, lw=0, label=label)


def stroke_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Sliding stroke x_b (mm) against time, with the soft and hard limits and interlock events."""
    usable = [(run, c) for run, c in zip(runs, colours(runs)) if run.has("sliding_displacement_m")]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(520)
        ax = fig.subplots()
        for run, colour in usable:
            ax.plot(_time(run), run["sliding_displacement_m"] * 1e3, color=colour, lw=1.0, label=run.label)
            _shade_interlocks(ax, run, colour)
            _mark_events(ax, run, colour)
        _limit_lines(ax, [run for run, _ in usable])
        ax.set_xlabel("Time (s)")
        ax.set_ylabel("Sliding displacement x_b (mm)")
        ax.set_title("Bearing stroke against its limits (dotted lines: interlock events; shading: interlock active)")
        _legend(ax)
        return save(fig, "stroke", "Sliding stroke against soft and hard limits, interlock events marked", out_dir)


def force_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Actuator force (kN): raw controller output, supervised command, measured force; a panel per controlled run."""
    lines = (
        ("force_raw_N", ":", "raw (controller)", "#7f7f7f"),
        ("force_command_N", "-", "command (supervised)", None),
        ("force_measured_N", "--", "measured", "#000000"),
    )
    usable = [
        (run, c) for run, c in zip(runs, colours(runs)) if not run.is_passive and any(run.has(line[0]) for line in lines)
    ]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(max(420, 260 * len(usable) + 80))
        axes = fig.subplots(len(usable), 1, sharex=True, squeeze=False)[:, 0]
        for ax, (run, colour) in zip(axes, usable):
            for column, dash, label, line_colour in lines:
                if column in run.signals:
                    ax.plot(_time(run), run[column] * 1e-3, ls=dash, lw=1.0, label=label, color=line_colour or colour)
            limit = run.metadata.get("force_limit_N")
            if isinstance(limit, (int, float)):
                ax.axhline(limit * 1e-3, color="#d62728", ls="--", lw=1.0, label=f"limit ±{limit * 1e-3:.1f} kN")
                ax.axhline(-limit * 1e-3, color="#d62728", ls="--", lw=1.0)
            _mark_events(ax, run, colour)
            ax.set_ylabel("Force (kN)")
            ax.set_title(run.label)
            _legend(ax)
        axes[-1].set_xlabel("Time (s)")
        fig.suptitle("Actuator force")
        return save(fig, "force", "Actuator force: command and measured", out_dir)


def sliding_variable_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """The sliding variable S (mm/s) against time."""
    usable = [(run, c) for run, c in zip(runs, colours(runs)) if run.has("sliding_variable_m_s")]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(440)
        ax = fig.subplots()
        for run, colour in usable:
            ax.plot(_time(run), run["sliding_variable_m_s"] * 1e3, color=colour, lw=1.0, label=run.label)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel("Time (s)")
        ax.set_ylabel("Sliding variable S (mm/s)")
        ax.set_title("Sliding variable S = p1·y_b + ẏ_b")
        _legend(ax)
        return save(fig, "sliding_variable", "Sliding variable", out_dir)


def timing_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Histograms of tick lateness and compute time (us) for real-time runs (run, dry-run)."""
    usable = [
        (run, c) for run, c in zip(runs, colours(runs)) if run.kind in ("run", "dry-run") and run.has("lateness_s")
    ]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(460)
        left, right = fig.subplots(1, 2)
        for ax, column, title in ((left, "lateness_s", "Tick lateness"), (right, "compute_s", "Compute time per tick")):
            for run, colour in usable:
                if column in run.signals:
                    _histogram(ax, run, column, colour)
            ax.set_xlabel(f"{title} (µs)")
            ax.set_ylabel("Ticks")
            ax.set_yscale("log")
            ax.set_title(title)
            _legend(ax, "below")
        fig.suptitle("Loop timing")
        return save(fig, "timing", "Loop timing histograms", out_dir)


def _histogram(ax: Axes, run: RunData, column: str, colour: str) -> None:
    values = run[column][np.isfinite(run[column])] * 1e6
    if not values.size:
        return
    overruns = int(np.nansum(run["overrun"] > 0)) if run.has("overrun") else 0
    p50, p99 = np.percentile(values, (50, 99))
    label = f"{run.label}: p50 {p50:.0f}, p99 {p99:.0f}, max {values.max():.0f} µs"
    if column == "lateness_s":
        label += f", {overruns} overruns"
    ax.hist(values, bins=60, color=colour, alpha=0.6, label=label)


def peak_profile_plot(runs: Sequence[RunData], out_dir: Path) -> PlotFile | None:
    """Peak drift per story (mm) and peak absolute acceleration per floor (m/s^2, floor 0 = base mat) over height."""
    stories = max((run.n_stories for run in runs), default=0)
    if stories == 0:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(520)
        left, right = fig.subplots(1, 2)
        for run, colour in zip(runs, colours(runs)):
            peaks = run_peaks(run)
            drifts = np.array(peaks.drift_m)
            if drifts.size == stories and np.isfinite(drifts).all():
                left.plot(drifts * 1e3, range(1, stories + 1), "o-", color=colour, label=run.label)
            accelerations = np.array((peaks.base_acceleration_m_s2, *peaks.floor_acceleration_m_s2))
            if accelerations.size == stories + 1 and np.isfinite(accelerations).all():
                right.plot(accelerations, range(0, stories + 1), "s-", color=colour, label=run.label)
        left.set(xlabel="Peak interstory drift (mm)", ylabel="Story", title="Peak drift per story")
        left.set_yticks(range(1, stories + 1))
        right.set(xlabel="Peak absolute acceleration (m/s²)", ylabel="Floor (0 = base mat)")
        right.set_title("Peak acceleration per floor")
        right.set_yticks(range(0, stories + 1))
        left.set_xlim(left=0)
        right.set_xlim(left=0)
        _legend(right)
        return save(fig, "peak_profile", "Peak drift and absolute acceleration over height", out_dir)


#: Every plot, in report order.
PLOTS: tuple[PlotFunction, ...] = (
    peak_profile_plot,
    drift_plot,
    table_motion_plot,
    hysteresis_plot,
    stroke_plot,
    force_plot,
    sliding_variable_plot,
    timing_plot,
)
