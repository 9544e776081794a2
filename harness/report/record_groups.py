"""The runs of a report grouped by record, for the plots that draw time histories.

Time histories of different records share no time axis: overlaid, they only hide one another.
:func:`record_groups` gives one :class:`RecordGroup` per record, in the runs' order, and each
plot draws one panel (or block of panels) per group. A batch (``harness simulate --record
a,b --controller X,Y --out``) holds the same passive case once per controller; a group keeps
it once (passive runs of one record whose signals are identical are one). A controlled
run keeps its colour from record to record (``OF`` is blue on every panel), passive runs are
grey, and legends name the runs without the record (the panel's title says it).

With a single record the groups are one, titled by nothing, and runs keep their full labels.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

import numpy as np

from harness.recording.reader import RunData
from harness.report.figure import PASSIVE_SHADES, RUN_COLOURS


@dataclass(frozen=True)
class RecordGroup:
    """The runs of one record as a plot draws them.

    Attributes
    ----------
    record : str or None
        The record's name; None when the runs name none.
    runs : tuple of RunData
        The runs of the record, identical passive runs once.
    colours : tuple of str
        One colour per run.
    labels : tuple of str
        One legend text per run.
    grouped : bool
        Whether the report has several records (then each group gets its own panel and title).
    """

    record: str | None
    runs: tuple[RunData, ...]
    colours: tuple[str, ...]
    labels: tuple[str, ...]
    grouped: bool

    @property
    def title(self) -> str:
        """The panel title of the group: the record (empty for a report of one record)."""
        if not self.grouped:
            return ""
        return f"record {self.record}" if self.record else "runs that name no record"

    def members(self) -> Iterator[tuple[RunData, str, str]]:
        """``(run, colour, label)`` of each run."""
        return zip(self.runs, self.colours, self.labels, strict=True)

    def having(self, keep: Sequence[bool]) -> RecordGroup:
        """The group with only the runs where ``keep`` is true."""
        chosen = [i for i, flag in enumerate(keep) if flag]
        return RecordGroup(self.record, tuple(self.runs[i] for i in chosen), tuple(self.colours[i] for i in chosen),
                           tuple(self.labels[i] for i in chosen), self.grouped)


def same_signals(first: RunData, second: RunData) -> bool:
    """Whether two runs recorded the same columns with the same values (NaN equal to NaN)."""
    if set(first.signals) != set(second.signals):
        return False
    return all(np.array_equal(first.signals[name], second.signals[name], equal_nan=True) for name in first.signals)


def _without(label: str, record: str | None, folder: str | None) -> str:
    """``label`` without the record's name and, for a passive run drawn for several, its folder."""
    text = label
    if folder is not None and text.endswith(f" ({folder})"):
        text = text[: -len(folder) - 3]
    if record:
        text = re.sub(rf"(?<![\w:.-]){re.escape(record)}(?![\w:.-])", "", text)
    return " ".join(text.split()) or label


def _distinct_runs(runs: Sequence[RunData]) -> tuple[list[RunData], set[int]]:
    """The runs with each identical passive run of a record once; the ids of the passives kept for several."""
    kept: list[RunData] = []
    shared: set[int] = set()
    for run in runs:
        twin = next((other for other in kept if run.is_passive and other.is_passive
                     and other.record_name == run.record_name and same_signals(other, run)), None)
        if twin is None:
            kept.append(run)
        else:
            shared.add(id(twin))
    return kept, shared


def record_groups(runs: Sequence[RunData]) -> list[RecordGroup]:
    """One group per record, in the order the runs first name it (see the module docstring)."""
    kept, shared = _distinct_runs(runs)
    records = list(dict.fromkeys(run.record_name for run in kept))
    grouped = len(records) > 1
    keys: dict[str, int] = {}
    groups = []
    for record in records:
        mine = [run for run in kept if run.record_name == record]
        labels, colours = [], []
        passive = 0
        for run in mine:
            folder = run.path.parent.name if id(run) in shared else None
            label = _without(run.label, record if grouped else None, folder)
            labels.append(label)
            if run.is_passive:
                colours.append(PASSIVE_SHADES[passive % len(PASSIVE_SHADES)])
                passive += 1
            else:
                colours.append(RUN_COLOURS[keys.setdefault(label, len(keys)) % len(RUN_COLOURS)])
        groups.append(RecordGroup(record, tuple(mine), tuple(colours), tuple(labels), grouped))
    return groups
