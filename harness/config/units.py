"""Physical units for profile values.

A profile value is either a plain number, taken in the unit its key names
(``stroke_limit_m: 0.1``), or a string with its own unit (``"10 cm"``), which is
converted to that unit. A unit of the wrong kind (``"10 kg"`` for a length) is an
error that names both units.

Units are products and quotients of the base tokens below, for example
``kN/m``, ``kN*s/m``, ``s/cm``, ``m/s^2``, ``1/s``.
"""

from __future__ import annotations

import re

#: token -> (factor to SI, (kg, m, s) exponents)
_BASE_UNITS: dict[str, tuple[float, tuple[int, int, int]]] = {
    "1": (1.0, (0, 0, 0)),
    "rad": (1.0, (0, 0, 0)),
    "m": (1.0, (0, 1, 0)),
    "cm": (1e-2, (0, 1, 0)),
    "mm": (1e-3, (0, 1, 0)),
    "um": (1e-6, (0, 1, 0)),
    "µm": (1e-6, (0, 1, 0)),
    "in": (0.0254, (0, 1, 0)),
    "kg": (1.0, (1, 0, 0)),
    "t": (1e3, (1, 0, 0)),
    "s": (1.0, (0, 0, 1)),
    "ms": (1e-3, (0, 0, 1)),
    "us": (1e-6, (0, 0, 1)),
    "µs": (1e-6, (0, 0, 1)),
    "min": (60.0, (0, 0, 1)),
    "Hz": (1.0, (0, 0, -1)),
    "kHz": (1e3, (0, 0, -1)),
    "N": (1.0, (1, 1, -2)),
    "kN": (1e3, (1, 1, -2)),
    "MN": (1e6, (1, 1, -2)),
    "g": (9.80665, (0, 1, -2)),
    "gal": (1e-2, (0, 1, -2)),
    "Pa": (1.0, (1, -1, -2)),
    "kPa": (1e3, (1, -1, -2)),
    "MPa": (1e6, (1, -1, -2)),
    "bar": (1e5, (1, -1, -2)),
    "GPa": (1e9, (1, -1, -2)),
    "psi": (6894.757293168, (1, -1, -2)),
    "L": (1e-3, (0, 3, 0)),
}

_TOKEN = re.compile(r"^([A-Za-zµ1]+)(?:\^?(-?\d+))?$")
_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(.*?)\s*$")


class UnitError(ValueError):
    """A unit string that cannot be parsed or does not fit the expected kind."""


def parse_unit(unit: str) -> tuple[float, tuple[int, int, int]]:
    """Parse a unit expression into its SI factor and dimension.

    Parameters
    ----------
    unit : str
        For example ``"kN*s/m"``, ``"m/s^2"``, ``"1/s"``.

    Returns
    -------
    factor : float
        Multiply a value in ``unit`` by this to get SI.
    dimension : tuple of int
        Exponents of (kg, m, s).
    """
    text = unit.replace(" ", "").replace("·", "*")
    if not text:
        raise UnitError("empty unit")
    factor = 1.0
    dims = [0, 0, 0]
    parts = text.split("/")
    for index, part in enumerate(parts):
        sign = 1 if index == 0 else -1
        for token in filter(None, part.split("*")):
            match = _TOKEN.match(token)
            if not match or match.group(1) not in _BASE_UNITS:
                raise UnitError(f"unknown unit {token!r} in {unit!r}")
            base_factor, base_dims = _BASE_UNITS[match.group(1)]
            power = sign * int(match.group(2) or 1)
            factor *= base_factor**power
            for i in range(3):
                dims[i] += base_dims[i] * power
    return factor, (dims[0], dims[1], dims[2])


def convert(value: float, from_unit: str, to_unit: str) -> float:
    """Convert ``value`` from ``from_unit`` to ``to_unit``; raise UnitError if they differ in kind."""
    f_from, d_from = parse_unit(from_unit)
    f_to, d_to = parse_unit(to_unit)
    if d_from != d_to:
        raise UnitError(f"unit {from_unit!r} is not a unit of the same kind as {to_unit!r}")
    return value * f_from / f_to


def parse_quantity(text: str, to_unit: str) -> float:
    """Parse ``"0.012 cm"`` into a float in ``to_unit``.

    A bare number in a string (``"0.5"``) is taken in ``to_unit``.
    """
    match = _QUANTITY.match(text)
    if not match:
        raise UnitError(f"expected a number with a unit such as '1.5 {to_unit}', found {text!r}")
    number = float(match.group(1))
    unit = match.group(2)
    if not unit:
        return number
    return convert(number, unit, to_unit)
