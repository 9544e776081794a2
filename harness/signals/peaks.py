"""Peak responses people compare (SPEC 5): one model, computed one way, from a case's columns.

:func:`peak_responses` turns the columns of one case (a simulated case, the rig twin, a
run folder read back) into a :class:`Peaks`; :func:`harness.recording.peaks.run_peaks` does the
same for a run folder, taking the weight and whether the run is passive from its metadata. ``harness
simulate``, dry runs, reports and benchmarks all read their peaks from here, and compare
two cases with :func:`reduction_pct`. Rendering (console, HTML, CSV) is
:mod:`harness.report.peak_table`'s business.

Every peak compared is taken over one window, :class:`ComparisonWindow`: the record's
duration from the moment the record started, plus :data:`COMPARISON_TAIL_S`. A dry run or
table run keeps running after its record (the loop's ``tail_s``, then the force's ramp to
zero); those rows are not compared, because the simulated cases it is compared with end with
the record.

Values are SI. A peak with nothing to measure (the column is absent, or holds no finite
value) is NaN.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from harness.signals.columns import (
    BASE_ACCELERATION,
    FORCE_COMMAND,
    FORCE_MEASURED,
    FORCE_RAW,
    SLIDING_DISPLACEMENT,
    TABLE_ACCELERATION,
    TABLE_DISPLACEMENT,
    TABLE_VELOCITY,
    TIME,
    count_stories,
    drift,
    floor_acceleration,
)

#: The control force u of SPEC 5, best source first: the supervised command sent to the
#: actuator, else the controller's raw output. A column without a finite value is skipped.
FORCE_COLUMNS: tuple[str, ...] = (FORCE_COMMAND, FORCE_RAW)

NAN = float("nan")
#: Seconds after the record's end that comparisons include (s). The simulated cases a run is
#: compared with (the passive reference, the rig twin, ``harness simulate``) end with the record,
#: whose last second brings the table to rest; a longer tail would compare a run's free decay
#: and the loop's force ramp-down with nothing.
COMPARISON_TAIL_S = 0.0


@dataclass(frozen=True)
class ComparisonWindow:
    """The rows compared: from the record's start, its duration plus a tail (loop time, s).

    Attributes
    ----------
    start_s : float
        Loop time at which the record started (s): 0 for a simulated case.
    record_s : float
        The record's duration (s).
    tail_s : float
        Time after the record's end that is included (s).
    """

    start_s: float
    record_s: float
    tail_s: float = COMPARISON_TAIL_S

    @property
    def end_s(self) -> float:
        """Loop time of the window's last row (s)."""
        return self.start_s + self.record_s + self.tail_s

    def inside(self, t_s: np.ndarray) -> np.ndarray:
        """Which of the times ``t_s`` (s) fall in the window (a boolean mask); a tick's rounding is allowed."""
        slack = 1e-9 * max(1.0, abs(self.end_s))
        return (t_s >= self.start_s - slack) & (t_s <= self.end_s + slack)

    def describe(self) -> str:
        """What the tables say: ``"compared over the record (30.00 s) plus a 0 s tail"``."""
        return f"compared over the record ({self.record_s:.2f} s) plus a {self.tail_s:g} s tail"


def windowed(columns: Mapping[str, np.ndarray], window: ComparisonWindow | None) -> Mapping[str, np.ndarray]:
    """The rows of ``columns`` inside ``window`` (all of them without a window or a time column)."""
    if window is None or TIME not in columns:
        return columns
    keep = window.inside(np.asarray(columns[TIME], dtype=float))
    return {name: np.asarray(values)[keep] for name, values in columns.items()}


def run_window(metadata: Mapping[str, object]) -> ComparisonWindow | None:
    """A run folder's comparison window, from its metadata: the record's start and duration; None without a record."""
    record, summary = metadata.get("record"), metadata.get("summary")
    duration = record.get("duration_s") if isinstance(record, Mapping) else None
    start = summary.get("record_start_t_s") if isinstance(summary, Mapping) else None
    if not isinstance(duration, (int, float)) or isinstance(duration, bool) or not duration > 0:
        return None
    return ComparisonWindow(float(start) if isinstance(start, (int, float)) else 0.0, float(duration))


@dataclass(frozen=True)
class Peaks:
    """Peak |value| of one case's responses (SPEC 5), SI; NaN where there is nothing to measure.

    Attributes
    ----------
    sliding_displacement_m : float
        Peak sliding displacement of the base mat on the table, ``x_b`` (m).
    base_acceleration_m_s2 : float
        Peak absolute acceleration of the base mat (m/s^2).
    drift_m : tuple of float
        Peak interstory drift of stories 1..n, bottom up (m).
    floor_acceleration_m_s2 : tuple of float
        Peak absolute acceleration of floors 1..n, bottom up (m/s^2).
    peak_force_pct_weight : float
        Peak control force ``u`` in percent of the total weight ``mbar g`` (%); 0 for a passive case.
    measured_force_pct_weight : float
        Peak force the actuator measured, in percent of the weight (%).
    table_acceleration_m_s2, table_velocity_m_s, table_displacement_m : float
        Peak table motion the case was fed (m/s^2, m/s, m): two runs of "the same record"
        can be seen to be fed the same input.
    """

    sliding_displacement_m: float
    base_acceleration_m_s2: float
    drift_m: tuple[float, ...]
    floor_acceleration_m_s2: tuple[float, ...]
    peak_force_pct_weight: float
    measured_force_pct_weight: float = NAN
    table_acceleration_m_s2: float = NAN
    table_velocity_m_s: float = NAN
    table_displacement_m: float = NAN

    @property
    def n_stories(self) -> int:
        """Stories with a drift peak."""
        return len(self.drift_m)

    def as_json(self) -> dict[str, float | list[float]]:
        """The SPEC 5 peaks as ``harness simulate --json`` writes each case (SI, story lists bottom up).

        Returns
        -------
        dict
            ``{"sliding_displacement_m", "base_acceleration_m_s2", "drift_m": [1..n],
            "floor_acceleration_m_s2": [1..n], "peak_force_pct_weight"}``.
        """
        return {
            "sliding_displacement_m": self.sliding_displacement_m,
            "base_acceleration_m_s2": self.base_acceleration_m_s2,
            "drift_m": list(self.drift_m),
            "floor_acceleration_m_s2": list(self.floor_acceleration_m_s2),
            "peak_force_pct_weight": self.peak_force_pct_weight,
        }

    def flatten(self) -> dict[str, float]:
        """The SPEC 5 peaks of :meth:`as_json`, one scalar each, named by their column (``drift_3_m`` ...)."""
        stories = range(1, self.n_stories + 1)
        return {
            "sliding_displacement_m": self.sliding_displacement_m,
            "base_acceleration_m_s2": self.base_acceleration_m_s2,
            **{drift(j): self.drift_m[j - 1] for j in stories},
            **{floor_acceleration(j): self.floor_acceleration_m_s2[j - 1] for j in stories},
            "peak_force_pct_weight": self.peak_force_pct_weight,
        }


def peak_abs(values: np.ndarray) -> float | None:
    """Largest finite |value| of ``values``, or None if there is none."""
    values = np.asarray(values, dtype=float)
    finite = np.abs(values[np.isfinite(values)])
    return float(finite.max()) if finite.size else None


def _column_peak(columns: Mapping[str, np.ndarray], name: str) -> float:
    """Peak |value| of column ``name``; NaN if it is absent or has no finite value."""
    peak = peak_abs(columns[name]) if name in columns else None
    return NAN if peak is None else peak


def force_column(columns: Mapping[str, np.ndarray]) -> str | None:
    """The column holding the control force u (:data:`FORCE_COLUMNS`, first with a finite value), or None."""
    for name in FORCE_COLUMNS:
        if name in columns and np.isfinite(columns[name]).any():
            return name
    return None


def _percent_of_weight(peak_N: float, total_weight_N: float | None) -> float:
    """``100 peak / weight`` (%); NaN without a positive weight."""
    if not isinstance(total_weight_N, (int, float)) or total_weight_N <= 0:
        return NAN
    return 100.0 * peak_N / total_weight_N


def _control_force_pct(columns: Mapping[str, np.ndarray], total_weight_N: float | None, passive: bool | None) -> float:
    """Peak control force in percent of the weight: 0 for a passive case without one, NaN if unknown."""
    column = force_column(columns)
    if column is None:
        is_passive = passive if passive is not None else not any(name in columns for name in FORCE_COLUMNS)
        return 0.0 if is_passive else NAN
    return _percent_of_weight(_column_peak(columns, column), total_weight_N)


def peak_responses(
    columns: Mapping[str, np.ndarray], total_weight_N: float | None, *, passive: bool | None = None,
    window: ComparisonWindow | None = None,
) -> Peaks:
    """Peaks of one case from its columns.

    Parameters
    ----------
    columns : mapping of str to ndarray
        Columns named as in :mod:`harness.signals.columns` (``drift_j_m``,
        ``floor_acceleration_j_m_s2``, ``sliding_displacement_m``, ``base_acceleration_m_s2``,
        a force column of :data:`FORCE_COLUMNS`, ...). Any may be absent: its peak is NaN.
    total_weight_N : float or None
        ``mbar g`` (N), for the forces in percent of it; None or not positive: those are NaN.
    passive : bool, optional
        Whether the case has no controller, so that no force column means a force of 0 %.
        Default: passive exactly when no column of :data:`FORCE_COLUMNS` is present.
    window : ComparisonWindow, optional
        Only the rows inside it (by ``t_s``) are measured; default: every row.

    Returns
    -------
    Peaks
    """
    columns = windowed(columns, window)
    stories = range(1, count_stories(tuple(columns)) + 1)
    measured = _column_peak(columns, FORCE_MEASURED)
    return Peaks(
        sliding_displacement_m=_column_peak(columns, SLIDING_DISPLACEMENT),
        base_acceleration_m_s2=_column_peak(columns, BASE_ACCELERATION),
        drift_m=tuple(_column_peak(columns, drift(j)) for j in stories),
        floor_acceleration_m_s2=tuple(_column_peak(columns, floor_acceleration(j)) for j in stories),
        peak_force_pct_weight=_control_force_pct(columns, total_weight_N, passive),
        measured_force_pct_weight=_percent_of_weight(measured, total_weight_N),
        table_acceleration_m_s2=_column_peak(columns, TABLE_ACCELERATION),
        table_velocity_m_s=_column_peak(columns, TABLE_VELOCITY),
        table_displacement_m=_column_peak(columns, TABLE_DISPLACEMENT),
    )


#: A reference (passive) peak at or below this, in its SI unit (m, m/s^2, % of the weight), is
#: numerically zero: 1 um and 1 um/s^2 are below the resolution of a rig's displacement
#: transducers and accelerometers, and far below the peaks any record gives a passive case;
#: a run that ended before its record started leaves passive peaks like 1e-14 m.
REFERENCE_FLOOR_SI = 1e-6
#: A reference peak smaller than this share of the compared peak is not at the response's
#: scale: the tables show peaks to about three significant figures, so such a reference has
#: no significant digit at the compared value's scale, and its "reduction" (below -99 900 %)
#: would only measure the reference's noise.
REFERENCE_RATIO_FLOOR = 1e-3


def comparable_reference(passive: float, hybrid: float) -> bool:
    """Whether a percent reduction of ``hybrid`` against the reference ``passive`` means something.

    Both must be finite, the reference above :data:`REFERENCE_FLOOR_SI` (numerically not zero)
    and at least :data:`REFERENCE_RATIO_FLOOR` times ``|hybrid|`` (at the response's scale).
    """
    if not math.isfinite(passive) or not math.isfinite(hybrid):
        return False
    reference = abs(passive)
    return reference > REFERENCE_FLOOR_SI and reference >= REFERENCE_RATIO_FLOOR * abs(hybrid)


def reduction_pct(passive: float | None, hybrid: float | None) -> float | None:
    """Percent reduction ``100 (passive - hybrid) / passive`` (SPEC 5), or None where it means nothing.

    The one place that decides whether a reduction is shown: every table, report, CSV and
    sweep column takes its reductions from here. None (shown as
    :data:`harness.report.peak_table.NO_REDUCTION`) unless :func:`comparable_reference`: a
    value absent or not finite, a reference that is numerically zero or far below the
    response's scale (a run that tripped before its record started).
    """
    if passive is None or hybrid is None or not comparable_reference(passive, hybrid):
        return None
    return 100.0 * (passive - hybrid) / passive
