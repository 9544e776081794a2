"""The bearing's identification on synthetic runs with known answers (tests/identify_synthetic.py).

The plant runs a bearing that differs from the profile's design by 20-40 % in every fitted
parameter; the run folder's profile is the design, so a fit that did not move, or moved the
wrong way, fails. The rig's sensor noise and quantization are on.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from harness.identification import friction_fit as ff
from harness.identification.bearing import identify_bearing, sliding_record
from harness.identification.force_balance import friction_from_balance
from harness.model.warmup import warm_up
from harness.profile import load_profile
from harness.recording import load_run
from harness.signals import columns as layout
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()
#: The plant's bearing: mu_max +25 %, mu_delta -20 %, a_mu -22 %, D_y +38 % from the design.
TRUTH = dataclasses.replace(DESIGN.bearing, mu_max=0.075, mu_delta=0.024, a_mu_s_per_m=70.0, yield_displacement_m=3.5e-5)


@pytest.fixture(scope="module")
def earthquake() -> dict[str, np.ndarray]:
    """30 s of the seeded synthetic record at 0.34 g (time scale 2): the bearing slides fast and slow, often."""
    warm_up()
    return simulate(DESIGN.structure, TRUTH, table_motion("synthetic:3", 0.34, 30.0))


def test_the_force_balance_gives_the_plants_friction(earthquake):
    floors = [earthquake[layout.floor_acceleration(j)] for j in (1, 2, 3)]
    friction = friction_from_balance(DESIGN.structure, earthquake[layout.FORCE_MEASURED], earthquake[layout.SLIDING_DISPLACEMENT],
                                     earthquake[layout.BASE_ACCELERATION], floors)
    true = earthquake[layout.FRICTION_FORCE]
    assert np.abs(true).max() > 2000.0  # it slid: friction near mu_max mbar g = 3 kN
    assert np.max(np.abs(friction - true)) < 1e-6 * np.abs(true).max()


def test_the_fused_displacement_keeps_the_motion_and_drops_the_noise(earthquake):
    rng = np.random.default_rng(0)
    x, v = earthquake[layout.SLIDING_DISPLACEMENT], earthquake[layout.SLIDING_VELOCITY]
    exact = ff.fused_displacement(x, v, 500.0) - x  # exact sensors: the motion passes, to the trapezoid's error at reversals
    assert np.max(np.abs(exact)) < 2e-6 and np.std(exact) < 3e-7
    noisy_x = x + 7e-6 * rng.standard_normal(len(x))  # the rig's two LVDTs' noise
    noisy_v = v + 3e-4 * rng.standard_normal(len(v))
    error = ff.fused_displacement(noisy_x, noisy_v, 500.0) - x
    assert np.std(error) < 0.4 * 7e-6  # well below the displacement sensors' own noise, and below D_y


def test_nu_along_the_true_displacement_is_the_plants_nu(earthquake):
    params = TRUTH.packed(DESIGN.structure.total_weight_N)
    nu = ff.nu_along(earthquake[layout.SLIDING_DISPLACEMENT], 0.0, params)
    assert np.abs(earthquake[layout.HYSTERETIC_NU]).max() == pytest.approx(1.0, abs=1e-3)
    # sampled travel against the plant's continuous integration: a whole swing differs only near the sample it happens in
    assert np.mean(np.abs(nu - earthquake[layout.HYSTERETIC_NU])) < 0.02


def test_the_fit_finds_a_bearing_unlike_the_design_at_the_rigs_noise(earthquake, tmp_path):
    folder = write_run(tmp_path, "quake", measured(earthquake, DESIGN), DESIGN)
    fit = ff.fit_friction([sliding_record(load_run(folder), DESIGN.structure)], DESIGN.bearing, DESIGN.structure.total_weight_N)
    assert fit.determined == ff.PARAMETERS
    found = {name: estimate.value for name, estimate in fit.estimates.items()}
    assert found["mu_max"] == pytest.approx(TRUTH.mu_max, rel=0.05)
    assert found["mu_delta"] == pytest.approx(TRUTH.mu_delta, rel=0.1)
    assert found["a_mu_s_per_m"] == pytest.approx(TRUTH.a_mu_s_per_m, rel=0.1)
    assert found["yield_displacement_m"] == pytest.approx(TRUTH.yield_displacement_m, rel=0.1)
    for name, estimate in fit.estimates.items():  # the stated uncertainty covers the error
        assert abs(estimate.value - getattr(TRUTH, name)) < 4.0 * estimate.standard_error + 0.02 * abs(estimate.value), name
    assert fit.relative_rms_error < 0.06


def test_a_load_cell_read_late_is_found_and_does_not_bias_the_law(earthquake, tmp_path):
    def fitted(columns, name):
        folder = write_run(tmp_path, name, columns, DESIGN)
        return ff.fit_friction([sliding_record(load_run(folder), DESIGN.structure)], DESIGN.bearing,
                               DESIGN.structure.total_weight_N)

    columns = measured(earthquake, DESIGN)
    on_time = fitted(columns, "on_time")  # the floors' half-rate reading lags them about a millisecond already
    columns[layout.FORCE_MEASURED] = np.concatenate([columns[layout.FORCE_MEASURED][:2], columns[layout.FORCE_MEASURED][:-2]])
    fit = fitted(columns, "late")  # the load cell two ticks (4 ms) behind the motion sensors
    assert fit.delay_s - on_time.delay_s == pytest.approx(-0.004, abs=0.0005)  # its force belongs 4 ms earlier
    assert fit.estimates["a_mu_s_per_m"].value == pytest.approx(TRUTH.a_mu_s_per_m, rel=0.1)
    assert fit.estimates["mu_delta"].value == pytest.approx(TRUTH.mu_delta, rel=0.1)


def test_a_run_that_slid_only_slowly_cannot_give_mu_max(tmp_path):
    slow = simulate(DESIGN.structure, TRUTH, table_motion("synthetic:3", 0.1, 30.0))
    assert 0.005 < np.abs(slow[layout.SLIDING_VELOCITY]).max() < 3.0 / TRUTH.a_mu_s_per_m  # never near mu_max's speeds
    folder = write_run(tmp_path, "slow", measured(slow, DESIGN), DESIGN)
    fit = ff.fit_friction([sliding_record(load_run(folder), DESIGN.structure)], DESIGN.bearing, DESIGN.structure.total_weight_N)
    assert "mu_max" not in fit.determined
    assert "sliding faster than 3/a_mu" in fit.estimates["mu_max"].reason


def test_a_run_that_never_slid_determines_nothing_and_says_why(tmp_path):
    still = simulate(DESIGN.structure, TRUTH, table_motion("synthetic:3", 0.02, 10.0))
    folder = write_run(tmp_path, "still", measured(still, DESIGN), DESIGN)
    fit = ff.fit_friction([sliding_record(load_run(folder), DESIGN.structure)], DESIGN.bearing, DESIGN.structure.total_weight_N)
    assert fit.determined == ()
    assert fit.slid == (False,)
    assert "no run slid" in fit.note and "lower bound" in fit.note


def test_identify_bearing_writes_an_overlay_of_the_determined_values(earthquake, tmp_path):
    import json

    import yaml

    from harness.identification.run_signals import file_sha256
    from harness.profile import Profile, merge

    folder = write_run(tmp_path, "quake", measured(earthquake, DESIGN), DESIGN)
    result = identify_bearing([folder], tmp_path / "out")
    overlay = yaml.safe_load(result.overlay_path.read_text())
    assert set(overlay) == {"bearing"} and set(overlay["bearing"]) == set(ff.PARAMETERS)
    assert overlay["bearing"]["mu_max"] == pytest.approx(TRUTH.mu_max, rel=0.05)
    assert "+/-" in result.overlay_path.read_text().split("mu_max:")[1].splitlines()[0]  # each value says its quality
    identified = Profile.from_resolved(merge(DESIGN.resolved_data(), overlay))
    assert identified.bearing.mu_max == overlay["bearing"]["mu_max"]  # a valid profile with the identified bearing
    record = json.loads(result.record_path.read_text())
    assert record["runs"][0]["signals_sha256"] == file_sha256(folder / "signals.csv")
    assert record["harness_version"] and record["determined"] == list(ff.PARAMETERS)
    assert record["parameters"]["mu_max"]["standard_error"] > 0
    assert result.plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_runs_of_different_masses_are_refused(earthquake, tmp_path):
    from harness.identification.run_signals import IdentificationError

    heavier = dataclasses.replace(DESIGN, structure=dataclasses.replace(DESIGN.structure, base_mass_kg=1500.0))
    first = write_run(tmp_path, "a", measured(earthquake, DESIGN), DESIGN)
    second = write_run(tmp_path, "b", measured(earthquake, DESIGN), heavier)
    with pytest.raises(IdentificationError, match="masses or restraining springs differ"):
        identify_bearing([first, second], tmp_path / "out")


def test_the_fit_path_is_the_plants_integration_not_a_copy(tmp_path):
    """With the design's own bearing on the plant, the fit stays at the design (nothing drifts it away)."""
    true = simulate(DESIGN.structure, DESIGN.bearing, table_motion("synthetic:5", 0.34, 20.0))
    folder = write_run(tmp_path, "design", measured(true, DESIGN, seed=4), DESIGN)
    fit = ff.fit_friction([sliding_record(load_run(folder), DESIGN.structure)], DESIGN.bearing, DESIGN.structure.total_weight_N)
    assert fit.estimates["mu_max"].value == pytest.approx(DESIGN.bearing.mu_max, rel=0.03)
    assert fit.estimates["mu_delta"].value == pytest.approx(DESIGN.bearing.mu_delta, rel=0.1)


def test_the_sliding_record_reads_the_load_cell_not_the_command(earthquake, tmp_path):
    columns = measured(earthquake, DESIGN)
    columns[layout.FORCE_COMMAND] = np.zeros_like(columns[layout.TIME])  # a command the load cell does not show
    folder = write_run(tmp_path, "quake", columns, DESIGN)
    record = sliding_record(load_run(folder), DESIGN.structure)
    floors = [columns[layout.floor_acceleration(j)] for j in (1, 2, 3)]
    expected = friction_from_balance(DESIGN.structure, columns[layout.FORCE_MEASURED], columns[layout.SLIDING_DISPLACEMENT],
                                     columns[layout.BASE_ACCELERATION], floors)
    assert np.allclose(record.friction_N(), expected, atol=1e-6)
    assert Path(folder).is_dir()
