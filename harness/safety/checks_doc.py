"""The safety table of docs/SAFETY.md: one record per check, built from the checks' own class attributes.

The records come from :data:`harness.safety.checks.CHECKS`, in bit order, so the table cannot
drift from the code (tests/unit/test_safety_doc.py compares docs/SAFETY.md with it). Actions
are the defaults; ``bus_error_frames``, ``bus_error_passive`` and ``force_tracking`` take theirs
from the configuration.
"""

from __future__ import annotations

from typing import NamedTuple

from harness.safety.checks import CHECKS_BY_BIT, Check
from harness.safety.events import Action


class SafetyRecord(NamedTuple):
    """One row of the safety table."""

    name: str
    detects: str
    bound: str
    action: str
    reset: str


def record_of(check: Check) -> SafetyRecord:
    """The row of one check: its name, what it detects, its bound, default action and reset."""
    kind = check.kind
    return SafetyRecord(kind.NAME, kind.DETECTS, kind.BOUND, Action(kind.ACTION).name.lower(), kind.RESET)


#: One record per check, in :data:`~harness.safety.checks.CHECK_NAMES` (bit) order.
SAFETY_TABLE: tuple[SafetyRecord, ...] = tuple(record_of(check) for check in CHECKS_BY_BIT)
