"""A titled table of text cells rendered for a terminal of a given width, for HTML and for CSV.

:class:`TextTable` holds cells already formatted. Its plain-text rendering never makes a line
longer than the width it is given: headings wrap onto several lines within their column, a
long text column (an event's detail) wraps within its cells, and when the value columns still
do not fit they are split into blocks, each repeating the leading key columns (the quantity
and its unit), so no column ever lands on a line of its own. :meth:`TextTable.to_rich` renders
the same blocks as rich tables for the console: a cell is never cut to an ellipsis, it
wraps. The peak tables (:class:`~harness.report.peak_table.PeakTable`), the report's
context tables and the sweep's summary tables (the cells of a
:class:`~harness.sweep.summary.ValueTable`) render through it.
"""

from __future__ import annotations

import csv
import io
import textwrap
from collections.abc import Sequence
from dataclasses import dataclass
from html import escape

from rich import box
from rich.console import Group
from rich.table import Table
from rich.text import Text

#: Width a heading may take before it wraps, unless its column's cells are wider (characters).
HEADING_WIDTH = 12
#: Narrowest a wrapped text column gets (characters).
MIN_TEXT_WIDTH = 24
#: Space between two columns.
GAP = "  "
#: Width of the plain text when none is given (summary.txt): wide enough for any peak table.
UNLIMITED = 10_000
#: What a column adds to a rich table's width besides its cells: one space of padding on each
#: side and one of the (blank) rule between columns; the table's edges give back the last one.
RICH_GAP = 3


@dataclass(frozen=True)
class TextTable:
    """Rows of text cells under headings, with a title and a note.

    Attributes
    ----------
    title : str
    headings : tuple of str
    rows : tuple of tuple of str
        One cell per heading.
    note : str
        A paragraph under the table.
    key_columns : int
        Leading columns repeated in every block when the table is split (e.g. quantity, unit).
    numeric : tuple of bool
        Per column, True to right-align (numbers); default: every column after the key columns.
    """

    title: str
    headings: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""
    key_columns: int = 1
    numeric: tuple[bool, ...] | None = None

    def _numeric(self) -> tuple[bool, ...]:
        if self.numeric is not None:
            return self.numeric
        return tuple(i >= self.key_columns for i in range(len(self.headings)))

    def _widths(self, wrap_headings: bool) -> list[int]:
        """Each column's width: its widest cell and its heading (its longest word, up to HEADING_WIDTH, if wrapped)."""
        widths = []
        for i, heading in enumerate(self.headings):
            cells = max((len(row[i]) for row in self.rows), default=0)
            longest_word = max((len(word) for word in heading.split()), default=0)
            shown = min(len(heading), HEADING_WIDTH) if wrap_headings else len(heading)
            widths.append(max(cells, longest_word, shown))
        return widths

    def to_text(self, width: int | None = None) -> str:
        """Fixed-width text no line of which is longer than ``width`` characters (None: no limit).

        Parameters
        ----------
        width : int, optional
            The terminal's width in columns; None keeps every heading on one line and every column in one block.
        """
        limit = width or UNLIMITED
        widths = self._widths(wrap_headings=width is not None)
        widths = _fit_text_column(widths, self._numeric(), self.key_columns, limit)
        lines = [*textwrap.wrap(self.title, limit), "=" * min(len(self.title), limit)]
        for number, block in enumerate(_blocks(widths, self.key_columns, limit)):
            lines += ([""] if number else []) + self._block_lines(block, widths)
        if self.note:
            lines += textwrap.wrap(self.note, limit)
        return "\n".join(lines)

    def to_rich(self, width: int | None = None) -> Group:
        """Rich tables for the console, each no wider than ``width`` columns (None: one table, any width).

        Headings stay on one line when the whole table fits; otherwise they wrap within their
        columns and the value columns that still do not fit go to further tables, each
        repeating the key columns, as in :meth:`to_text`. Every cell wraps rather than being
        cut: no figure is ever lost to an ellipsis.
        """
        limit = (width or UNLIMITED) + 1  # the edges give back one column (RICH_GAP)
        numeric = self._numeric()
        widths = self._widths(wrap_headings=False)
        if sum(widths) + RICH_GAP * len(widths) > limit:
            widths = _fit_text_column(self._widths(wrap_headings=True), numeric, self.key_columns, limit, RICH_GAP)
        blocks = _blocks(widths, self.key_columns, limit, RICH_GAP)
        tables = []
        for number, block in enumerate(blocks):
            last = number == len(blocks) - 1
            table = Table(title=Text(self.title) if number == 0 else None, title_justify="left",
                          caption=Text(self.note) if last and self.note else None, caption_justify="left",
                          box=box.SIMPLE_HEAVY, pad_edge=False)
            for i in block:
                heading = "\n".join(textwrap.wrap(self.headings[i], widths[i])) or self.headings[i]
                table.add_column(Text(heading), justify="right" if numeric[i] else "left", overflow="fold",
                                 style="bold" if i == 0 else None)
            for row in self.rows:
                table.add_row(*(Text(row[i]) for i in block))
            tables.append(table)
        return Group(*tables)

    def _block_lines(self, columns: list[int], widths: list[int]) -> list[str]:
        numeric = self._numeric()
        heading_lines = [textwrap.wrap(self.headings[i], widths[i]) or [""] for i in columns]
        depth = max(len(lines) for lines in heading_lines)
        lines = []
        for level in range(depth):
            cells = [lines_[level] if level < len(lines_) else "" for lines_ in heading_lines]
            lines.append(_line(cells, [widths[i] for i in columns], [numeric[i] for i in columns]))
        lines.append(GAP.join("-" * widths[i] for i in columns))
        for row in self.rows:
            wrapped = [textwrap.wrap(row[i], widths[i]) or [""] if len(row[i]) > widths[i] else [row[i]] for i in columns]
            for level in range(max(len(cell) for cell in wrapped)):
                cells = [cell[level] if level < len(cell) else "" for cell in wrapped]
                lines.append(_line(cells, [widths[i] for i in columns], [numeric[i] for i in columns]))
        return lines

    def to_html(self, level: int = 2) -> str:
        """An ``<h{level}>`` title, the ``<table>`` (numbers in ``td.num``) and the note, escaped."""
        numeric = self._numeric()
        head = "<tr>" + "".join(f"<th>{escape(h)}</th>" for h in self.headings) + "</tr>"
        body = "".join(
            "<tr>" + "".join(f"<td class='num'>{escape(c)}</td>" if numeric[i] else f"<td>{escape(c)}</td>"
                             for i, c in enumerate(row)) + "</tr>"
            for row in self.rows
        )
        note = f"<p class='note'>{escape(self.note)}</p>" if self.note else ""
        return f"<h{level}>{escape(self.title)}</h{level}><table>{head}{body}</table>{note}"

    def to_csv(self) -> str:
        """The headings and cells as CSV text."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.headings)
        writer.writerows(self.rows)
        return buffer.getvalue()


def _line(cells: Sequence[str], widths: Sequence[int], numeric: Sequence[bool]) -> str:
    text = GAP.join(cell.rjust(w) if right else cell.ljust(w) for cell, w, right in zip(cells, widths, numeric, strict=True))
    return text.rstrip()


def _fit_text_column(widths: list[int], numeric: tuple[bool, ...], keys: int, limit: int, gap: int = len(GAP)) -> list[int]:
    """Narrow the widest left-aligned column after the keys (a free-text column) until a block fits."""
    total = sum(widths) + gap * (len(widths) - 1)
    text_columns = [i for i in range(keys, len(widths)) if not numeric[i]]
    if total <= limit or not text_columns:
        return widths
    widest = max(text_columns, key=lambda i: widths[i])
    fitted = list(widths)
    fitted[widest] = max(MIN_TEXT_WIDTH, widths[widest] - (total - limit))
    return fitted


def _blocks(widths: list[int], keys: int, limit: int, gap: int = len(GAP)) -> list[list[int]]:
    """Column indices of each block: the key columns, then as many value columns as fit in ``limit``.

    ``gap`` is what each column adds besides its cells (the space between two columns).
    """
    key_columns = list(range(min(keys, len(widths))))
    base = sum(widths[i] for i in key_columns) + gap * len(key_columns)
    blocks: list[list[int]] = []
    current: list[int] = []
    used = base
    for i in range(len(key_columns), len(widths)):
        needed = widths[i] + gap
        if current and used + needed - gap > limit:
            blocks.append(key_columns + current)
            current, used = [], base
        current.append(i)
        used += needed
    if current or not blocks:
        blocks.append(key_columns + current)
    return blocks
