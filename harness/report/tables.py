"""The peak tables people read, each a :class:`~harness.report.peak_table.PeakTable`.

From peaks (the console of ``harness simulate`` and ``harness dry-run``):

- :func:`reduction_table`: passive beside controlled, with the percent reduction
  ``(passive - hybrid) / passive`` (SPEC 5), or the passive case alone.

From run folders (``harness report``), hiding quantities no run has:

- :func:`runs_table`: every run side by side (one column per run);
- :func:`pair_table`: passive against controlled, with the percent reduction beside the
  controlled value;
- :func:`comparison_table`: two runs of the same record (e.g. the table run against its
  simulation): both peaks, their difference and the difference in percent.

Reductions are computed from the SI peaks, differences from the displayed values.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

from harness.recording.peaks import run_peaks
from harness.recording.reader import RunData
from harness.report.peak_table import PERCENT_DIGITS, PeakRow, PeakTable
from harness.report.quantities import (
    CONSOLE_WORDING,
    REPORT_WORDING,
    Quantity,
    Wording,
    report_quantities,
    response_quantities,
)
from harness.report.table_check import run_table_check
from harness.signals.peaks import Peaks, force_column, run_window


def _row(quantity: Quantity, values: Sequence[float | None]) -> PeakRow:
    return PeakRow(quantity.key, quantity.label, quantity.unit, quantity.digits, tuple(values))


def _reduction_row(quantity: Quantity, passive: Peaks, controlled: Peaks, withheld: bool = False) -> PeakRow:
    """Passive and controlled peaks (display units), then the percent reduction (None if not comparable or withheld)."""
    reduction = None if withheld else quantity.reduction(passive, controlled)
    return _row(quantity, (quantity.display_value(passive), quantity.display_value(controlled), reduction))


def _caveat(heading: str, note: str, withheld: str, flagged: str) -> tuple[str, str]:
    """The reduction column's heading and the table's note, with why its reductions are withheld or doubtful.

    ``withheld``: the reductions are not shown (the table did not play the told record); ``flagged``:
    they are shown, marked with ``*``, and doubtful (harness/report/table_check.py).
    """
    if withheld:
        return heading, f"Reductions not shown: {withheld}. {note}".strip()
    if flagged:
        return heading + "*", f"*Doubtful: {flagged}. {note}".strip()
    return heading, note


def _headings(wording: Wording) -> tuple[str, str]:
    return (wording.quantity_heading, wording.unit_heading)


def reduction_table(
    passive: Peaks, controlled: Peaks | None, title: str, labels: tuple[str, str] = ("passive", "controlled"),
    withheld: str = "", flagged: str = "",
) -> PeakTable:
    """The console's peak table: rows per story and for the base mat; passive, controlled and % reduction.

    Parameters
    ----------
    passive, controlled : Peaks
        The two cases' peaks; ``controlled`` may be None (then only the passive column).
    title : str
    labels : tuple of (str, str)
        Column headings of the two cases (e.g. ``("passive (sim.)", "dry run")``).
    withheld, flagged : str
        Why the reductions are not shown, or shown but doubtful ("": shown as they are;
        :class:`harness.report.table_check.TableCheck`).
    """
    quantities = response_quantities(passive.n_stories, CONSOLE_WORDING)
    if controlled is None:
        rows = tuple(_row(q, (q.display_value(passive),)) for q in quantities)
        return PeakTable(title, _headings(CONSOLE_WORDING), labels[:1], rows, (None,))
    rows = tuple(_reduction_row(q, passive, controlled, bool(withheld)) for q in quantities)
    heading, note = _caveat("reduction %", "", withheld, flagged)
    columns = (*labels, heading)
    return PeakTable(title, _headings(CONSOLE_WORDING), columns, rows, (None, None, PERCENT_DIGITS), note,
                     reduction_columns=(2,))


def in_console_wording(table: PeakTable) -> PeakTable:
    """``table`` (built in the report's wording, e.g. a batch's) with the console's headings, labels and units.

    A row keeps its numbers; its label and unit become the console's for the same quantity
    (:data:`CONSOLE_WORDING`), except a unit the row does not share with its quantity (a
    percent reduction stays in %).
    """
    stories = max((int(row.key[len("drift_"):]) for row in table.rows
                   if row.key.startswith("drift_") and row.key[len("drift_"):].isdigit()), default=0)
    report = {q.key: q for q in response_quantities(stories, REPORT_WORDING)}
    console = {q.key: q for q in response_quantities(stories, CONSOLE_WORDING)}
    rows = []
    for row in table.rows:
        source, target = report.get(row.key), console.get(row.key)
        if source is None or target is None:
            rows.append(row)
            continue
        unit = target.unit if row.unit == source.unit else row.unit
        rows.append(dataclasses.replace(row, label=target.label, unit=unit))
    return dataclasses.replace(table, headings=_headings(CONSOLE_WORDING), rows=tuple(rows))


def _stories(runs: Sequence[RunData]) -> int:
    return max((run.n_stories for run in runs), default=0)


def runs_table(runs: Sequence[RunData]) -> PeakTable:
    """Peaks of every run side by side (one column per run)."""
    peaks = [run_peaks(run) for run in runs]
    rows = tuple(_row(q, [q.display_value(p) for p in peaks]) for q in report_quantities(_stories(runs)))
    labels = tuple(run.label for run in runs)
    return PeakTable("Peak responses", _headings(REPORT_WORDING), labels, _drop_empty(rows), (None,) * len(runs),
                     _join(window_note(runs), _force_note(runs)))


def peaks_pair_table(
    passive: Peaks, controlled: Peaks, title: str, labels: tuple[str, str], note: str = "", withheld: str = "",
    flagged: str = "",
) -> PeakTable:
    """Passive against controlled peaks (report rows) with the percent reduction beside the controlled value.

    ``withheld`` / ``flagged``: why the reductions are not shown, or doubtful (see :func:`reduction_table`).
    """
    stories = max(passive.n_stories, controlled.n_stories)
    rows = tuple(_reduction_row(q, passive, controlled, bool(withheld)) for q in report_quantities(stories))
    heading, note = _caveat("reduction (%)", "reduction = (passive - hybrid) / passive. " + note, withheld, flagged)
    columns = (*labels, heading)
    return PeakTable(title, _headings(REPORT_WORDING), columns, _drop_empty(rows), (None, None, PERCENT_DIGITS),
                     note.strip(), reduction_columns=(2,))


def pair_table(passive: RunData, controlled: RunData) -> PeakTable:
    """Passive against controlled peaks with the percent reduction beside the controlled value.

    Withheld, or flagged, when the controlled run's table did not follow its record (harness/report/table_check.py).
    """
    first = passive.label if "passive" in passive.label else f"passive: {passive.label}"
    check = run_table_check(controlled.metadata)
    return peaks_pair_table(run_peaks(passive), run_peaks(controlled), f"Passive against controlled: {controlled.label}",
                            (first, controlled.label), _join(window_note((passive, controlled)), _force_note((controlled,))),
                            check.withheld, check.flagged)


def _difference_row(quantity: Quantity, first: Peaks, second: Peaks) -> PeakRow:
    """Both peaks (display units), ``second - first`` and that difference in percent of ``first``."""
    left, right = quantity.display_value(first), quantity.display_value(second)
    difference = None if left is None or right is None else right - left
    percent = None if difference is None or not left else 100.0 * difference / left
    return _row(quantity, (left, right, difference, percent))


def peaks_comparison_table(first: Peaks, second: Peaks, title: str, labels: tuple[str, str], note: str = "") -> PeakTable:
    """Both peaks (report rows), ``second - first`` and that difference in percent of ``first``."""
    stories = max(first.n_stories, second.n_stories)
    rows = tuple(_difference_row(q, first, second) for q in report_quantities(stories))
    columns = (*labels, "difference (B - A)", "difference (%)")
    return PeakTable(title, _headings(REPORT_WORDING), columns, _drop_empty(rows), (None, None, None, PERCENT_DIGITS),
                     note)


def comparison_table(first: RunData, second: RunData) -> PeakTable:
    """Both runs' peaks, ``second - first`` and that difference in percent of ``first``."""
    note = _join(f"A = {first.label} ({first.path}); B = {second.label} ({second.path}).",
                 window_note((first, second)), _force_note((first, second)))
    return peaks_comparison_table(run_peaks(first), run_peaks(second), f"Comparison: {first.label} against {second.label}",
                                  (f"A: {first.label}", f"B: {second.label}"), note)


def _drop_empty(rows: tuple[PeakRow, ...]) -> tuple[PeakRow, ...]:
    return tuple(row for row in rows if any(value is not None for value in row.values))


def _join(*notes: str) -> str:
    return " ".join(note for note in notes if note)


def window_note(runs: Sequence[RunData]) -> str:
    """Over which rows the runs' peaks were taken (:func:`harness.signals.peaks.run_window`), once when they share it."""
    windows = {run.label: run_window(run.metadata) for run in runs}
    texts = {label: window.describe() if window else "every row (no record in the metadata)"
             for label, window in windows.items()}
    if not texts:
        return ""
    if len(set(texts.values())) == 1:
        return f"Peaks {next(iter(texts.values()))}; rows after it are not compared."
    return "Peaks " + "; ".join(f"{text} ({label})" for label, text in texts.items()) + "; rows after it are not compared."


def _force_note(runs: Sequence[RunData]) -> str:
    """Which column each run's control force comes from (once when all runs share it), and missing weights."""
    sources = {run.label: force_column(run.signals) for run in runs if force_column(run.signals)}
    if not sources:
        return ""
    columns = set(sources.values())
    if len(columns) == 1:
        text = f"Control force from {columns.pop()}"
        text += " (every run)." if len(sources) > 1 else "."
    else:
        text = "Control force from " + "; ".join(f"{column} ({label})" for label, column in sources.items()) + "."
    unweighed = [run.label for run in runs if run.label in sources and not run.metadata.get("total_weight_N")]
    if unweighed:
        text += f" No total_weight_N in the metadata of {', '.join(unweighed)}: force in % of weight absent."
    return text
