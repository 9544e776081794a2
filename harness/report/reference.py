"""A dry run against what it is compared with: its simulated passive reference, its rig twin, its target motion.

A dry run keeps in its folder (:mod:`harness.runs.run_context`) the peaks of the passive
reference and of the rig twin it printed on the console, and the processed record the table
was asked to follow. From these:

- :func:`reference_tables`: the dry run against its passive reference, with the percent
  reduction (the console's table), and against its rig twin (``harness simulate
  --rig-effects``), with the differences;
- :func:`target_motion_table`: the table's target peaks (the processed record) against the
  achieved ones (the table sensors), and the RMS tracking error over the record;
- :func:`target_motion` reads the target time series back, for the plot.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.motions.tracking import Tracking, tracking
from harness.recording.peaks import run_peaks
from harness.recording.reader import RunData
from harness.report.peak_table import PeakTable
from harness.report.table_check import run_table_check
from harness.report.tables import peaks_comparison_table, peaks_pair_table, window_note
from harness.report.text_table import TextTable
from harness.signals.peaks import Peaks

REFERENCE_KEY = "reference"
TARGET_FILE_KEY = "target_motion_file"
PASSIVE_FILE_KEY = "passive_reference_file"
G_M_S2 = 9.80665


def _float(value: Any) -> float:
    """A peak read back: JSON's ``null`` (a peak with nothing to measure) is NaN again."""
    return float("nan") if value is None else float(value)


def _peaks(data: Any) -> Peaks | None:
    """A :class:`Peaks` from its ``dataclasses.asdict`` form (stories as lists); None if malformed."""
    if not isinstance(data, Mapping):
        return None
    try:
        values: dict[str, Any] = {key: tuple(map(_float, value)) if isinstance(value, list) else _float(value)
                                  for key, value in data.items()}
        return Peaks(**values)
    except (TypeError, ValueError):
        return None


def _span_note(reference: Mapping[str, Any]) -> str:
    span = reference.get("span_s")
    return f"Simulated over the {span:.2f} s of record the run covered before it ended. " if span else ""


def passive_reference(run: RunData) -> Peaks | None:
    """The peaks of the simulated passive reference a dry run was compared with; None for other runs."""
    reference = run.metadata.get(REFERENCE_KEY)
    return _peaks(reference.get("passive_peaks")) if isinstance(reference, Mapping) else None


def reference_tables(runs: Sequence[RunData]) -> list[PeakTable]:
    """For each run holding a ``reference`` entry: against its passive reference, and against its rig twin."""
    tables = []
    for run in runs:
        reference = run.metadata.get(REFERENCE_KEY)
        if not isinstance(reference, Mapping):
            continue
        measured = run_peaks(run)
        passive, twin = _peaks(reference.get("passive_peaks")), _peaks(reference.get("twin_peaks"))
        note = _span_note(reference) + window_note((run,)) + " "
        check = run_table_check(run.metadata)  # a table that did not play the told record: no reductions
        if passive is not None:
            tables.append(peaks_pair_table(
                passive, measured, f"Against the simulated passive reference: {run.label}",
                ("passive (sim.)", run.label), note + "The passive case simulated offline under the same record.",
                check.withheld, check.flagged,
            ))
        if twin is not None:
            delay = reference.get("twin_delay", "")
            caveat = f" Not comparable: {check.withheld}." if check.withheld else ""
            tables.append(peaks_comparison_table(
                twin, measured, f"Against the rig twin: {run.label}", ("A: rig twin (sim.)", f"B: {run.label}"),
                note + "Rig twin: harness simulate --rig-effects, the rig's sensor, actuator and safety models "
                f"offline (asynchrony: {delay}).{caveat}",
            ))
    return tables


@dataclass(frozen=True)
class TargetMotion:
    """The processed record a run's table was asked to follow, in record time (s, m/s^2, m/s, m)."""

    t_s: np.ndarray
    acceleration_m_s2: np.ndarray
    velocity_m_s: np.ndarray
    displacement_m: np.ndarray


def target_motion(run: RunData) -> TargetMotion | None:
    """The run's target motion (``target_motion.csv``), or None if it has none or it cannot be read."""
    name = run.metadata.get(TARGET_FILE_KEY)
    path = run.path / name if isinstance(name, str) else None
    if path is None or not path.is_file():
        return None
    try:
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError):
        return None
    if table.shape[1] < 4 or table.shape[0] < 2:
        return None
    return TargetMotion(table[:, 0], table[:, 1], table[:, 2], table[:, 3])


def passive_reference_drifts(run: RunData) -> dict[str, np.ndarray] | None:
    """The dry run's simulated passive drift histories (``t_s`` in record time, ``drift_j_m``), or None.

    None for a run without them (not a dry run, an older one, a file that cannot be read).
    """
    name = run.metadata.get(PASSIVE_FILE_KEY)
    path = run.path / name if isinstance(name, str) else None
    if path is None or not path.is_file():
        return None
    try:
        header = path.read_text(encoding="utf-8").split("\n", 1)[0].strip().split(",")
        table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    if table.shape[1] != len(header) or table.shape[0] < 2 or header[0] != "t_s":
        return None
    return {column: table[:, index] for index, column in enumerate(header)}


def record_start_s(run: RunData) -> float:
    """Loop time at which the run's record (the table motion) started (s); 0 when unknown (simulations)."""
    summary = run.metadata.get("summary")
    start = summary.get("record_start_t_s") if isinstance(summary, Mapping) else None
    return float(start) if isinstance(start, (int, float)) else 0.0


def tracking_error(run: RunData, target: TargetMotion, column: str, target_values: np.ndarray) -> Tracking | None:
    """Achieved against target over the record (:func:`harness.motions.tracking.tracking`); None without overlap.

    The achieved signal is taken at the run's samples inside the record and resampled to
    a uniform grid of the run's median step, as is the target.
    """
    if not run.has(column):
        return None
    t = run["t_s"] - record_start_s(run)
    inside = (t >= target.t_s[0]) & (t <= target.t_s[-1]) & np.isfinite(run[column])
    if inside.sum() < 3:
        return None
    times = t[inside]
    step = float(np.median(np.diff(times)))
    if not step > 0.0:
        return None
    grid = np.arange(times[0], times[-1] + 0.5 * step, step)
    achieved = np.interp(grid, times, run[column][inside])
    return tracking(achieved, np.interp(grid, target.t_s, target_values), step)


def _peak(values: np.ndarray) -> float:
    return float(np.max(np.abs(values))) if values.size else float("nan")


def target_motion_table(runs: Sequence[RunData]) -> TextTable | None:
    """Target (the processed record) against achieved (the table sensors): peaks, their difference, RMS error."""
    rows = []
    for run in runs:
        target = target_motion(run)
        if target is None:
            continue
        achieved = run_peaks(run)
        for name, values, peak, column, scale, unit in (
            ("acceleration", target.acceleration_m_s2, achieved.table_acceleration_m_s2, "table_acceleration_m_s2", 1.0,
             "m/s^2"),
            ("velocity", target.velocity_m_s, achieved.table_velocity_m_s, "table_velocity_m_s", 1e3, "mm/s"),
            ("displacement", target.displacement_m, achieved.table_displacement_m, "table_displacement_m", 1e3, "mm"),
        ):
            wanted = _peak(values)
            difference = 100.0 * (peak - wanted) / wanted if wanted else float("nan")
            measured = tracking_error(run, target, column, values)
            rows.append((run.label, f"Peak table {name}", unit, f"{wanted * scale:.3f}", f"{peak * scale:.3f}",
                         f"{difference:+.1f}", *_tracking_cells(measured, scale)))
    if not rows:
        return None
    headings = ("Run", "Quantity", "Unit", "Target", "Achieved", "Difference (%)", "RMS error", "Peak error", "Delay (ms)")
    note = ("Target: the processed record (target_motion.csv, the table's drive); achieved: the table sensors "
            "(signals.csv), in record time. RMS and peak of achieved minus target over the record, in the row's unit; "
            "delay: where their cross-correlation peaks (positive: the table lags its drive).")
    numeric = (False, False, True, True, True, True, True, True)
    if len({row[0] for row in rows}) == 1:  # one run: its label is in the title
        title = f"Table motion: target against achieved: {rows[0][0]}"
        return TextTable(title, headings[1:], tuple(row[1:] for row in rows), note, key_columns=2, numeric=numeric)
    return TextTable("Table motion: target against achieved", headings, tuple(rows), note, key_columns=3,
                     numeric=(False, *numeric))


def _tracking_cells(measured: Tracking | None, scale: float) -> tuple[str, str, str]:
    """RMS error, peak error (scaled to the row's unit) and delay (ms), or dashes."""
    if measured is None:
        return "-", "-", "-"
    return f"{measured.rms_error * scale:.3f}", f"{measured.peak_error * scale:.3f}", f"{measured.delay_s * 1e3:+.2f}"
