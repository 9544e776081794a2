"""The one table type of peak responses, :class:`PeakTable`, and its renderings.

Rows are quantities (a label and a display unit), columns are cases (runs, simulated
cases) and derived columns (percent reduction, differences). Cells hold numbers in
display units (mm, m/s^2, %), None where absent, so tests and other tools read the
numbers, and each rendering formats them the same way: rich (the console), plain text,
HTML and CSV. The tables themselves are built in :mod:`harness.report.tables`.

A percent-reduction column (:attr:`PeakTable.reduction_columns`) shows :data:`NO_REDUCTION`
where it has no value: :func:`harness.signals.peaks.reduction_pct` found no comparable reference, or
:func:`without_reductions` took them out (a run that did not play its record). The CSV
leaves such a cell empty, as it does every absent value, so it stays a column of numbers.
"""

from __future__ import annotations

import csv
import io
from dataclasses import dataclass, replace
from html import escape

from rich.console import Group

from harness.report.text_table import TextTable

#: What an absent cell shows.
ABSENT = "-"
#: What a percent reduction shows where it means nothing (no comparable reference, a run that did not play its record).
NO_REDUCTION = "\u2014"
#: Decimals of a percent reduction or difference.
PERCENT_DIGITS = 1


def reduction_text(value: float | None, digits: int = PERCENT_DIGITS) -> str:
    """A percent reduction as every table shows it: ``digits`` decimals, or :data:`NO_REDUCTION` for None."""
    return NO_REDUCTION if value is None else f"{value:.{digits}f}"


@dataclass(frozen=True)
class PeakRow:
    """One quantity's cells.

    Attributes
    ----------
    key : str
        Quantity key (see :class:`harness.report.quantities.Quantity`).
    label : str
        Quantity label.
    unit : str
        Display unit of the peak values.
    digits : int
        Decimals of the quantity's values.
    values : tuple of (float or None)
        One cell per table column, in display units (percent columns in %).
    """

    key: str
    label: str
    unit: str
    digits: int
    values: tuple[float | None, ...]

    def value(self, column: int) -> float | None:
        """Cell ``column``."""
        return self.values[column]


@dataclass(frozen=True)
class PeakTable:
    """A titled table of quantities (rows) against cases and derived values (columns).

    Attributes
    ----------
    title : str
    headings : tuple of (str, str)
        Headings of the quantity and unit columns (``("Quantity", "Unit")``).
    columns : tuple of str
        Headings of the value columns, after the quantity and unit.
    rows : tuple of PeakRow
    digits : tuple of (int or None)
        Decimals per value column; None: the row's own.
    note : str
        One line under the table (sources, definitions).
    reduction_columns : tuple of int
        The value columns that hold percent reductions (shown by :func:`reduction_text`).
    """

    title: str
    headings: tuple[str, str]
    columns: tuple[str, ...]
    rows: tuple[PeakRow, ...]
    digits: tuple[int | None, ...]
    note: str = ""
    reduction_columns: tuple[int, ...] = ()

    def row(self, key: str) -> PeakRow:
        """The row of quantity ``key``."""
        for row in self.rows:
            if row.key == key:
                return row
        raise KeyError(f"table {self.title!r} has no row {key!r}; it has {', '.join(r.key for r in self.rows)}")

    def cell_text(self, row: PeakRow, column: int) -> str:
        """Cell ``column`` of ``row``, formatted (:data:`ABSENT` when absent, :data:`NO_REDUCTION` for a reduction)."""
        value = row.values[column]
        digits = self.digits[column]
        if column in self.reduction_columns:
            return reduction_text(value, PERCENT_DIGITS if digits is None else digits)
        if value is None:
            return ABSENT
        return f"{value:.{row.digits if digits is None else digits}f}"

    def cells(self, row: PeakRow) -> list[str]:
        """Label, unit, then every formatted cell of ``row``."""
        return [row.label, row.unit, *(self.cell_text(row, i) for i in range(len(self.columns)))]

    def to_rich(self, width: int | None = None) -> Group:
        """Rich tables for the console, no wider than ``width`` columns (the note as the last one's caption).

        Value columns that do not fit go to further tables, each repeating the quantity and
        unit; a cell wraps rather than being cut (:meth:`TextTable.to_rich`).
        """
        return self.text_table().to_rich(width)

    def text_table(self) -> TextTable:
        """The formatted cells as a :class:`~harness.report.text_table.TextTable` (quantity and unit are its keys)."""
        return TextTable(self.title, (*self.headings, *self.columns), tuple(tuple(self.cells(row)) for row in self.rows),
                         self.note, key_columns=2)

    def to_text(self, width: int | None = None) -> str:
        """Fixed-width plain text no wider than ``width`` columns (None: one block, any width).

        Headings wrap within their columns; value columns that do not fit go to further
        blocks, each repeating the quantity and unit columns.
        """
        return self.text_table().to_text(width)

    def to_html(self) -> str:
        """An HTML ``<h2>`` title, ``<table>`` and note (escaped; numbers in ``td.num``)."""
        head = "<tr>" + "".join(f"<th>{escape(h)}</th>" for h in (*self.headings, *self.columns)) + "</tr>"
        body = []
        for row in self.rows:
            label, unit, *texts = self.cells(row)
            numbers = "".join(f"<td class='num'>{escape(text)}</td>" for text in texts)
            body.append(f"<tr><td>{escape(label)}</td><td>{escape(unit)}</td>{numbers}</tr>")
        note = f"<p class='note'>{escape(self.note)}</p>" if self.note else ""
        return f"<h2>{escape(self.title)}</h2><table>{head}{''.join(body)}</table>{note}"

    def to_csv(self) -> str:
        """CSV text: quantity, key, unit, then one column per value column (full precision, empty = absent)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(["quantity", "key", "unit", *self.columns])
        for row in self.rows:
            writer.writerow([row.label, row.key, row.unit, *("" if v is None else repr(float(v)) for v in row.values)])
        return buffer.getvalue()


def without_reductions(table: PeakTable, reason: str) -> PeakTable:
    """``table`` with every percent reduction taken out (shown as :data:`NO_REDUCTION`) and ``reason`` in its note.

    For a run whose reductions must not be read as the controller's (its table did not
    follow the record it was told): the peaks stay, the reductions go.
    """
    rows = tuple(replace(row, values=tuple(None if i in table.reduction_columns else value
                                           for i, value in enumerate(row.values))) for row in table.rows)
    note = f"{table.note} No reductions: {reason}".strip() if table.reduction_columns else table.note
    return replace(table, rows=rows, note=note)
