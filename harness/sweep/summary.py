"""Summary tables of a sweep's results: % reduction per design, per record and overall; peaks per design.

A *design* is a controller together with the values of the study's grid axes (``axes.set``
and ``axes.scale``: "FSF-I, design_stiffness_scale=0.7"); records, PGA levels and Monte-Carlo
samples are what a design is judged over. Only cases whose outcome is ``ok`` count; the
tables say how many failed. Columns are the ones :mod:`harness.sweep.rows` writes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.report.peak_table import reduction_text
from harness.sweep.axes import SCALE_PREFIX
from harness.sweep.rows import (
    CONTROLLED,
    FAILED,
    MAX_DRIFT,
    MAX_FLOOR_ACCELERATION,
    OK,
    OUTCOME,
    PASSIVE,
    REDUCTION,
    SLIDING,
)

Columns = Mapping[str, np.ndarray]

#: Responses whose % reduction the summary reports, with a short heading for each.
REDUCED = {
    MAX_DRIFT: "drift", MAX_FLOOR_ACCELERATION: "floor accel", "base_acceleration_m_s2": "base accel", SLIDING: "sliding",
}
FORCE = "peak_force_pct_weight"
ALL = "all"
#: The columns of the short tables (console, summary.md); the CSV files hold every column. Each
#: response's largest reduction comes with its smallest, the worst case (negative: it grew).
SHORT_REDUCTION = ["design", "record", "cases", "failed", "drift median %", "drift min %", "drift max %",
                   "floor accel median %", "floor accel min %", "floor accel max %", "sliding median %", "sliding min %",
                   "sliding max %", "force median % W", "force max % W"]
SHORT_PEAKS = ["design", "cases", SLIDING, "base_acceleration_m_s2", MAX_DRIFT, MAX_FLOOR_ACCELERATION, FORCE]


@dataclass(frozen=True)
class ValueTable:
    """Rows of raw values (numbers at full precision, or text) under column names, with a title.

    What a sweep's summaries hold: its CSV files take the values as they are, and
    :meth:`cells` formats them for Markdown and the console (where a
    :class:`~harness.report.text_table.TextTable` of those cells draws them). Beside it,
    :class:`~harness.report.peak_table.PeakTable` holds peak responses (quantities against cases).
    """

    title: str
    header: list[str]
    rows: list[list[Any]]
    #: The columns holding percent reductions (see :meth:`cells`).
    reductions: frozenset[str] = frozenset()

    def select(self, names: Sequence[str]) -> ValueTable:
        """The same table with only the columns ``names`` (those it has), in that order."""
        keep = [self.header.index(name) for name in names if name in self.header]
        return ValueTable(self.title, [self.header[i] for i in keep], [[row[i] for i in keep] for row in self.rows],
                     self.reductions)

    def cells(self, row: Sequence[Any], digits: int = 3) -> list[str]:
        """The texts of ``row``, numbers to ``digits`` significant figures.

        A missing reduction shows as :func:`harness.report.peak_table.reduction_text` shows it,
        another missing number as ``-``.
        """
        def cell(value: Any, name: str) -> str:
            if isinstance(value, float) and not np.isfinite(value):
                return reduction_text(None) if name in self.reductions else "-"
            if isinstance(value, float):
                return f"{value:.{digits}g}"
            return str(value)

        return [cell(value, name) for value, name in zip(row, self.header, strict=True)]

    def to_markdown(self, digits: int = 3) -> str:
        """The table as Markdown, numbers to ``digits`` significant figures."""
        lines = ["| " + " | ".join(self.header) + " |", "|" + "---|" * len(self.header)]
        lines += ["| " + " | ".join(self.cells(row, digits)) + " |" for row in self.rows]
        return "\n".join(lines)


def _short(key: str) -> str:
    """The last part of a key path (``control.design_stiffness_scale`` -> ``design_stiffness_scale``)."""
    return key.rsplit(".", 1)[-1]


def _format(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def design_labels(columns: Columns, grid_keys: Sequence[str]) -> np.ndarray:
    """One label per row: the controller and the grid axes' values (``FSF-I, design_stiffness_scale=0.7``)."""
    controllers = columns["controller"]
    labels = []
    for i, controller in enumerate(controllers):
        parts = [str(controller)]
        for key in grid_keys:
            if key not in columns:
                continue
            value = columns[key][i]
            if key.startswith(SCALE_PREFIX):
                parts.append(f"{_short(key[len(SCALE_PREFIX):])} x{_format(value)}")
            else:
                parts.append(f"{_short(key)}={_format(value)}")
        labels.append(", ".join(parts))
    return np.array(labels, dtype=object)


def groups(labels: np.ndarray) -> dict[str, np.ndarray]:
    """Row indices of each label, in the order labels first appear."""
    found: dict[str, list[int]] = {}
    for i, label in enumerate(labels):
        found.setdefault(str(label), []).append(i)
    return {label: np.array(rows, dtype=int) for label, rows in found.items()}


def _stat(values: np.ndarray, how: str) -> float:
    finite = values[np.isfinite(values)]
    if not finite.size:
        return float("nan")
    if how == "median":
        return float(np.median(finite))
    return float(np.min(finite) if how == "min" else np.max(finite))


def ok_rows(columns: Columns) -> np.ndarray:
    """Mask of the rows whose case succeeded."""
    return np.asarray(columns[OUTCOME] == OK, dtype=bool)


def passive_rows(columns: Columns) -> np.ndarray:
    """Indices of the succeeded rows with distinct passive simulations.

    Every design of a study repeats the same passive simulation (same record, level, bearing),
    so the passive case is counted once per distinct simulation: rows whose record, PGA and
    passive peaks are all equal are one.
    """
    seen: set[tuple] = set()
    chosen = []
    names = [name for name in (f"{PASSIVE}.{SLIDING}", f"{PASSIVE}.{MAX_DRIFT}", f"{PASSIVE}.{MAX_FLOOR_ACCELERATION}")
             if name in columns]
    for i in np.flatnonzero(ok_rows(columns)):
        key = (str(columns["record"][i]), float(columns["pga_g"][i]), *(float(columns[name][i]) for name in names))
        if key not in seen:
            seen.add(key)
            chosen.append(i)
    return np.array(chosen, dtype=int)


def _summary_row(columns: Columns, rows: np.ndarray, design: str, record: str) -> list[Any]:
    ok = rows[ok_rows(columns)[rows]]
    failed = int(np.sum(columns[OUTCOME][rows] == FAILED))
    row: list[Any] = [design, record, len(ok), failed]
    for name in REDUCED:
        values = columns.get(f"{REDUCTION}.{name}", np.full(len(columns[OUTCOME]), np.nan))[ok]
        row += [_stat(values, "median"), _stat(values, "min"), _stat(values, "max")]
    force = columns.get(f"{CONTROLLED}.{FORCE}", np.full(len(columns[OUTCOME]), np.nan))[ok]
    return row + [_stat(force, "median"), _stat(force, "max")]


def reduction_by_design(columns: Columns, grid_keys: Sequence[str]) -> ValueTable:
    """Median, min (the worst case) and max % reduction of each response per design, per record and over all records."""
    header = ["design", "record", "cases", "failed"]
    reductions = [f"{heading} {how} %" for heading in REDUCED.values() for how in ("median", "min", "max")]
    header += reductions
    header += ["force median % W", "force max % W"]
    designs = groups(design_labels(columns, grid_keys))
    records = groups(columns["record"])
    rows = []
    for design, design_rows in designs.items():
        if design.split(",")[0] == "none":
            continue
        for record, record_rows in records.items():
            rows.append(_summary_row(columns, np.intersect1d(design_rows, record_rows), design, record))
        if len(records) > 1:
            rows.append(_summary_row(columns, design_rows, design, ALL))
    return ValueTable("% reduction against the passive case, per design and record (min: the worst case; negative: the "
                 "response grew)", header, rows, frozenset(reductions))


def peak_names(columns: Columns) -> list[str]:
    """The flattened peak names present for the controlled case (or the passive one)."""
    prefix = f"{CONTROLLED}." if any(name.startswith(f"{CONTROLLED}.") for name in columns) else f"{PASSIVE}."
    return [name[len(prefix):] for name in columns if name.startswith(prefix)]


def peaks_by_design(columns: Columns, grid_keys: Sequence[str]) -> ValueTable:
    """Median peak responses per design (controlled), beside the passive case's: the Table 2 layout."""
    names = peak_names(columns)
    ok = ok_rows(columns)
    header = ["design", "cases"] + names
    rows = []
    passive = passive_rows(columns)
    rows.append(["passive", len(passive)] + [_stat(columns[f"{PASSIVE}.{n}"][passive], "median") for n in names])
    for design, design_rows in groups(design_labels(columns, grid_keys)).items():
        chosen = design_rows[ok[design_rows]]
        if design.split(",")[0] == "none":
            continue
        rows.append([design, len(chosen)] + [_stat(columns.get(f"{CONTROLLED}.{n}", np.full(len(ok), np.nan))[chosen], "median")
                                             for n in names])
    return ValueTable("median peak responses (SI; force in % of the weight)", header, rows)
