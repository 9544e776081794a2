"""Signal column names of run folders: re-exported from :mod:`harness.rowlayout`, where they are defined.

The record package's public API (``harness.record.canonical_columns``, ``drift``,
``floor_acceleration``, ``unit_of``) and older imports of this module keep working; new
code imports :mod:`harness.rowlayout`, the one definition of every column's name, unit
and place.
"""

from __future__ import annotations

from harness.rowlayout import (
    BASE,
    BEARING,
    CONTROLLER,
    SLIDING,
    SUPERVISOR,
    TABLE,
    TIME,
    TIMING,
    canonical_columns,
    count_stories,
    drift,
    floor_acceleration,
    unit_of,
)

__all__ = [
    "BASE",
    "BEARING",
    "CONTROLLER",
    "SLIDING",
    "SUPERVISOR",
    "TABLE",
    "TIME",
    "TIMING",
    "canonical_columns",
    "count_stories",
    "drift",
    "floor_acceleration",
    "unit_of",
]
