"""Peak-response tables built from run folders, and their plain-text form.

Three tables:

- :func:`peak_table`: every run side by side (one column per run);
- :func:`pair_table`: passive against controlled, with the percent reduction
  ``(passive - hybrid) / passive`` beside each controlled value (SPEC section 5);
- :func:`comparison_table`: two runs of the same record (e.g. the table run against
  its simulation): both peaks, their difference and the difference in percent.

Cells hold numbers in display units (mm, m/s^2, %), ``None`` where absent, so tests
and other tools read the numbers and :func:`table_text` / the HTML page format them.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence
from dataclasses import dataclass

from harness.record.reader import RunData
from harness.report.peaks import Quantity, force_column, quantities, reduction_percent, run_peaks


@dataclass(frozen=True)
class Row:
    """One quantity's cells.

    Attributes
    ----------
    key : str
        Quantity key (see :func:`harness.report.peaks.quantities`).
    label : str
        Quantity label.
    unit : str
        Display unit of the peak values.
    values : tuple of (float or None)
        One cell per table column, in display units (percent columns in %).
    """

    key: str
    label: str
    unit: str
    values: tuple[float | None, ...]

    def value(self, column: int) -> float | None:
        """Cell ``column``."""
        return self.values[column]


@dataclass(frozen=True)
class Table:
    """A titled table of quantities against columns.

    Attributes
    ----------
    title : str
    columns : tuple of str
        Column headings after the quantity and unit columns.
    rows : tuple of Row
    digits : tuple of int
        Decimals per column for the text form (-1: use the quantity's own).
    note : str
        One line under the table (sources, definitions).
    """

    title: str
    columns: tuple[str, ...]
    rows: tuple[Row, ...]
    digits: tuple[int, ...]
    note: str = ""

    def row(self, key: str) -> Row:
        """The row of quantity ``key``."""
        for row in self.rows:
            if row.key == key:
                return row
        raise KeyError(f"table {self.title!r} has no row {key!r}; it has {', '.join(r.key for r in self.rows)}")

    def cell_text(self, row: Row, column: int, quantity_digits: int) -> str:
        """Formatted cell (``"-"`` for absent)."""
        value = row.values[column]
        if value is None:
            return "-"
        digits = self.digits[column] if self.digits[column] >= 0 else quantity_digits
        return f"{value:.{digits}f}"


def _display(quantity: Quantity, value_si: float | None) -> float | None:
    return None if value_si is None else value_si * quantity.scale


def _stories(runs: Sequence[RunData]) -> int:
    return max((run.n_stories for run in runs), default=0)


def peak_table(runs: Sequence[RunData]) -> Table:
    """Peaks of every run side by side (one column per run)."""
    stories = _stories(runs)
    peaks = [run_peaks(run, stories) for run in runs]
    rows = tuple(
        Row(q.key, q.label, q.unit, tuple(_display(q, p[q.key]) for p in peaks)) for q in quantities(stories)
    )
    labels = tuple(run.label for run in runs)
    return Table("Peak responses", labels, _drop_empty(rows), (-1,) * len(runs), _force_note(runs))


def pair_table(passive: RunData, controlled: RunData) -> Table:
    """Passive against controlled peaks with the percent reduction beside the controlled value."""
    stories = _stories((passive, controlled))
    base, hybrid = run_peaks(passive, stories), run_peaks(controlled, stories)
    rows = []
    for q in quantities(stories):
        comparable = not (q.key.endswith("force_percent_weight") or q.key.startswith("table_"))
        reduction = reduction_percent(base[q.key], hybrid[q.key]) if comparable else None
        rows.append(Row(q.key, q.label, q.unit, (_display(q, base[q.key]), _display(q, hybrid[q.key]), reduction)))
    columns = (f"passive: {passive.label}", f"controlled: {controlled.label}", "reduction (%)")
    note = "reduction = (passive - hybrid) / passive. " + _force_note((controlled,))
    return Table("Passive against controlled", columns, _drop_empty(tuple(rows)), (-1, -1, 1), note)


def comparison_table(first: RunData, second: RunData) -> Table:
    """Both runs' peaks, ``second - first`` and that difference in percent of ``first``."""
    stories = _stories((first, second))
    a, b = run_peaks(first, stories), run_peaks(second, stories)
    rows = []
    for q in quantities(stories):
        left, right = _display(q, a[q.key]), _display(q, b[q.key])
        difference = None if left is None or right is None else right - left
        percent = None if difference is None or not left else 100.0 * difference / left
        rows.append(Row(q.key, q.label, q.unit, (left, right, difference, percent)))
    columns = (first.label, second.label, "difference (B - A)", "difference (%)")
    note = f"A = {first.label} ({first.path.name}); B = {second.label} ({second.path.name}). "
    note += _force_note((first, second))
    title = f"Comparison: {first.label} / {second.label}"
    return Table(title, columns, _drop_empty(tuple(rows)), (-1, -1, -1, 1), note)


def _drop_empty(rows: tuple[Row, ...]) -> tuple[Row, ...]:
    return tuple(row for row in rows if any(value is not None for value in row.values))


def _force_note(runs: Sequence[RunData]) -> str:
    parts = []
    for run in runs:
        column = force_column(run)
        weight = run.metadata.get("total_weight_N")
        if column:
            parts.append(f"{run.label}: force from {column}" + ("" if weight else " (no total_weight_N in metadata)"))
    return "; ".join(parts)


def table_text(table: Table) -> str:
    """Fixed-width plain text of ``table`` for the console."""
    digits = quantity_digits(table)
    header = ["Quantity", "Unit", *table.columns]
    body = [
        [row.label, row.unit, *(table.cell_text(row, i, digits.get(row.key, 3)) for i in range(len(table.columns)))]
        for row in table.rows
    ]
    widths = [max(len(line[i]) for line in [header, *body]) for i in range(len(header))]
    lines = [table.title, "=" * len(table.title)]
    lines.append(_text_line(header, widths))
    lines.append("  ".join("-" * w for w in widths))
    lines += [_text_line(line, widths) for line in body]
    if table.note:
        lines.append(table.note)
    return "\n".join(lines)


def table_csv(table: Table) -> str:
    """CSV text of ``table`` (quantity, unit, then one column per table column; full precision, empty = absent)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["quantity", "key", "unit", *table.columns])
    for row in table.rows:
        writer.writerow([row.label, row.key, row.unit, *("" if v is None else repr(float(v)) for v in row.values)])
    return buffer.getvalue()


def _text_line(cells: list[str], widths: list[int]) -> str:
    """Label columns left-aligned, number columns right-aligned."""
    return "  ".join(cell.ljust(w) if i < 2 else cell.rjust(w) for i, (cell, w) in enumerate(zip(cells, widths)))


def quantity_digits(table: Table) -> dict[str, int]:
    """Decimals of each row's quantity, for formatting."""
    return {q.key: q.digits for q in quantities(_max_story(table))}


def _max_story(table: Table) -> int:
    stories = [int(row.key.split("_")[1]) for row in table.rows if row.key.startswith("drift_")]
    return max(stories, default=0)
