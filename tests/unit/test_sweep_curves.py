"""Summary tables, IDA curves and the lognormal fragility fit of a sweep's rows."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from harness.report.peak_table import NO_REDUCTION
from harness.sweep.curves import design_curves, fit_lognormal, fragility
from harness.sweep.summary import SHORT_REDUCTION, design_labels, passive_rows, peaks_by_design, reduction_by_design


def test_the_fit_recovers_a_known_fragility():
    levels = np.array([0.1, 0.2, 0.3, 0.4, 0.6, 0.8])
    count = np.full(levels.size, 4000)
    exceeded = np.round(count * stats.norm.cdf(np.log(levels / 0.35) / 0.4)).astype(int)
    theta, beta, note = fit_lognormal(levels, exceeded, count)
    assert theta == pytest.approx(0.35, rel=0.01) and beta == pytest.approx(0.4, rel=0.02) and note == ""


def test_no_fit_without_the_data_for_one():
    assert fit_lognormal(np.array([0.1, 0.2]), np.array([0, 0]), np.array([5, 5]))[2] == "never exceeded"
    assert fit_lognormal(np.array([0.1, 0.2]), np.array([5, 5]), np.array([5, 5]))[2] == "always exceeded"
    assert fit_lognormal(np.array([0.1]), np.array([2]), np.array([5]))[2] == "one PGA level: no fit"


def test_exceedance_is_counted_per_level():
    pga = np.array([0.1, 0.1, 0.2, 0.2, 0.2, np.nan])
    peak = np.array([0.01, 0.09, 0.08, 0.09, np.nan, 1.0])
    curve = fragility("x", pga, peak, limit=0.075)
    assert list(curve.pga_g) == [0.1, 0.2] and list(curve.count) == [2, 2] and list(curve.exceeded) == [1, 2]


def _columns():
    """Two designs x two records x two levels; the passive case repeats across designs."""
    design = np.array(["FSF-I"] * 4 + ["OF-I"] * 4, dtype=object)
    record = np.array(["a", "a", "b", "b"] * 2, dtype=object)
    pga = np.array([0.1, 0.2] * 4)
    passive = np.array([0.02, 0.04, 0.03, 0.06] * 2)
    controlled = np.array([0.01, 0.02, 0.015, 0.03, 0.002, 0.004, 0.003, 0.006])
    return {
        "controller": design, "record": record, "pga_g": pga, "outcome": np.array(["ok"] * 8, dtype=object),
        "passive.max_drift_m": passive, "controlled.max_drift_m": controlled,
        "passive.sliding_displacement_m": passive, "controlled.sliding_displacement_m": controlled,
        "reduction_pct.max_drift_m": 100 * (passive - controlled) / passive,
        "controlled.peak_force_pct_weight": np.full(8, 5.0), "passive.peak_force_pct_weight": np.zeros(8),
    }


def test_summary_per_design_and_record():
    columns = _columns()
    table = reduction_by_design(columns, [])
    rows = {(row[0], row[1]): dict(zip(table.header, row, strict=True)) for row in table.rows}
    assert set(rows) == {("FSF-I", "a"), ("FSF-I", "b"), ("FSF-I", "all"), ("OF-I", "a"), ("OF-I", "b"), ("OF-I", "all")}
    assert rows[("FSF-I", "all")]["drift median %"] == pytest.approx(50.0)
    assert rows[("OF-I", "a")]["drift max %"] == pytest.approx(90.0) and rows[("OF-I", "all")]["cases"] == 4
    peaks = peaks_by_design(columns, [])
    assert peaks.rows[0][:2] == ["passive", 4], "the passive simulations are counted once, not once per design"
    assert len(passive_rows(columns)) == 4


def test_the_short_summary_shows_the_worst_growth_of_the_stroke_beside_the_largest_reduction():
    columns = _columns()
    growth = np.array([-10.0, 20.0, 5.0, -60.0, 30.0, 40.0, np.nan, np.nan])  # sliding: grew by 60 % once
    columns["reduction_pct.sliding_displacement_m"] = growth
    short = reduction_by_design(columns, []).select(SHORT_REDUCTION)
    rows = {(row[0], row[1]): dict(zip(short.header, row, strict=True)) for row in short.rows}
    assert rows[("FSF-I", "all")]["sliding max %"] == pytest.approx(20.0)
    assert rows[("FSF-I", "all")]["sliding min %"] == pytest.approx(-60.0)  # what "max %" alone hid
    assert rows[("FSF-I", "b")]["sliding min %"] == pytest.approx(-60.0)
    assert "-60" in short.to_markdown()
    # OF-I on record b has no comparable reference: no number, the table's mark for it
    cells = dict(zip(short.header, short.cells(short.rows[[r[:2] for r in short.rows].index(["OF-I", "b"])]), strict=True))
    assert cells["sliding min %"] == cells["sliding max %"] == NO_REDUCTION


def test_ida_curves_per_design_with_the_passive_case_first():
    columns = _columns()
    curves = design_curves(columns, design_labels(columns, []), "max_drift_m")
    assert [c.design for c in curves] == ["passive", "FSF-I", "OF-I"]
    assert list(curves[0].pga_g) == [0.1, 0.2] and curves[0].median[0] == pytest.approx(0.025)
    assert curves[2].median[1] == pytest.approx(0.005)
