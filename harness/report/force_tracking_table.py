"""The report's force-tracking table: for every controlled run with a load cell, how well the actuator followed.

Rows come from :func:`harness.report.force_tracking.run_force_tracking`, over the record (from
the loop time the record started, :func:`harness.report.reference.record_start_s`, for the
record's duration or until a trip, :func:`record_span`; the stopping ramp after it is left out): the load
cell against the controller's force, and against the command sent. A run without a load cell
(an offline simulation without rig effects) or without a force asked (a passive run) has no
row; a report with no such run has no table.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from harness.recording.reader import RunData
from harness.report.force_tracking import ASKED_COLUMNS, ForceTracking, run_force_tracking
from harness.report.reference import record_start_s
from harness.report.text_table import TextTable
from harness.signals.peaks import run_window

__all__ = ["force_tracking_table", "record_span", "run_tracking"]

TITLE = "Force tracking: load cell against the force asked"
HEADINGS = ("Run", "Against", "Delay (ms)", "Correlation", "RMS error (kN)", "RMS error (% of RMS asked)", "Peak error (kN)",
            "Peak error (% of peak asked)", "Largest error at (s)")
NOTE = ("Load cell (force_measured_N) over the record against the controller's force (force_raw_N) and the command "
        "sent (force_command_N, after a compensator and the supervisor). Error: the load cell at the next sample minus "
        "the force asked (the command is held over the period). RMS error % = 100 RMS(error) / RMS(force asked); "
        "peak error % = 100 max|error| / max|force asked|. Delay: where the cross-correlation of the load cell with "
        "the force asked peaks, refined to a fraction of a sample (positive: the force lags); correlation: the "
        "normalized cross-correlation there (well below 1: the load cell is not a late copy of the force asked, and "
        "the delay means little). Largest error at: record time.")


def record_span(run: RunData) -> tuple[float, float]:
    """Loop times (s) over which the run's actuator followed its controller: from the record's start to its end or the trip.

    The end is the end of the run's comparison window (:func:`harness.signals.peaks.run_window`:
    the record and its stated tail; infinite when unknown), or the run's first fault event (a
    trip) if that came earlier: after a trip the force is the supervisor's, not the controller's.
    """
    window = run_window(run.metadata)
    start = window.start_s if window else record_start_s(run)
    end = window.end_s if window else math.inf
    trips = [float(event["t_s"]) for event in run.events
             if event.get("kind") == "fault" and isinstance(event.get("t_s"), (int, float))]
    return start, min([end, *trips])


def run_tracking(run: RunData) -> dict[str, ForceTracking]:
    """The run's force tracking against each force asked that it has, over its record; empty without a load cell.

    Parameters
    ----------
    run : RunData
        A run folder read back.

    Returns
    -------
    dict of str to ForceTracking
        Keyed by the column asked (``force_raw_N``, ``force_command_N``); passive runs get none.
    """
    if run.is_passive:
        return {}
    start, end = record_span(run)
    found = {asked: run_force_tracking(run.signals, asked, start, end) for asked in ASKED_COLUMNS}
    return {asked: result for asked, result in found.items() if result is not None}


def _row(run: RunData, result: ForceTracking) -> tuple[str, ...]:
    return (run.label, ASKED_COLUMNS[result.asked], f"{result.delay_s * 1e3:+.2f}", f"{result.correlation:.3f}",
            f"{result.rms_error_N / 1e3:.3f}",
            f"{result.rms_error_percent:.1f}", f"{result.peak_error_N / 1e3:.3f}", f"{result.peak_error_percent:.1f}",
            f"{result.peak_error_t_s - record_start_s(run):.3f}")


def force_tracking_table(runs: Sequence[RunData]) -> TextTable | None:
    """The force-tracking table of the runs that have a load cell and a force asked; None if none has.

    Parameters
    ----------
    runs : sequence of RunData

    Returns
    -------
    TextTable or None
    """
    rows = tuple(_row(run, result) for run in runs for result in run_tracking(run).values())
    if not rows:
        return None
    numeric = (False, False, True, True, True, True, True, True, True)
    return TextTable(TITLE, HEADINGS, rows, NOTE, key_columns=2, numeric=numeric)
