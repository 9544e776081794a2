"""Unit strings in profiles."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from harness.config.units import UnitError, convert, parse_quantity, parse_unit


@pytest.mark.parametrize(
    "text, unit, expected",
    [
        ("345.6 t", "kg", 345600.0),
        ("3.40e5 kN/m", "N/m", 3.40e8),
        ("490 kN*s/m", "N*s/m", 490e3),
        ("0.2 s/cm", "s/m", 20.0),
        ("2.29 s/in", "s/m", 2.29 / 0.0254),
        ("0.012 cm", "m", 1.2e-4),
        ("0.3 g", "m/s^2", 0.3 * 9.80665),
        ("250 Hz", "1/s", 250.0),
        ("4 ms", "s", 0.004),
        ("12", "m", 12.0),
    ],
)
def test_parse_quantity_converts(text, unit, expected):
    assert parse_quantity(text, unit) == pytest.approx(expected)


@pytest.mark.parametrize("text, unit", [("3 kg", "m"), ("1 s", "Hz"), ("2 N", "N/m")])
def test_wrong_kind_is_refused(text, unit):
    with pytest.raises(UnitError, match="not a unit of the same kind"):
        parse_quantity(text, unit)


@pytest.mark.parametrize("text", ["abc", "1 parsec", "", "m 3"])
def test_garbage_is_refused(text):
    with pytest.raises(UnitError):
        parse_quantity(text, "m")


@given(st.floats(min_value=-1e9, max_value=1e9, allow_nan=False), st.sampled_from(["mm", "cm", "in", "um"]))
def test_conversion_round_trip(value, unit):
    assert convert(convert(value, unit, "m"), "m", unit) == pytest.approx(value, rel=1e-12, abs=1e-12)


def test_dimensions_compose():
    assert parse_unit("kN*s/m")[1] == (1, 0, -1)
    assert parse_unit("m/s^2")[1] == (0, 1, -2)
