"""The loop-timing plot: histograms of tick lateness and compute time of real-time runs (run, dry run).

In lockstep the loop waits for the rig, so there is no lateness to show: the panel says so
instead of drawing an empty histogram. Each legend gives the percentiles of its column (the
compute column is the measurement the console's summary is made of).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.axes import Axes

from harness.recording.reader import RunData
from harness.report.figure import PlotFile, colours, figure, save, style
from harness.report.plot_common import PlotOptions, legend
from harness.signals.timing_counts import TimingCounts


def _timing(run: RunData) -> Mapping[str, Any]:
    summary = run.metadata.get("summary")
    timing = summary.get("timing") if isinstance(summary, Mapping) else None
    return timing if isinstance(timing, Mapping) else {}


def is_lockstep(run: RunData) -> bool:
    """True for a run whose loop waited for the rig (no lateness to measure)."""
    return bool(_timing(run).get("lockstep", run.metadata.get("lockstep", False)))


def _histogram(ax: Axes, run: RunData, column: str, colour: str) -> bool:
    values = run[column][np.isfinite(run[column])] * 1e6
    if not values.size:
        return False
    p50, p99 = np.percentile(values, (50, 99))
    label = f"{run.label}: p50 {p50:.0f}, p99 {p99:.0f}, max {values.max():.0f} µs"
    if column == "lateness_s":
        if run.has("overrun"):
            label += f", {TimingCounts.of_overrun_column(run['overrun']).words()}"
    ax.hist(values, bins=60, color=colour, alpha=0.6, label=label)
    return True


def _not_real_time(ax: Axes, runs: Sequence[RunData]) -> None:
    names = ", ".join(run.label for run in runs)
    ax.text(0.5, 0.5, f"lockstep: the loop waited for the rig,\nso tick lateness is not measured\n({names})",
            transform=ax.transAxes, ha="center", va="center", fontsize=11, color="#555555")
    ax.set_xticks([])
    ax.set_yticks([])


def timing_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """Histograms of tick lateness and compute time (µs) for runs and dry runs."""
    del options
    usable = [(run, c) for run, c in zip(runs, colours(runs), strict=True)
              if run.kind in ("run", "dry-run") and run.has("lateness_s")]
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(460)
        left, right = fig.subplots(1, 2)
        for ax, column, title in ((left, "lateness_s", "Tick lateness"), (right, "compute_s", "Compute time per tick")):
            candidates = [(run, colour) for run, colour in usable if not (column == "lateness_s" and is_lockstep(run))]
            drawn = [_histogram(ax, run, column, colour) for run, colour in candidates if column in run.signals]
            ax.set_title(title)
            if not any(drawn):
                _not_real_time(ax, [run for run, _ in usable if is_lockstep(run)])
                continue
            ax.set_xlabel(f"{title} (µs)")
            ax.set_ylabel("Ticks")
            ax.set_yscale("log")
            legend(ax, "below")
        fig.suptitle("Loop timing")
        return save(fig, "timing", "Loop timing histograms", out_dir)
