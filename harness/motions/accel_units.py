"""Acceleration units of record files: names, aliases and the factor to m/s^2.

A record file states its unit in a column header (``accel_g``, ``acc_m_s2``,
``acc [cm/s^2]``) or the caller states it (``accel_unit="gal"``). Nothing here
guesses a unit from the size of the numbers.
"""

from __future__ import annotations

import re

from harness.errors import RecordError

#: Standard gravity (m/s^2), the ``g`` of every record format (1 g = 980.665 cm/s^2).
G_M_S2 = 9.80665

#: Canonical unit name -> factor to m/s^2.
ACCEL_UNITS: dict[str, float] = {
    "g": G_M_S2,
    "m/s^2": 1.0,
    "cm/s^2": 1e-2,
    "mm/s^2": 1e-3,
}

_ALIASES: dict[str, str] = {
    "g": "g",
    "gs": "g",
    "m/s^2": "m/s^2",
    "m/s2": "m/s^2",
    "m_s2": "m/s^2",
    "m_s^2": "m/s^2",
    "m/s/s": "m/s^2",
    "ms^-2": "m/s^2",
    "ms-2": "m/s^2",
    "mps2": "m/s^2",
    "cm/s^2": "cm/s^2",
    "cm/s2": "cm/s^2",
    "cm_s2": "cm/s^2",
    "cm_s^2": "cm/s^2",
    "cm/s/s": "cm/s^2",
    "gal": "cm/s^2",
    "gals": "cm/s^2",
    "mm/s^2": "mm/s^2",
    "mm/s2": "mm/s^2",
    "mm_s2": "mm/s^2",
    "mm_s^2": "mm/s^2",
}

_TIME_UNITS: dict[str, float] = {"s": 1.0, "sec": 1.0, "ms": 1e-3}

def normalize_accel_unit(text: str) -> str:
    """Return the canonical name (a key of :data:`ACCEL_UNITS`) of an acceleration unit.

    Parameters
    ----------
    text : str
        For example ``"g"``, ``"m/s^2"``, ``"m_s2"``, ``"gal"``, ``"cm/s^2"``.

    Raises
    ------
    RecordError
        If the unit is not an acceleration unit this module knows.
    """
    key = text.strip().lower().replace(" ", "").replace("**", "^").replace("²", "^2")
    if key in _ALIASES:
        return _ALIASES[key]
    known = ", ".join(repr(u) for u in ACCEL_UNITS) + " (also 'gal')"
    raise RecordError(f"unknown acceleration unit {text!r}; expected one of {known}")


def accel_factor(unit: str) -> float:
    """Factor that turns a value in ``unit`` into m/s^2 (``unit`` may be an alias)."""
    return ACCEL_UNITS[normalize_accel_unit(unit)]


def split_column_name(name: str) -> tuple[str, str]:
    """Split a column header such as ``accel_g`` or ``time (s)`` into (base, unit).

    The unit part is ``""`` when the header gives none (``t``, ``acc``).
    """
    cleaned = name.strip().strip('"').strip("'")
    base_match = re.match(r"^([A-Za-z]+)(.*)$", cleaned)
    if not base_match:
        return cleaned.lower(), ""
    base, rest = base_match.group(1), base_match.group(2)
    rest = rest.strip().lstrip("_.- ").strip()
    if rest.startswith(("[", "(")) and rest.endswith(("]", ")")):
        rest = rest[1:-1].strip()
    return base.lower(), rest


def time_factor(unit: str) -> float | None:
    """Factor that turns a time in ``unit`` (``s``, ``sec``, ``ms``) into seconds, or None if unknown."""
    return _TIME_UNITS.get(unit.strip().lower())
