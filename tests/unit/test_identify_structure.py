"""The structure's identification on synthetic runs with known answers (tests/identify_synthetic.py).

The plant's structure differs from the profile's design by 12-18 % in story stiffness and by half
in damping; the run folders' profile is the design, so a fit that stayed at the design fails the
targets (modal frequencies within 2 %, damping within 30 %, story stiffness within 10 %). The
rig's sensor noise and quantization are on, and the story sensors are read at half rate.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from harness.identification import lti
from harness.identification.modal_fit import ModalFit, modal_response
from harness.identification.story_fit import floor_frequency_response, shear_matrices, undamped_frequencies_hz
from harness.identification.structure import identify_structure
from harness.model.building import fixed_base_modes
from harness.model.warmup import warm_up
from harness.profile import load_profile
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()
#: The plant's structure: k_1 +15 %, k_2 -12 %, k_3 +18 %, first-mode damping 1.5 % (the design: 1 %).
TRUTH = dataclasses.replace(DESIGN.structure, story_stiffness_N_per_m=(0.8395e6, 1.848e6, 1.7464e6),
                            first_mode_damping_ratio=0.015)


def _modes(building) -> tuple[np.ndarray, np.ndarray]:
    omega, zeta = fixed_base_modes(building)
    return omega / (2.0 * np.pi), zeta


@pytest.fixture(scope="module")
def white_noise_run(tmp_path_factory):
    """40 s of white_noise:0.5-20 at 0.1 g under the plant with TRUTH, measured as the rig measures."""
    warm_up()
    columns = measured(simulate(TRUTH, DESIGN.bearing, table_motion("white_noise:0.5-20:0.1", None, 40.0)), DESIGN, seed=7)
    return write_run(tmp_path_factory.mktemp("runs"), "white_noise", columns, DESIGN)


def test_the_first_order_hold_is_exact_for_a_linear_input():
    # x' = -2 x + u with u = t from rest: x = t/2 - 1/4 + exp(-2 t)/4, whatever the step
    dt = 0.05
    t = np.arange(0, 3.0, dt)
    y = lti.simulate(np.array([[-2.0]]), np.array([1.0]), np.array([[1.0]]), np.array([0.0]), t, dt)[0]
    assert np.max(np.abs(y - (t / 2 - 0.25 + np.exp(-2 * t) / 4))) < 1e-12


def test_the_modal_form_and_the_story_form_are_one_response():
    """The modal model with the building's own modes and participations is the story model's response."""
    masses = np.asarray(TRUTH.floor_masses_kg)
    stiffness = np.asarray(TRUTH.story_stiffness_N_per_m)
    damping = TRUTH.story_damping()  # stiffness-proportional: classical modes
    k_matrix, _ = shear_matrices(stiffness, damping)
    values, shapes = np.linalg.eigh(k_matrix / np.sqrt(np.outer(masses, masses)))
    phi = shapes / np.sqrt(masses)[:, None]  # mass-normalised mode shapes, phi' M phi = I
    gamma = phi.T @ masses  # participation factors
    frequency_hz, zeta = _modes(TRUTH)
    assert np.allclose(np.sqrt(values) / (2 * np.pi), undamped_frequencies_hz(masses, stiffness))
    fit = ModalFit(np.sqrt(values) / (2 * np.pi), np.zeros(3), zeta, np.zeros(3), (phi * gamma).T, 0.0, 0.0, 1.0, 0)
    freq = np.linspace(0.5, 20.0, 200)
    story = floor_frequency_response(masses, stiffness, damping, freq)
    assert np.allclose(modal_response(fit, freq), story, rtol=1e-6, atol=1e-9)
    assert np.allclose((phi * gamma).sum(axis=1), 1.0)  # the participations of a floor add up to one


def test_the_modes_and_stories_are_found_within_the_targets_at_the_rigs_noise(white_noise_run, tmp_path):
    result = identify_structure([white_noise_run], tmp_path / "out")
    true_hz, true_zeta = _modes(TRUTH)
    design_hz, _ = _modes(DESIGN.structure)
    assert np.max(np.abs(design_hz / true_hz - 1)) > 0.04  # the design is off by twice what the target allows
    assert np.allclose(result.modal.frequency_hz, true_hz, rtol=0.02)
    assert np.allclose(result.modal.damping_ratio, true_zeta, rtol=0.3)
    assert all(mode.determined for mode in result.modes)
    assert np.allclose(result.stories.stiffness_N_per_m, TRUTH.story_stiffness_N_per_m, rtol=0.1)
    assert result.stories.damping_model == "proportional"  # the profile's form
    assert result.stories.first_mode_damping_ratio == pytest.approx(0.015, rel=0.3)
    assert result.stiffness.determined and result.damping.determined
    story_hz, _ = result.stories.modes()
    assert np.allclose(story_hz, result.modal.frequency_hz, rtol=0.02)  # the stories reproduce the modes
    for found, se, true in zip(result.stories.stiffness_N_per_m, result.stories.stiffness_se, TRUTH.story_stiffness_N_per_m,
                               strict=True):
        assert abs(found - true) < 4.0 * se + 0.02 * true  # the stated uncertainty covers the error


def test_per_story_damping_is_found_when_asked(white_noise_run, tmp_path):
    result = identify_structure([white_noise_run], tmp_path / "out", damping_model="per_story")
    assert result.stories.first_mode_damping_ratio is None
    assert np.allclose(result.stories.damping_Ns_per_m, TRUTH.story_damping(), rtol=0.3)
    _, zeta = result.stories.modes()
    assert np.allclose(zeta, _modes(TRUTH)[1], rtol=0.3)
    text = result.overlay_path.read_text()
    assert "story_damping_Ns_per_m: [" in text
    assert "first_mode_damping_ratio: null" in text  # the profile's other form is cleared, or the overlay would not load


def test_the_overlay_makes_a_valid_profile_with_the_identified_stories(white_noise_run, tmp_path):
    import json

    import yaml

    from harness.identification.run_signals import file_sha256
    from harness.profile import Profile, merge

    result = identify_structure([white_noise_run], tmp_path / "out")
    overlay = yaml.safe_load(result.overlay_path.read_text())
    assert set(overlay) == {"structure"}
    assert set(overlay["structure"]) == {"story_stiffness_N_per_m", "first_mode_damping_ratio"}
    identified = Profile.from_resolved(merge(DESIGN.resolved_data(), overlay))
    assert np.allclose(identified.structure.story_stiffness_N_per_m, TRUTH.story_stiffness_N_per_m, rtol=0.1)
    assert identified.structure.floor_masses_kg == DESIGN.structure.floor_masses_kg  # only identified values change
    record = json.loads(result.record_path.read_text())
    assert record["runs"][0]["signals_sha256"] == file_sha256(white_noise_run / "signals.csv")
    assert len(record["modes"]) == 3 and record["modes"][0]["frequency_se_hz"] > 0
    assert result.plot_path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_band_beyond_the_rows_nyquist_frequency_is_refused(white_noise_run, tmp_path):
    from harness.identification.run_signals import IdentificationError

    with pytest.raises(IdentificationError, match="Nyquist"):
        identify_structure([white_noise_run], tmp_path / "out", band_hz=(1.0, 240.0))
