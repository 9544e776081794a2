"""The summary of a batch study (``harness simulate --record a,b --controller X,Y``): the source's tables.

Two :class:`~harness.report.peak_table.PeakTable`:

- :func:`peaks_per_record`: per record, the passive peaks and each controller's (one column each);
- :func:`reduction_summary`: per controller, the mean, the smallest (the worst case: where a
  response grew most, e.g. the sliding displacement) and the largest percent reduction
  ``(passive - hybrid) / passive`` over the records (SPEC 5), quantity by quantity.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from harness.report.peak_table import PERCENT_DIGITS, PeakRow, PeakTable
from harness.report.quantities import REPORT_WORDING, Quantity, response_quantities
from harness.signals.peaks import Peaks

#: The statistics over the records of each controller's reductions, in column order.
STATISTICS = ("mean", "min", "max")


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
    """The comparable reductions of ``quantity`` over ``cases`` (:meth:`Quantity.reduction`)."""
    values = [quantity.reduction(case.passive, case.controlled) for case in cases]
    return [value for value in values if value is not None]


def _statistics(found: list[float]) -> list[float | None]:
    """Mean, min (the worst case) and max of ``found``, in :data:`STATISTICS` order; None each when empty."""
    if not found:
        return [None] * len(STATISTICS)
    return [float(np.mean(found)), float(np.min(found)), float(np.max(found))]


def reduction_summary(cases: Sequence[BatchCase]) -> PeakTable:
    """Per controller, the mean, the smallest (worst case) and the largest percent reduction over the records."""
    controllers = _controllers(cases)
    records = _records(cases)
    rows = []
    for quantity in _quantities(cases):
        cells: list[float | None] = []
        for controller in controllers:
            cells += _statistics(_reductions(quantity, [case for case in cases if case.controller == controller]))
        if any(cell is not None for cell in cells):
            rows.append(PeakRow(quantity.key, quantity.label, "%", PERCENT_DIGITS, tuple(cells)))
    columns = tuple(f"{controller} {which}" for controller in controllers for which in STATISTICS)
    title = f"Reduction (%) per controller over {len(records)} record{'s' if len(records) != 1 else ''}"
    note = (f"reduction = (passive - hybrid) / passive, per record ({', '.join(records)}); mean, min (the worst "
            "case; negative: the response grew) and max over them.")
    return PeakTable(title, _headings(), columns, tuple(rows), (PERCENT_DIGITS,) * len(columns), note,
                     reduction_columns=tuple(range(len(columns))))


def batch_tables(cases: Sequence[BatchCase]) -> list[PeakTable]:
    """The per-record peaks and the per-controller reduction summary."""
    return [peaks_per_record(cases), reduction_summary(cases)]
