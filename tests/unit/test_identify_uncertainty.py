"""The structure identification's stated uncertainty and its input (issue 33, item 2).

The input's noise biased the first mode's damping (an output-error fit lowers a resonance that
the noise would excite); the base mat's acceleration is now blended with its differentiated
velocity where that is quieter. The standard errors are the larger of the Jacobian's and a block
sandwich over stretches of time, and the 95 % interval uses Student's t for the blocks.
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.identification.fit_statistics import (
    BLOCKS,
    block_covariance,
    correlation_time,
    covariance,
    honest_standard_errors,
    interval_95,
    t_factor_95,
    time_blocks,
)
from harness.identification.structure import identify_structure
from harness.identification.structure_records import base_acceleration_estimate, crossover_hz
from harness.model.building import fixed_base_modes
from harness.model.warmup import warm_up
from harness.profile import load_profile
from harness.signals import columns as layout
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()


def test_the_blended_input_passes_the_true_acceleration_unchanged():
    rate = 500.0
    t = np.arange(0, 20.0, 1 / rate)
    velocity = np.sin(2 * np.pi * 2.3 * t) * 0.1 + 0.02 * np.sin(2 * np.pi * 11.0 * t)
    acceleration = 0.1 * 2 * np.pi * 2.3 * np.cos(2 * np.pi * 2.3 * t) + 0.02 * 2 * np.pi * 11.0 * np.cos(2 * np.pi * 11.0 * t)
    blended = base_acceleration_estimate(rate, acceleration, velocity, 16.0)
    inner = slice(500, -500)  # away from the filter's ends
    assert np.max(np.abs(blended[inner] - acceleration[inner])) < 0.01 * np.max(np.abs(acceleration))


def test_the_crossover_is_where_the_two_sensors_noise_is_equal():
    assert crossover_hz(0.02, 2e-4, 500.0) == pytest.approx(0.02 / (2 * np.pi * 2e-4))  # 15.9 Hz, the shipped rig
    assert crossover_hz(0.0, 2e-4, 500.0) == 0.0  # a noiseless accelerometer is used alone
    assert crossover_hz(0.02, 0.0, 500.0) == pytest.approx(200.0)


def test_block_errors_cover_a_slope_under_slowly_correlated_noise():
    """A straight-line fit whose noise is correlated over a tenth of the record: the stated interval covers the truth."""
    rng = np.random.default_rng(3)
    n = 2000
    x = np.linspace(-1, 1, n)
    jacobian = -np.column_stack([np.ones(n), x])
    covered_blocks = covered_plain = 0
    trials = 200
    for _ in range(trials):
        noise = np.convolve(rng.standard_normal(n + 199), np.ones(200) / np.sqrt(200), mode="valid")
        noise *= 1.0 + x  # and its size grows along the record
        y = 0.5 + 2.0 * x + noise
        slope = np.polyfit(x, y, 1)[0]
        residuals = y - np.polyval(np.polyfit(x, y, 1), x)
        se = honest_standard_errors(jacobian, residuals, time_blocks(n))[1]
        plain = np.sqrt(covariance(jacobian, residuals, 1.0)[1, 1])
        low, high = interval_95(slope, se)
        covered_blocks += low <= 2.0 <= high
        covered_plain += abs(slope - 2.0) <= 1.96 * plain
    assert covered_blocks >= 0.9 * trials
    assert covered_plain < 0.5 * trials  # what the plain formula claimed


def test_the_block_covariance_is_the_sandwich_of_the_blocks_scores():
    rng = np.random.default_rng(0)
    jacobian = rng.standard_normal((80, 2))
    residuals = rng.standard_normal(80)
    blocks = time_blocks(80, 4)
    assert np.bincount(blocks).tolist() == [20, 20, 20, 20]
    scores = np.array([jacobian[blocks == b].T @ residuals[blocks == b] for b in range(4)])
    scores -= scores.mean(axis=0)
    bread = np.linalg.inv(jacobian.T @ jacobian)
    expected = bread @ (scores.T @ scores * 4 / 3) @ bread
    assert np.allclose(block_covariance(jacobian, residuals, blocks), expected)
    assert correlation_time(residuals) >= 1.0
    assert t_factor_95(BLOCKS) == pytest.approx(2.3646, abs=1e-3)


def test_the_reported_values_errors_carry_both_covariances_through_the_change_of_parameters():
    """The bearing's fit reports mu_delta = mu_max * ratio and exp(ln a_mu): each covariance goes through the
    derivatives, then the larger is taken (the larger of the fit's own two, taken first, is not the same)."""
    rng = np.random.default_rng(1)
    n = 400
    jacobian = rng.standard_normal((n, 2))
    residuals = np.convolve(rng.standard_normal(n + 39), np.ones(40) / np.sqrt(40), mode="valid")
    blocks = time_blocks(n)
    gradient = np.array([[1.0, 0.0], [0.7, 3.0]])  # value 2 = 0.7 theta_1 + 3 theta_2
    model = covariance(jacobian, residuals, correlation_time(residuals))
    data = block_covariance(jacobian, residuals, blocks)
    expected = np.sqrt(np.maximum(np.diag(gradient @ model @ gradient.T), np.diag(gradient @ data @ gradient.T)))
    assert np.allclose(honest_standard_errors(jacobian, residuals, blocks, gradient), expected)
    assert np.allclose(honest_standard_errors(jacobian, residuals, blocks, np.eye(2)),
                       honest_standard_errors(jacobian, residuals, blocks))
    assert np.allclose(honest_standard_errors(jacobian, residuals, blocks, 2.0 * np.eye(2)),
                       2.0 * honest_standard_errors(jacobian, residuals, blocks))


@pytest.fixture(scope="module")
def design_plant_run(tmp_path_factory):
    """40 s of white_noise:0.5-20 at 0.1 g under the shipped design itself (1 % first-mode damping), measured as the rig does."""
    warm_up()
    columns = measured(simulate(DESIGN.structure, DESIGN.bearing, table_motion("white_noise:0.5-20:0.1", None, 40.0)),
                       DESIGN, seed=3)
    folder = tmp_path_factory.mktemp("runs")
    return (write_run(folder, "with_velocity", columns, DESIGN),
            write_run(folder, "accelerometer_only", columns, DESIGN, leave_out=(layout.BASE_VELOCITY,)))


def test_the_first_modes_damping_interval_holds_the_truth_where_the_accelerometer_alone_misses(design_plant_run, tmp_path):
    with_velocity, accelerometer_only = design_plant_run
    _, true_zeta = fixed_base_modes(DESIGN.structure)
    old = identify_structure([accelerometer_only], tmp_path / "old")
    assert old.modal.damping_ratio[0] > 1.03 * true_zeta[0]  # the input's noise biases the accelerometer-only fit upward
    new = identify_structure([with_velocity], tmp_path / "new")
    for r in range(3):
        low, high = interval_95(float(new.modal.damping_ratio[r]), float(new.modal.damping_se[r]))
        assert low <= true_zeta[r] <= high, r
    ratio = new.stories.first_mode_damping_ratio
    low, high = interval_95(float(ratio or 0), float(new.stories.first_mode_damping_se or 0))
    assert low <= 0.01 <= high


def test_the_plot_says_why_the_measured_first_peak_is_lower_than_the_fit():
    from harness.identification.structure_plot import smearing_note
    from harness.identification.structure_records import MeasuredResponse

    note = smearing_note(MeasuredResponse(np.arange(0, 10, 0.125), np.zeros((1, 80), dtype=complex), np.ones((1, 80))))
    assert "0.125 Hz" in note and "lower and wider" in note


def test_a_story_model_that_misses_the_modes_widens_the_stiffness_errors():
    from harness.identification.story_fit import StoryFit, with_model_error

    building = DESIGN.structure
    stiffness = np.asarray(building.story_stiffness_N_per_m, dtype=float)
    fit = StoryFit(building, "proportional", stiffness, 1e-4 * stiffness, np.ones(3), np.zeros(3), 0.01, 1e-5, 0.0, 0.0, 1)
    frequency_hz, _ = fit.modes()
    missed = frequency_hz * np.array([1.0, 1.0, 1.01])  # the modal fit's third mode 1 % above the story model's
    widened = with_model_error(fit, missed)
    assert np.allclose(widened.stiffness_se / stiffness, np.hypot(1e-4, 2 * 0.01 / 1.01), rtol=1e-6)
    assert np.allclose(with_model_error(fit, frequency_hz).stiffness_se, fit.stiffness_se)  # nothing missed, nothing added
    assert with_model_error(fit, frequency_hz, 0.0103).first_mode_damping_se == pytest.approx(np.hypot(1e-5, 0.0003))
    assert with_model_error(fit, frequency_hz, 0.01).first_mode_damping_se == pytest.approx(1e-5)
