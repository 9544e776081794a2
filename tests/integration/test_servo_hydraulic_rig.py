"""The servo-hydraulic rig end to end: a dry run agrees with its twin; the free actuator shows the interaction.

Both run the shipped profile, whose rig is servo-hydraulic (actuator and table), in lockstep.
"""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.runs.dry_run import DryRunOptions, dry_run
from harness.runs.options import StudyOptions


@pytest.fixture(scope="module")
def el_centro_dry_run(tmp_path_factory, records_dir):
    options = DryRunOptions(
        study=StudyOptions(record="el_centro", records_dir=str(records_dir), pga_g=0.34, time_scale=2.0, duration_s=12.0),
        lockstep=True, show_console=False, log_dir=str(tmp_path_factory.mktemp("runs")),
    )
    return dry_run(load_profile(None), options)


def test_the_shipped_rig_is_servo_hydraulic() -> None:
    rig = load_profile(None).rig
    assert rig.actuator.model == "servo_hydraulic" and rig.table.model == "servo_hydraulic"


def test_a_lockstep_dry_run_and_its_twin_agree_on_stroke_drifts_and_force(el_centro_dry_run) -> None:
    result = el_centro_dry_run
    assert result.session.outcome == "completed"
    ours, twin = result.peaks.flatten(), result.twin.peaks.flatten()
    compared = ("sliding_displacement_m", "drift_1_m", "drift_2_m", "drift_3_m", "peak_force_pct_weight")
    differences = {key: abs(ours[key] - twin[key]) / abs(twin[key]) for key in compared}
    # 5 % for the drifts and the force. The sliding displacement gets 10 %: with the friction estimator's
    # wider pre-sliding band (control.estimator.yield_displacement_m) it follows the estimate's lag at each
    # reversal, and a lockstep dry run on a loaded machine still differs from run to run (0.9-3.3 % from its
    # twin on a quiet machine, 6.4-7.0 % measured under load): that non-determinism is issue 34's to remove.
    bounds = {key: 0.10 if key == "sliding_displacement_m" else 0.05 for key in compared}
    assert all(differences[key] <= bounds[key] for key in compared), differences


def test_the_dry_run_sees_the_achieved_table_not_the_drive(el_centro_dry_run) -> None:
    # The table's own servo loop under the payload: the achieved motion differs from the record.
    from harness.recording import load_run
    from harness.report.reference import target_motion, tracking_error

    run = load_run(el_centro_dry_run.session.run_path)
    target = target_motion(run)
    assert target is not None
    measured = tracking_error(run, target, "table_displacement_m", target.displacement_m)
    assert measured is not None
    assert 0.0005 < measured.delay_s < 0.03  # the table lags its drive by milliseconds
    assert measured.rms_error > 1e-5 and measured.correlation > 0.99


def _frf(path: Path) -> dict[str, np.ndarray]:
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    return {key: np.array([float(row[key]) for row in rows]) for key in rows[0]}


@pytest.mark.slow
def test_the_free_actuator_shows_the_interaction_the_blocked_one_does_not(tmp_path) -> None:
    # Large enough to slide the base mat past its bearings' friction, slow enough for the rate limit.
    # A servo controller without velocity feed-forward (SPEC 7a'): the whole natural velocity feedback.
    status = main(["identify", "actuator", "--out", str(tmp_path), "--both", "--quiet", "--amplitude-N", "6000",
                   "--band-hz", "0.5,10", "--duration", "24", "--set", "rig.actuator.hydraulics.feedforward.gain=0",
                   "--set", "safety.force.velocity_feedforward_gain=0", "--allow-weaker-safety"])
    assert status == exit_codes.OK
    free, blocked = _frf(tmp_path / "frf.csv"), _frf(tmp_path / "frf_blocked.csv")
    assert np.allclose(free["freq_hz"], blocked["freq_hz"])
    between = (free["freq_hz"] >= 3.0) & (free["freq_hz"] <= 6.0)  # between the fixed-base modes (2.3, 7.3 Hz)
    # Blocked: the force loop alone, gain near 1.
    assert np.all(blocked["magnitude"] > 0.9)
    # Free: the sliding base mat bleeds the force (a dip of more than 3 dB) ...
    assert np.all(free["magnitude"][between] < blocked["magnitude"][between] * 10 ** (-3 / 20))
    # ... and the coupled motion adds phase lag around the coupled resonance.
    around = (free["freq_hz"] >= 2.6) & (free["freq_hz"] <= 3.4)
    assert np.all(free["phase_deg"][around] < blocked["phase_deg"][around] - 5.0)
    assert (tmp_path / "frf.png").stat().st_size > 10_000
