"""The rig's phi controller with p1 = 8.0 1/s holds the base mat nearly still in space (SPEC 6b).

With p1 in 1/s read correctly (8.0, not the mis-converted 0.315), the base mat's
absolute motion is well damped, so the bearing stroke stays near the table's own peak
displacement; with 0.315 a lightly damped 0.56 Hz mode about doubles it. These tests
would fail if the shipped profile went back to 0.315 or if p1 stopped reaching the
controller.
"""

from __future__ import annotations

import pytest

from harness.profile import load_profile
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study
from tests.conftest import PROFILES

RIG_PROFILE = PROFILES / "nceer_4dof.yaml"


def _stroke_and_pgd(options: StudyOptions, overrides: tuple[str, ...] = ()) -> tuple[float, float, float]:
    """Controlled peak stroke (m), the record's PGD (m) and the peak force (% W)."""
    study = run_study(load_profile(RIG_PROFILE, overrides=overrides), options)
    peaks = study.cases["controlled"].peaks
    return peaks.sliding_displacement_m, study.motion.pgd_m, peaks.peak_force_pct_weight


def test_shipped_profile_uses_p1_8_per_s():
    design = load_profile(RIG_PROFILE).control.designs["phi"]
    assert design.p1_per_s == 8.0


def test_stroke_follows_the_table_with_p1_8_and_doubles_with_0_315():
    options = StudyOptions(duration_s=30.0)  # the default, seeded synthetic record
    stroke, pgd, _ = _stroke_and_pgd(options)
    assert stroke <= 1.25 * pgd, f"stroke {stroke * 1e3:.1f} mm against table PGD {pgd * 1e3:.1f} mm"
    stroke_wrong, _, _ = _stroke_and_pgd(options, ("control.designs.phi.p1_per_s=0.315",))
    assert stroke_wrong >= 1.6 * pgd, "the mis-converted p1 should leave the 0.56 Hz mode lightly damped"


@pytest.mark.parametrize(
    ("record", "pga_g", "stroke_mm", "force_pct"),
    [("el_centro", 0.34, 27.1, 10.0), ("hachinohe", 0.23, 31.2, 10.6), ("pacoima", 0.40, 37.3, 12.1)],
)
def test_rig_records_reproduce_the_measured_peaks(records_dir, record, pga_g, stroke_mm, force_pct):
    """Issue 12's figures for the rig's three records at time scale 2, 30 s, ideal control.

    Measured with the friction estimator on the bearing's yield displacement (the source's design);
    the shipped estimator's wider one (issue 31) slides the base mat 8-9 % more on Hachinohe and Pacoima.
    """
    options = StudyOptions(record=record, records_dir=str(records_dir), pga_g=pga_g, time_scale=2.0, duration_s=30.0)
    stroke, _, force = _stroke_and_pgd(options, ("control.estimator.yield_displacement_m=null",))
    assert stroke * 1e3 == pytest.approx(stroke_mm, rel=0.03)
    assert force == pytest.approx(force_pct, rel=0.03)
    assert force <= 14.0  # the source: the peak control force was 12-14 % of the weight
