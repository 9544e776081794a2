"""The response spectrum against scipy's exact linear-interpolation solution, and the largest PGA that fits a table."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from harness.motions import (
    RecordConfig,
    TableLimits,
    largest_fitting_pga_g,
    load_motion,
    response_spectrum,
    table_excesses,
)


def _accel(n: int = 2000, dt: float = 0.01) -> np.ndarray:
    rng = np.random.default_rng(3)
    return np.convolve(rng.normal(size=n), np.ones(5) / 5, mode="same") * np.hanning(n)


@pytest.mark.parametrize("period_s", [0.05, 0.3, 1.0, 4.0])
def test_peak_displacement_matches_an_exact_solution_at_the_samples(period_s: float) -> None:
    dt, accel = 0.01, _accel()
    spectrum = response_spectrum(accel, dt, np.array([period_s]), damping=0.05)
    omega = 2 * np.pi / period_s
    t = np.arange(accel.size) * dt
    _, response, _ = signal.lsim(signal.lti([-1.0], [1.0, 2 * 0.05 * omega, omega**2]), accel, t)
    assert spectrum.sd_m[0] == pytest.approx(np.max(np.abs(response)), rel=1e-9)
    assert spectrum.sa_m_s2[0] == pytest.approx(omega**2 * spectrum.sd_m[0])


def test_a_stiff_oscillator_follows_the_ground_and_sa_tends_to_the_pga() -> None:
    dt, accel = 0.005, _accel(4000)
    spectrum = response_spectrum(accel, dt, np.array([0.005]))
    assert spectrum.sa_m_s2[0] == pytest.approx(np.max(np.abs(accel)), rel=0.02)


def test_bad_damping_or_periods_are_refused() -> None:
    with pytest.raises(ValueError, match="damping"):
        response_spectrum(_accel(), 0.01, damping=1.0)
    with pytest.raises(ValueError, match="periods"):
        response_spectrum(_accel(), 0.01, np.array([0.0, 1.0]))


def test_the_largest_fitting_pga_just_fits_and_a_little_more_does_not(tmp_path) -> None:
    table = TableLimits(stroke_limit_m=0.05, velocity_limit_m_s=0.5, acceleration_limit_g=1.5)
    config = RecordConfig(name="synthetic:4", pga_g=0.5, duration_s=10.0)
    motion = load_motion(config, base_dir=tmp_path)
    largest, binding = largest_fitting_pga_g(motion, table)
    assert binding in ("stroke", "velocity", "acceleration")
    at_limit = load_motion(RecordConfig(name="synthetic:4", pga_g=largest * 0.999, duration_s=10.0), base_dir=tmp_path)
    beyond = load_motion(RecordConfig(name="synthetic:4", pga_g=largest * 1.01, duration_s=10.0), base_dir=tmp_path)
    assert not table_excesses(at_limit, table)
    assert table_excesses(beyond, table)
