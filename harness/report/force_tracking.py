"""How well the actuator gave the force it was asked for: delay, RMS and peak error of the load cell.

The measures of the real-time hybrid simulation benchmark's evaluation (Silva et al., 2020),
the ones :func:`harness.motions.tracking.tracking` applies to the shaking table, applied to the
control actuator: the load cell's force ``force_measured_N`` against the force asked,

- ``force_raw_N``, the controller's force (default): what a compensation
  (``control.compensation``, harness/control/compensation.py) is meant to make the actuator
  give, so the error compared between compensation methods;
- or ``force_command_N``, the command the supervisor sent (it holds a compensator's flow term
  and the force clamp): the actuator's own tracking of its input.

Definitions, for the samples ``k`` of a run (one per control period ``dt``):

- the error is ``e[k] = measured[k + 1] - asked[k]`` (N): the command is held over the period,
  so the load cell read at the next tick is the first that can answer it. A force that follows
  the command exactly one sample later has no error;
- RMS error % = ``100 * RMS(e) / RMS(asked)``, peak error % = ``100 * max|e| / max|asked|``,
  both over the same samples;
- the delay (s) is where the cross-correlation of ``measured[k]`` with ``asked[k]`` (same
  sample index, so it includes the period's hold) peaks, to a fraction of a sample by a
  parabola through the peak and its neighbours; positive when the force lags.

One piece of code serves the report (``harness report``: a table and a plot for every run
with a load cell, :mod:`harness.report.force_tracking_view`) and ``harness simulate
--rig-effects`` (:meth:`harness.runs.simulate.StudyResult.force_tracking`). This module
does not load matplotlib.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from harness.motions.tracking import tracking
from harness.signals.columns import FORCE_COMMAND, FORCE_MEASURED, FORCE_RAW, TIME

__all__ = ["ASKED_COLUMNS", "MAX_LAG_S", "ForceTracking", "force_tracking", "has_load_cell", "run_force_tracking",
           "tracking_line", "tracking_lines"]

#: The forces the load cell may be compared with, and what each is called in words.
ASKED_COLUMNS: dict[str, str] = {FORCE_RAW: "the controller's force", FORCE_COMMAND: "the command sent"}

#: Largest delay searched each way (s): ten times the 8 ms force loop of the shipped rig.
MAX_LAG_S = 0.1


@dataclass(frozen=True)
class ForceTracking:
    """The load cell against the force asked, over one run.

    Attributes
    ----------
    asked : str
        The column compared with (``force_raw_N`` or ``force_command_N``).
    delay_s : float
        Where the cross-correlation of the measured with the asked force peaks (s), same sample
        index (the period's hold included); positive when the force lags.
    rms_error_N, peak_error_N : float
        RMS and largest ``|e|`` of ``e[k] = measured[k + 1] - asked[k]`` (N).
    rms_error_percent : float
        ``100 * RMS(e) / RMS(asked)`` (%; NaN when nothing was asked).
    peak_error_percent : float
        ``100 * max|e| / max|asked|`` (%; NaN when nothing was asked).
    peak_error_t_s : float
        Time of the largest error (s, the run's clock: the sample of the measured force).
    correlation : float
        Normalized cross-correlation at the delay (1: the same shape).
    samples : int
        Error samples used.
    """

    asked: str
    delay_s: float
    rms_error_N: float
    peak_error_N: float
    rms_error_percent: float
    peak_error_percent: float
    peak_error_t_s: float
    correlation: float
    samples: int

    def as_json(self) -> dict[str, float | int | str]:
        """The fields as a plain dict (SI units)."""
        return {"asked": self.asked, "delay_s": self.delay_s, "rms_error_N": self.rms_error_N,
                "peak_error_N": self.peak_error_N, "rms_error_percent": self.rms_error_percent,
                "peak_error_percent": self.peak_error_percent, "peak_error_t_s": self.peak_error_t_s,
                "correlation": self.correlation, "samples": self.samples}


def force_tracking(t_s: np.ndarray, measured_N: np.ndarray, asked_N: np.ndarray, asked: str = FORCE_RAW,
                   max_lag_s: float = MAX_LAG_S) -> ForceTracking | None:
    """The :class:`ForceTracking` of a measured force against the force asked, sample by sample.

    Parameters
    ----------
    t_s : ndarray
        Sample times (s), increasing; their median step is the sample period.
    measured_N, asked_N : ndarray
        The load cell's force and the force asked (N), same length as ``t_s``. Samples where
        either is not finite are left out (the samples on both sides of the gap are joined).
    asked : str
        Which column ``asked_N`` is (recorded in the result).
    max_lag_s : float
        Largest delay searched each way (s).

    Returns
    -------
    ForceTracking or None
        None with fewer than 4 usable samples (3 errors), or no positive sample step.
    """
    t_s, measured_N, asked_N = (np.asarray(values, dtype=float) for values in (t_s, measured_N, asked_N))
    if not t_s.shape == measured_N.shape == asked_N.shape:
        raise ValueError(f"force_tracking needs three arrays of one length, got {t_s.shape}, {measured_N.shape}, "
                         f"{asked_N.shape}")
    usable = np.isfinite(t_s) & np.isfinite(measured_N) & np.isfinite(asked_N)
    t_s, measured_N, asked_N = t_s[usable], measured_N[usable], asked_N[usable]
    if t_s.size < 4:
        return None
    dt_s = float(np.median(np.diff(t_s)))
    if not dt_s > 0.0:
        return None
    held = tracking(measured_N[1:], asked_N[:-1], dt_s, max_lag_s)  # error: the next sample's force
    error = measured_N[1:] - asked_N[:-1]
    worst = int(np.argmax(np.abs(error)))
    aligned = tracking(measured_N, asked_N, dt_s, max_lag_s)  # delay: same sample index
    return ForceTracking(
        asked=asked, delay_s=aligned.delay_s, rms_error_N=held.rms_error, peak_error_N=held.peak_error,
        rms_error_percent=held.rms_error_percent, peak_error_percent=held.peak_error_percent,
        peak_error_t_s=float(t_s[1:][worst]), correlation=aligned.correlation, samples=int(error.size),
    )


def has_load_cell(columns: Mapping[str, np.ndarray]) -> bool:
    """True if the columns hold a load cell's force with at least one finite sample."""
    measured = columns.get(FORCE_MEASURED)
    return measured is not None and bool(np.isfinite(np.asarray(measured, dtype=float)).any())


def run_force_tracking(columns: Mapping[str, np.ndarray], asked: str = FORCE_RAW,
                       start_s: float = -math.inf, end_s: float = math.inf) -> ForceTracking | None:
    """The :class:`ForceTracking` of a run's or a case's columns, from ``start_s`` to ``end_s``.

    Parameters
    ----------
    columns : mapping of str to ndarray
        A run folder's signals (:attr:`harness.recording.reader.RunData.signals`) or a simulated
        case's columns; ``t_s``, ``force_measured_N`` and ``asked`` are read.
    asked : str
        ``force_raw_N`` (the controller's force, default) or ``force_command_N`` (the command sent).
    start_s, end_s : float
        First and last time included (s, the columns' clock), e.g. the record's span; default all.

    Returns
    -------
    ForceTracking or None
        None without a load cell (:func:`has_load_cell`), without the ``asked`` column, when
        nothing was asked (a passive run: the force asked is zero throughout), or with too few
        samples.
    """
    if asked not in ASKED_COLUMNS:
        raise ValueError(f"asked must be one of {sorted(ASKED_COLUMNS)}, found {asked!r}")
    if not has_load_cell(columns) or asked not in columns or TIME not in columns:
        return None
    t_s = np.asarray(columns[TIME], dtype=float)
    inside = (t_s >= start_s) & (t_s <= end_s)
    wanted = np.asarray(columns[asked], dtype=float)[inside]
    if not np.any(np.nan_to_num(wanted) != 0.0):
        return None
    return force_tracking(t_s[inside], np.asarray(columns[FORCE_MEASURED], dtype=float)[inside], wanted, asked)


def tracking_line(result: ForceTracking) -> str:
    """One line of text: the delay (ms), RMS and peak error (kN and % of the force asked)."""
    return (f"force tracking against {ASKED_COLUMNS[result.asked]}: delay {result.delay_s * 1e3:+.1f} ms, "
            f"RMS error {result.rms_error_N / 1e3:.3f} kN ({result.rms_error_percent:.1f} % of its RMS), "
            f"peak error {result.peak_error_N / 1e3:.3f} kN ({result.peak_error_percent:.1f} % of its peak)")


def tracking_lines(results: Mapping[str, ForceTracking | None]) -> list[str]:
    """:func:`tracking_line` of each result that is not None, in order."""
    return [tracking_line(result) for result in results.values() if result is not None]
