"""The summary of a batch study (``harness simulate --record a,b --controller X,Y``): the source's tables.

Two :class:`~harness.report.peak_table.PeakTable`:

- :func:`peaks_per_record`: per record, the passive peaks and each controller's (one column each);
- :func:`reduction_summary`: per controller, the mean and the largest percent reduction
  ``(passive - hybrid) / passive`` over the records (SPEC 5), quantity by quantity.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from harness.peaks import Peaks, reduction_pct
from harness.report.peak_table import PeakRow, PeakTable
from harness.report.quantities import REPORT_WORDING, Quantity, response_quantities
from harness.report.tables import PERCENT_DIGITS


@dataclass(frozen=True)
class BatchCase:
    """One combination of a batch: its record, its controller, and both cases' peaks (SI)."""

    record: str
    controller: str
    passive: Peaks
    controlled: Peaks


def _records(cases: Sequence[BatchCase]) -> list[str]:
    return list(dict.fromkeys(case.record for case in cases))


def _controllers(cases: Sequence[BatchCase]) -> list[str]:
    return list(dict.fromkeys(case.controller for case in cases))


def _quantities(cases: Sequence[BatchCase]) -> list[Quantity]:
    return response_quantities(max((case.passive.n_stories for case in cases), default=0), REPORT_WORDING)


def _headings() -> tuple[str, str]:
    return (REPORT_WORDING.quantity_heading, REPORT_WORDING.unit_heading)


def peaks_per_record(cases: Sequence[BatchCase]) -> PeakTable:
    """Per record, the passive peaks then each controller's, in display units (one column each)."""
    columns: list[str] = []
    peaks: list[Peaks] = []
    for record in _records(cases):
        mine = [case for case in cases if case.record == record]
        columns.append(f"{record} passive")
        peaks.append(mine[0].passive)
        for case in mine:
            columns.append(f"{record} {case.controller}")
            peaks.append(case.controlled)
    rows = tuple(PeakRow(q.key, q.label, q.unit, q.digits, tuple(q.display_value(p) for p in peaks))
                 for q in _quantities(cases))
    return PeakTable("Peak responses per record", _headings(), tuple(columns), rows, (None,) * len(columns),
                     "Each record's passive case, then each controller's controlled case.")


def _reductions(quantity: Quantity, cases: Sequence[BatchCase]) -> list[float]:
    values = [reduction_pct(quantity.si_value(case.passive), quantity.si_value(case.controlled)) for case in cases]
    return [value for value in values if value is not None]


def reduction_summary(cases: Sequence[BatchCase]) -> PeakTable:
    """Per controller, the mean and the largest percent reduction over the records, quantity by quantity."""
    controllers = _controllers(cases)
    records = _records(cases)
    rows = []
    for quantity in _quantities(cases):
        cells: list[float | None] = []
        for controller in controllers:
            found = _reductions(quantity, [case for case in cases if case.controller == controller])
            usable = quantity.comparable and bool(found)
            cells += [float(np.mean(found)) if usable else None, float(np.max(found)) if usable else None]
        if any(cell is not None for cell in cells):
            rows.append(PeakRow(quantity.key, quantity.label, "%", PERCENT_DIGITS, tuple(cells)))
    columns = tuple(f"{controller} {which}" for controller in controllers for which in ("mean", "max"))
    title = f"Reduction (%) per controller over {len(records)} record{'s' if len(records) != 1 else ''}"
    note = f"reduction = (passive - hybrid) / passive, per record ({', '.join(records)}); mean and largest over them."
    return PeakTable(title, _headings(), columns, tuple(rows), (PERCENT_DIGITS,) * len(columns), note)


def batch_tables(cases: Sequence[BatchCase]) -> list[PeakTable]:
    """The per-record peaks and the per-controller reduction summary."""
    return [peaks_per_record(cases), reduction_summary(cases)]
