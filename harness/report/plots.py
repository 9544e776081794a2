"""The report's plots, in report order; a plot whose columns no run has is skipped (None).

Every function takes the runs (drawn in the same colour everywhere, the first passive run
in grey), the output folder and the :class:`PlotOptions`, and returns a
:class:`~harness.report.figure.PlotFile`. The plots themselves live in
:mod:`.plots_response` (peak profiles, drifts, hysteresis), :mod:`.plots_control` (table
motion, tracking error, stroke, force, sliding variable), :mod:`.plots_force_tracking` (force
asked against the load cell) and :mod:`.plots_timing`.
"""

from __future__ import annotations

from harness.report.plot_common import PlotFunction, PlotOptions
from harness.report.plots_control import (
    force_plot,
    sliding_variable_plot,
    stroke_plot,
    table_motion_plot,
    tracking_error_plot,
)
from harness.report.plots_force_tracking import force_tracking_plot
from harness.report.plots_response import drift_height_px, drift_plot, hysteresis_plot, peak_profile_plot
from harness.report.plots_timing import timing_plot

__all__ = ["PLOTS", "PLOT_NAMES", "PlotFunction", "PlotOptions", "drift_height_px"]

#: Every plot, in report order.
PLOTS: tuple[PlotFunction, ...] = (
    peak_profile_plot,
    drift_plot,
    table_motion_plot,
    tracking_error_plot,
    hysteresis_plot,
    stroke_plot,
    force_plot,
    force_tracking_plot,
    sliding_variable_plot,
    timing_plot,
)

#: The file names (without ``.png``) the plots write.
PLOT_NAMES = ("peak_profile", "drift", "table_motion", "table_tracking", "hysteresis", "stroke", "force", "force_tracking",
              "sliding_variable", "timing")
