"""Rounding times to the rig's grids (sub-steps, steps): half up, never banker's rounding.

Python's ``round`` sends 0.5 to 0 and 1.5 to 2; a delay of half a step must not
vanish on one grid and double on another, so the rig rounds halves up (a delay
is never shortened by more than half a grid interval, nor lengthened by more).
"""

from __future__ import annotations

import math

_EPS = 1e-9


def half_up(intervals: float) -> int:
    """``intervals`` rounded to a whole number, halves up (tolerant of float noise such as 2.9999999)."""
    return max(0, math.floor(intervals + 0.5 + _EPS))
