"""The force-tracking plot: the force asked and the load cell's force over the record, and a zoom on the largest error.

One row of two panels per controlled run with a load cell (:func:`harness.report.force_tracking_table.run_tracking`):
on the left the whole record, the controller's force (the force the tracking is judged
against), the command sent where it differs, and the load cell; on the right the same
signals over :data:`ZOOM_S` either side of the largest error, with the error marked.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.axes import Axes

from harness.recording.reader import RunData
from harness.report.figure import PlotFile, colours, figure, save, style
from harness.report.force_tracking import ForceTracking
from harness.report.force_tracking_table import run_tracking
from harness.report.plot_common import PlotOptions, legend, record_time
from harness.report.reference import record_start_s
from harness.signals.columns import FORCE_COMMAND, FORCE_MEASURED, FORCE_RAW

__all__ = ["ZOOM_S", "force_tracking_plot"]

#: Half-width of the zoom around the largest error (s of record time).
ZOOM_S = 0.25
#: Height of one run's row of panels (px).
ROW_PX = 300

#: (column, line style, legend text, colour; None: the run's colour).
LINES = (
    (FORCE_RAW, "-", "controller's force (asked)", None),
    (FORCE_COMMAND, ":", "command sent", "#7f7f7f"),
    (FORCE_MEASURED, "--", "load cell", "#000000"),
)


def _draw(ax: Axes, run: RunData, colour: str, inside: np.ndarray, with_command: bool) -> None:
    t = record_time(run)[inside]
    for column, dash, text, line_colour in LINES:
        if run.has(column) and (column != FORCE_COMMAND or with_command):
            ax.plot(t, run[column][inside] * 1e-3, ls=dash, lw=1.0, label=text, color=line_colour or colour)


def _command_differs(run: RunData) -> bool:
    """True if the command sent differs from the controller's force (a compensator, the clamp) by more than 1 N."""
    if not run.has(FORCE_RAW, FORCE_COMMAND):
        return False
    return bool(np.nanmax(np.abs(run[FORCE_COMMAND] - run[FORCE_RAW]), initial=0.0) > 1.0)


def _zoom(ax: Axes, run: RunData, colour: str, result: ForceTracking, with_command: bool) -> None:
    """The signals within :data:`ZOOM_S` of the largest error, and the error marked by a vertical span."""
    at = result.peak_error_t_s - record_start_s(run)
    t = record_time(run)
    _draw(ax, run, colour, (t >= at - ZOOM_S) & (t <= at + ZOOM_S), with_command)
    ax.axvline(at, color="#d62728", lw=1.0, ls="-.")
    ax.set_title(f"largest error {result.peak_error_N * 1e-3:.2f} kN at {at:.2f} s", fontsize=10)
    ax.set_xlim(at - ZOOM_S, at + ZOOM_S)


def force_tracking_plot(runs: Sequence[RunData], out_dir: Path, options: PlotOptions) -> PlotFile | None:
    """The controller's force, the command sent and the load cell (kN) against record time, with a zoom.

    Parameters
    ----------
    runs : sequence of RunData
    out_dir : Path
    options : PlotOptions
        Unused (no option applies).

    Returns
    -------
    PlotFile or None
        None when no run has a load cell and a force asked.
    """
    del options
    usable = []
    for run, colour in zip(runs, colours(runs), strict=True):
        tracked = run_tracking(run).get(FORCE_RAW)
        if tracked is not None:
            usable.append((run, colour, tracked))
    if not usable:
        return None
    with matplotlib.rc_context(style()):
        fig = figure(max(420, ROW_PX * len(usable) + 80))
        grid = fig.subplots(len(usable), 2, squeeze=False, gridspec_kw={"width_ratios": (3, 1)})
        for (whole, zoom), (run, colour, tracked) in zip(grid, usable, strict=True):
            with_command = _command_differs(run)
            _draw(whole, run, colour, np.isfinite(record_time(run)), with_command)
            whole.axvspan(tracked.peak_error_t_s - record_start_s(run) - ZOOM_S,
                          tracked.peak_error_t_s - record_start_s(run) + ZOOM_S, color="#d62728", alpha=0.12, lw=0)
            whole.set_ylabel("Force (kN)")
            whole.set_title(f"{run.label}: delay {tracked.delay_s * 1e3:.1f} ms, RMS error "
                            f"{tracked.rms_error_percent:.0f} %, peak error {tracked.peak_error_percent:.0f} %")
            _zoom(zoom, run, colour, tracked, with_command)
            legend(zoom, source=whole)
        grid[-1][0].set_xlabel("Record time (s)")
        grid[-1][1].set_xlabel("Record time (s)")
        fig.suptitle("Force tracking: the controller's force against the load cell (shaded: the zoom, right)")
        return save(fig, "force_tracking", "Force tracking: force asked against the load cell", out_dir)
