"""SIMEX for the bearing fit: the sensors' noise from the samples, the extrapolation, and the bias it removes.

The synthetic record is the plant's own Bouc-Wen (:func:`harness.model.bearing.advance_hysteretic`,
through :func:`~harness.identification.friction_fit.nu_along`) along a known sliding path with
stick spells and reversals, its friction ``mu(xdot) mbar g nu`` the force, and Gaussian noise of
known standard deviation on the displacement and velocity (the rig's sliding displacement and
velocity are differences of two sensors each: sqrt(2) times one sensor's noise).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.identification import friction_fit as ff
from harness.identification.simex import extrapolate, extrapolation_weights, noise_std
from harness.profile import load_profile
from harness.signals import columns as layout

PROFILE = load_profile()
BEARING = PROFILE.bearing
WEIGHT_N = PROFILE.structure.total_weight_N
RATE_HZ = 500.0
#: The rig's sliding displacement and velocity noise: two sensors' differences (m, m/s).
SIGMA_X_M = math.sqrt(2.0) * 5.2e-6
SIGMA_V_M_S = math.sqrt(2.0) * 2.0e-4


def sliding_path(duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """A sliding path (m) and its velocity (m/s): two tones, cubed, so the bearing sticks around each reversal."""
    t = np.arange(int(duration_s * RATE_HZ) + 1) / RATE_HZ
    tone = np.sin(2 * np.pi * 0.9 * t) + 0.6 * np.sin(2 * np.pi * 2.1 * t + 0.4)
    velocity = 0.03 * np.sign(tone) * np.abs(tone) ** 3
    displacement = np.concatenate([[0.0], np.cumsum(0.5 * (velocity[1:] + velocity[:-1]) / RATE_HZ)])
    return displacement, velocity


def noisy_record(duration_s: float, seed: int, sigma_x: float = SIGMA_X_M, sigma_v: float = SIGMA_V_M_S) -> ff.SlidingRecord:
    """The friction of :data:`BEARING` along :func:`sliding_path`, the motion measured with the given noise."""
    x, v = sliding_path(duration_s)
    nu = ff.nu_along(x, 0.0, BEARING.packed(WEIGHT_N))
    friction = (BEARING.mu_max - BEARING.mu_delta * np.exp(-BEARING.a_mu_s_per_m * np.abs(v))) * WEIGHT_N * nu
    rng = np.random.default_rng(seed)
    x_read = x + sigma_x * rng.standard_normal(len(x))
    v_read = v + sigma_v * rng.standard_normal(len(v))
    force = friction + 5.0 * rng.standard_normal(len(x))
    return ff.SlidingRecord("synthetic", RATE_HZ, ff.fused_displacement(x_read, v_read, RATE_HZ), v_read, force,
                            np.zeros_like(force), x_read)


@pytest.mark.parametrize("sigma", [2e-6, 7e-6, 2e-5])
def test_the_noise_estimate_finds_a_known_sigma_under_the_motion(sigma):
    x, _ = sliding_path(30.0)
    rng = np.random.default_rng(3)
    assert noise_std(x + sigma * rng.standard_normal(len(x))) == pytest.approx(sigma, rel=0.2)
    assert noise_std(x) < 0.2 * 2e-6  # the motion alone is not noise


def test_the_noise_estimate_of_quantized_samples_is_not_stuck_on_whole_counts():
    x, _ = sliding_path(30.0)
    rng = np.random.default_rng(4)
    step = 5e-6
    found = [noise_std(step * np.round((x + sigma * rng.standard_normal(len(x))) / step)) for sigma in (6e-6, 6.5e-6, 7e-6)]
    for sigma, estimate in zip((6e-6, 6.5e-6, 7e-6), found, strict=True):
        assert estimate == pytest.approx(math.sqrt(sigma**2 + step**2 / 12), rel=0.05)
    assert found[0] < found[1] < found[2]


def test_the_noise_estimate_finds_the_rigs_configured_sensor_noise():
    from harness.model.warmup import warm_up
    from tests.identify_synthetic import measured, simulate, table_motion

    warm_up()
    true = simulate(PROFILE.structure, BEARING, table_motion("synthetic:3", 0.34, 10.0))
    read = measured(true, PROFILE)
    sensors = PROFILE.rig.sensors
    # the sliding motion is the base mat's sensor minus the table's: two sensors' noise and quantization
    expected_x = math.sqrt(2.0 * (sensors.displacement.noise_std_m**2 + sensors.displacement.quantization_m**2 / 12))
    expected_v = math.sqrt(2.0 * (sensors.velocity.noise_std_m_s**2 + sensors.velocity.quantization_m_s**2 / 12))
    assert noise_std(read[layout.SLIDING_DISPLACEMENT]) == pytest.approx(expected_x, rel=0.2)
    assert noise_std(read[layout.SLIDING_VELOCITY]) == pytest.approx(expected_v, rel=0.2)


def test_the_quadratic_extrapolation_of_exact_quadratics_is_exact_and_has_no_monte_carlo_error():
    lambdas = (0.5, 1.0, 1.5, 2.0)

    def curve(lam: float) -> np.ndarray:
        return np.array([1.0 + 0.2 * lam - 0.03 * lam**2, 5.0 - lam])

    replicates = np.array([[curve(lam) for lam in lambdas]] * 3)
    result = extrapolate(curve(0.0), lambdas, replicates)
    np.testing.assert_allclose(result.value, curve(-1.0), rtol=1e-12)
    np.testing.assert_allclose(result.standard_error, 0.0, atol=1e-12)
    assert extrapolation_weights((0.0, *lambdas)).sum() == pytest.approx(1.0)  # a constant stays itself


def test_the_extrapolations_spread_is_the_monte_carlo_error():
    lambdas = (1.0, 2.0)
    replicates = np.array([[[1.0 + lam] for lam in lambdas], [[1.0 + 2.0 * lam] for lam in lambdas]])  # two lines
    result = extrapolate(np.array([1.0]), lambdas, replicates)
    assert result.value[0] == pytest.approx(-0.5)  # the lines at -1: 0 and -1
    assert result.standard_error[0] == pytest.approx(np.std([0.0, -1.0], ddof=1) / math.sqrt(2))


@pytest.mark.slow
def test_simex_removes_most_of_the_noises_bias_in_the_yield_displacement():
    record = noisy_record(20.0, seed=5)
    plain = ff.fit_friction([record], BEARING, WEIGHT_N, simex=False)
    corrected = ff.fit_friction([record], BEARING, WEIGHT_N)
    truth = BEARING.yield_displacement_m
    plain_bias = plain.estimates["yield_displacement_m"].value / truth - 1.0
    simex_bias = corrected.estimates["yield_displacement_m"].value / truth - 1.0
    assert plain_bias > 0.04  # the noise in the fit's input widens the yield
    assert abs(simex_bias) < 0.5 * plain_bias
    assert corrected.simex is not None and corrected.simex.plain["yield_displacement_m"][0] == pytest.approx(
        plain.estimates["yield_displacement_m"].value, rel=1e-12)
    # the noise it added was the record's own, found from its samples
    assert corrected.simex.displacement_noise_m[0] == pytest.approx(SIGMA_X_M, rel=0.2)
    assert corrected.simex.velocity_noise_m_s[0] == pytest.approx(SIGMA_V_M_S, rel=0.2)
    # its standard error holds the plain fit's and the extrapolation's
    se = corrected.estimates["yield_displacement_m"].standard_error
    assert se == pytest.approx(math.hypot(plain.estimates["yield_displacement_m"].standard_error,
                                          corrected.simex.extrapolation_se["yield_displacement_m"]), rel=1e-9)
    assert abs(simex_bias) * truth < 1.96 * se


def test_simex_is_deterministic():
    record = noisy_record(6.0, seed=6)
    plain = ff.fit_friction([record], BEARING, WEIGHT_N, simex=False)
    theta = np.array([plain.bearing.mu_max, plain.bearing.mu_delta / plain.bearing.mu_max,
                      math.log(plain.bearing.a_mu_s_per_m), math.log(plain.bearing.yield_displacement_m), 1e3 * plain.delay_s])
    errors = np.array([plain.estimates[name].standard_error for name in ff.PARAMETERS])
    first, second = (ff.simex_correction([record], BEARING, WEIGHT_N, ff.LOWPASS_HZ, theta, errors, lambdas=(1.0, 2.0),
                                         replicates=2) for _ in range(2))
    assert first == second
    other = ff.simex_correction([record], BEARING, WEIGHT_N, ff.LOWPASS_HZ, theta, errors, lambdas=(1.0, 2.0),
                                replicates=2, seed=ff.SIMEX_SEED + 1)
    assert other.extrapolated != first.extrapolated  # the seed is what fixes it


def test_a_record_without_its_displacement_samples_is_fitted_without_the_correction():
    record = noisy_record(6.0, seed=7)
    bare = ff.SlidingRecord(record.label, record.rate_hz, record.displacement_m, record.velocity_m_s,
                            record.actuator_force_N, record.other_forces_N)
    assert ff.fit_friction([bare], BEARING, WEIGHT_N).simex is None
