"""A record cut short: corrected whole, then brought to rest over its last second; a warning when it leaves much out.

The issue's case: ``harness records el_centro --duration 10`` (time scale 2, 0.34 g) had a PGD of
68.6 mm, where the same record's motion over its first 10 s peaks at 36.3 mm: the baseline
correction was fitted to the 10 s cut, which ends in strong shaking (16 % of the record's
Arias intensity comes after it).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from harness.cli import main
from harness.motions import load_raw, process_record, rule_residuals
from harness.motions.processing import ARIAS_WARNING_SHARE, CUT_STOP_S

TIME_SCALE, PGA_G = 2.0, 0.34


def _pgd_over(motion, seconds: float) -> float:
    return float(np.max(np.abs(motion.displacement_m[motion.t_s <= seconds + 1e-9])))


@pytest.fixture(scope="module")
def el_centro(records_dir: Path):
    raw = load_raw("el_centro", records_dir)
    return raw, process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE)


def test_a_10_s_cut_has_the_pgd_of_the_whole_records_first_10_s(el_centro) -> None:
    """Tolerance 1 %: before its last second the cut moves exactly as the whole corrected record
    (same PGA scaling: the PGA falls in the first 10 s); the stop can only add its bumps' motion,
    at most 0.2 % of the PGD on the three real records cut anywhere after 4 s."""
    raw, whole = el_centro
    cut = process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE, duration_s=10.0)
    assert cut.pgd_m == pytest.approx(_pgd_over(whole, 10.0), rel=0.01)  # 36.3 mm; it was 68.6 mm
    before_stop = cut.t_s < cut.duration_s - CUT_STOP_S
    np.testing.assert_allclose(cut.displacement_m[before_stop], whole.displacement_m[: cut.n_samples][before_stop],
                               rtol=0, atol=1e-9 * whole.pgd_m)


def test_the_motion_does_not_depend_on_where_the_cut_falls(el_centro) -> None:
    raw, _ = el_centro
    short, longer = (process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE, duration_s=d) for d in (8.0, 12.5))
    shared = int(np.count_nonzero(short.t_s < short.duration_s - CUT_STOP_S))
    np.testing.assert_allclose(short.accel_m_s2[:shared], longer.accel_m_s2[:shared], rtol=0, atol=1e-9 * PGA_G * 9.80665)
    np.testing.assert_allclose(short.displacement_m[:shared], longer.displacement_m[:shared], rtol=0,
                               atol=1e-9 * short.pgd_m)


@pytest.mark.parametrize("duration_s", [3.0, 7.3, 10.0, 14.0])
def test_the_tapered_end_is_at_rest_and_the_triple_exact(el_centro, duration_s: float) -> None:
    raw, _ = el_centro
    cut = process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE, duration_s=duration_s)
    assert cut.accel_m_s2[-1] == 0.0
    assert abs(cut.velocity_m_s[-1]) < 1e-9 * cut.pgv_m_s and abs(cut.displacement_m[-1]) < 1e-9 * cut.pgd_m
    rv, rx = rule_residuals(cut.accel_m_s2, cut.velocity_m_s, cut.displacement_m, cut.dt_s)
    assert np.max(np.abs(rv)) < 1e-12 * cut.pgv_m_s and np.max(np.abs(rx)) < 1e-12 * cut.pgd_m
    assert cut.pga_g == pytest.approx(PGA_G, rel=1e-9)
    stop = cut.t_s >= cut.duration_s - CUT_STOP_S
    ramp = np.abs(cut.accel_m_s2[stop])  # the taper: no step at the end, the acceleration fades to 0
    assert ramp[-5:].max() < 0.01 * PGA_G * 9.80665


def test_a_cut_that_leaves_out_much_of_the_shaking_is_warned_about_with_its_share(el_centro) -> None:
    raw, whole = el_centro
    cut = process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE, duration_s=10.0)
    assert cut.arias_left_out == pytest.approx(0.160, abs=0.005)
    assert len(cut.warnings) == 1 and "leaves out 16 % of the record's Arias intensity" in cut.warnings[0]
    assert whole.warnings == () and whole.arias_left_out == 0.0
    nearly_all = process_record(raw, pga_g=PGA_G, time_scale=TIME_SCALE, duration_s=15.0)
    assert nearly_all.arias_left_out < ARIAS_WARNING_SHARE and nearly_all.warnings == ()


def test_harness_records_prints_the_cut_warning(records_dir: Path, capsys) -> None:
    assert main(["records", "el_centro", "--records-dir", str(records_dir), "--duration", "10"]) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "warning: the cut to 10 s leaves out 16 % of the record's Arias intensity" in out
    assert "brought to rest over the last 1 s" in out
    assert re.search(r"PGD [│|] +36\.\d\d mm", out), out  # 68.56 mm before
