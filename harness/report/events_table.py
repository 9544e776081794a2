"""A run's events and interlocks as tables: what happened when, and how long each safety check acted.

:func:`events_table` lists ``events.jsonl`` in time order, folding repeats of one interlock
into one row with a count and the first and last time. The force clamp's and the rate limit's
events say the demanded value and the limit; an interlock event with no detail of its own
(the stroke fade, the stopping ramp, runs recorded before those had one) gets what the check
does (:data:`harness.safety.SAFETY_TABLE`) and what the signals held at that tick: the
controller's force, the supervised command and the stroke.
:func:`interlocks_table` counts, from the ``interlock_flags`` column, the ticks and the time
each check acted.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from harness.recording.reader import RunData
from harness.report.drive_faults import fault_text
from harness.report.text_table import TextTable
from harness.safety import SAFETY_TABLE, bit, names_of

#: Rows of an events table at most; the rest are counted in its note.
MAX_EVENT_ROWS = 40
_DESCRIPTIONS = {record.name: f"{record.detects} ({record.action})" for record in SAFETY_TABLE}


@dataclass
class _EventRow:
    first_s: float | None
    last_s: float | None
    kind: str
    name: str
    count: int
    detail: str


def _signals_at(run: RunData, t_s: float) -> str:
    """The force and stroke the run recorded at loop time ``t_s`` (kN, mm); "" if unknown."""
    if not run.has("t_s") or run.n_rows == 0:
        return ""
    k = int(np.clip(np.searchsorted(run["t_s"], t_s), 0, run.n_rows - 1))
    parts = []
    for column, label, scale, unit in (("force_raw_N", "controller", 1e-3, "kN"),
                                       ("force_command_N", "command", 1e-3, "kN"),
                                       ("sliding_displacement_m", "x_b", 1e3, "mm")):
        if run.has(column) and np.isfinite(run[column][k]):
            parts.append(f"{label} {run[column][k] * scale:+.3f} {unit}")
    return "at this tick: " + ", ".join(parts) if parts else ""


def _detail_text(detail: Any) -> str:
    if detail is None or detail == "":
        return ""
    if isinstance(detail, Mapping):
        return ", ".join(f"{key} {value}" for key, value in detail.items())
    return str(detail)


def _describe(run: RunData, event: Mapping[str, Any]) -> str:
    """The event's own detail, else what its check does and the signals at that tick."""
    own = _detail_text(event.get("detail"))
    if own:
        return own
    name = str(event.get("name", ""))
    t_s = event.get("t_s")
    where = _signals_at(run, float(t_s)) if isinstance(t_s, (int, float)) else ""
    return "; ".join(filter(None, (_DESCRIPTIONS.get(name, ""), where)))


def _with_drive_fault(run: RunData, rows: list[_EventRow]) -> list[_EventRow]:
    """Name the servo's fault code (from can.log) in the rows of a ``drive_fault``."""
    mentions = [row for row in rows if row.name == "drive_fault" or "drive_fault" in row.detail]
    text = fault_text(run) if mentions else ""
    for row in mentions if text else ():
        row.detail = f"{row.detail}; {text} (ACTUATOR_STATUS fault_code in can.log)" if row.detail else text
    return rows


def _folded(run: RunData) -> list[_EventRow]:
    """Events in order; an interlock repeated later adds to its first row."""
    rows: list[_EventRow] = []
    by_interlock: dict[str, _EventRow] = {}
    for event in run.events:
        t_s = event.get("t_s")
        time = float(t_s) if isinstance(t_s, (int, float)) else None
        kind, name = str(event.get("kind", "")), str(event.get("name", ""))
        if kind == "interlock" and name in by_interlock:
            row = by_interlock[name]
            row.count += 1
            row.last_s = time if time is not None else row.last_s
            continue
        row = _EventRow(time, time, kind, name, 1, _describe(run, event))
        rows.append(row)
        if kind == "interlock":
            by_interlock[name] = row
    return _with_drive_fault(run, rows)


def _time_text(value: float | None) -> str:
    return "-" if value is None else f"{value:.3f}"


def events_table(run: RunData) -> TextTable | None:
    """The run's events in time order (interlock repeats folded into their first row); None without events."""
    rows = _folded(run)
    if not rows:
        return None
    shown = rows[:MAX_EVENT_ROWS]
    cells = tuple(
        (_time_text(row.first_s), row.kind, row.name, str(row.count),
         _time_text(row.last_s) if row.count > 1 else "", row.detail)
        for row in shown
    )
    note = "Times in loop time (s), the t_s column's clock. "
    if len(rows) > len(shown):
        note += f"{len(rows) - len(shown)} more rows in events.jsonl. "
    note += "An interlock acts from its first event; its later rising edges are counted in the same row."
    headings = ("t (s)", "Kind", "Name", "Count", "Last t (s)", "Detail")
    return TextTable(f"Events: {run.label}", headings, cells, note, key_columns=1,
                     numeric=(True, False, False, True, True, False))


def interlocks_table(run: RunData) -> TextTable | None:
    """Per safety check that acted: the ticks and the time it acted, its first and last tick (``interlock_flags``)."""
    if not run.has("interlock_flags", "t_s") or run.n_rows < 2:
        return None
    flags = np.nan_to_num(run["interlock_flags"]).astype(np.int64)
    acted = int(np.bitwise_or.reduce(flags)) if flags.size else 0
    if not acted:
        return None
    t = run["t_s"]
    period_s = float(np.median(np.diff(t)))
    rows = []
    for name in names_of(acted):
        ticks = np.flatnonzero(flags & bit(name))
        rows.append((name, str(ticks.size), f"{ticks.size * period_s:.3f}", f"{t[ticks[0]]:.3f}", f"{t[ticks[-1]]:.3f}",
                     _DESCRIPTIONS.get(name, "")))
    headings = ("Check", "Ticks acting", "Time acting (s)", "First (s)", "Last (s)", "What it does")
    note = "From the interlock_flags column (bit i = the i-th name of harness.safety.CHECK_NAMES; logs/README.md)."
    return TextTable(f"Interlocks that acted: {run.label}", headings, tuple(rows), note, key_columns=1,
                     numeric=(False, True, True, True, True, False))


def event_tables(runs: Sequence[RunData]) -> list[TextTable]:
    """The events and interlock tables of every run that has them."""
    tables: list[TextTable] = []
    for run in runs:
        tables += [table for table in (events_table(run), interlocks_table(run)) if table is not None]
    return tables
