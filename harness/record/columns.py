"""Canonical signal column names for run folders, and the unit each name carries.

Every name ends in its unit (``_m``, ``_m_s``, ``_m_s2``, ``_N``, ``_s``) or is
dimensionless. Stories are numbered from 1 at the bottom (story 1 sits on the base
mat). A run may lack any column except ``t_s``.
"""

from __future__ import annotations

from typing import Final

TIME: Final = "t_s"

TABLE: Final[tuple[str, ...]] = ("table_displacement_m", "table_velocity_m_s", "table_acceleration_m_s2")
BASE: Final[tuple[str, ...]] = ("base_displacement_m", "base_velocity_m_s", "base_acceleration_m_s2")
SLIDING: Final[tuple[str, ...]] = ("sliding_displacement_m", "sliding_velocity_m_s")
BEARING: Final[tuple[str, ...]] = ("friction_force_N", "hysteretic_nu")
CONTROLLER: Final[tuple[str, ...]] = (
    "friction_estimate_N",
    "sliding_variable_m_s",
    "equivalent_force_N",
    "force_raw_N",
    "force_command_N",
    "force_measured_N",
)
SUPERVISOR: Final[tuple[str, ...]] = ("drive_enabled", "state", "interlock_flags")
TIMING: Final[tuple[str, ...]] = ("lateness_s", "compute_s", "overrun")

#: Suffix -> SI unit, longest suffix first so ``_m_s2`` wins over ``_m``.
_SUFFIX_UNITS: Final[tuple[tuple[str, str], ...]] = (
    ("_m_s2", "m/s^2"),
    ("_m_s", "m/s"),
    ("_m", "m"),
    ("_N", "N"),
    ("_s", "s"),
)


def drift(story: int) -> str:
    """Column name of story ``story``'s interstory drift (m), stories from 1."""
    return f"drift_{story}_m"


def floor_acceleration(floor: int) -> str:
    """Column name of floor ``floor``'s absolute acceleration (m/s^2), floors from 1."""
    return f"floor_acceleration_{floor}_m_s2"


def canonical_columns(n_stories: int, *, timing: bool = True) -> tuple[str, ...]:
    """All canonical columns for an ``n_stories`` building, in the recommended order.

    Parameters
    ----------
    n_stories : int
        Number of stories (>= 1).
    timing : bool
        Include the loop-timing columns (real-time runs).

    Returns
    -------
    tuple of str
    """
    if n_stories < 1:
        raise ValueError(f"found n_stories={n_stories}, expected at least 1")
    stories = tuple(drift(j) for j in range(1, n_stories + 1))
    floors = tuple(floor_acceleration(j) for j in range(1, n_stories + 1))
    names = (TIME, *TABLE, *BASE, *SLIDING, *stories, *floors, *BEARING, *CONTROLLER, *SUPERVISOR)
    return names + (TIMING if timing else ())


def count_stories(columns: tuple[str, ...] | list[str]) -> int:
    """Number of stories with a drift column: the largest ``j`` with ``drift_j_m`` present (0 if none)."""
    highest = 0
    for name in columns:
        if name.startswith("drift_") and name.endswith("_m"):
            middle = name[len("drift_") : -len("_m")]
            if middle.isdigit():
                highest = max(highest, int(middle))
    return highest


def unit_of(name: str) -> str:
    """SI unit a column name carries (``"1"`` for dimensionless names such as ``state``)."""
    for suffix, unit in _SUFFIX_UNITS:
        if name.endswith(suffix):
            return unit
    return "1"
