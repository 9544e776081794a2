"""Synthetic Clough-Penzien record: determinism, envelope, PGA, spectrum, parameter checks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.errors import RecordError
from harness.motions import G_M_S2, process_record, synthetic_record
from harness.motions.summary import mean_period
from harness.motions.synthetic import envelope_shape


def test_same_seed_gives_the_identical_array():
    a = synthetic_record(seed=11)
    b = synthetic_record(seed=11)
    assert np.array_equal(a.accel_m_s2, b.accel_m_s2)


@settings(max_examples=20, deadline=None)
@given(seed_a=st.integers(0, 2**32 - 1), seed_b=st.integers(0, 2**32 - 1))
def test_different_seeds_give_different_arrays(seed_a, seed_b):
    a = synthetic_record(seed=seed_a, duration_s=5.0)
    b = synthetic_record(seed=seed_b, duration_s=5.0)
    assert np.array_equal(a.accel_m_s2, b.accel_m_s2) == (seed_a == seed_b)


@settings(max_examples=20, deadline=None)
@given(pga=st.floats(0.01, 1.5), duration=st.floats(2.0, 40.0), dt=st.sampled_from([0.005, 0.01, 0.02]))
def test_length_step_and_pga(pga, duration, dt):
    record = synthetic_record(duration_s=duration, dt_s=dt, pga_g=pga)
    assert record.n_samples == int(round(duration / dt)) + 1
    assert record.dt_s == dt
    assert record.pga_g == pytest.approx(pga, rel=1e-12)
    assert record.accel_m_s2[0] == 0.0


@pytest.mark.parametrize("envelope", ["saragoni_hart", "trapezoidal"])
def test_envelope_starts_at_zero_peaks_at_one_and_decays_to_the_end_amplitude(envelope):
    t = np.linspace(0.0, 30.0, 3001)
    shape = envelope_shape(t, 30.0, envelope, 0.2, 0.05)
    assert shape[0] == 0.0
    assert np.max(shape) == pytest.approx(1.0, rel=1e-6)
    assert shape[-1] == pytest.approx(0.05, rel=1e-6)
    assert t[np.argmax(shape)] <= 0.2 * 30.0 + 1e-9


def test_motion_is_strongest_in_the_middle_as_the_envelope_says():
    record = synthetic_record(seed=5, duration_s=30.0)
    t = np.arange(record.n_samples) * record.dt_s
    rms = lambda lo, hi: np.sqrt(np.mean(record.accel_m_s2[(t >= lo) & (t < hi)] ** 2))  # noqa: E731
    strong = rms(3.0, 12.0)
    assert rms(0.0, 0.5) < 0.2 * strong
    assert rms(27.0, 30.0) < 0.3 * strong


def test_site_frequency_moves_the_frequency_content():
    soft = [mean_period(synthetic_record(seed=s, omega_g_rad_s=6.0).accel_m_s2, 0.01) for s in range(3)]
    firm = [mean_period(synthetic_record(seed=s, omega_g_rad_s=25.0).accel_m_s2, 0.01) for s in range(3)]
    assert min(soft) > max(firm)


def test_processed_synthetic_motion_ends_at_rest_with_a_bounded_stroke():
    motion = process_record(synthetic_record(seed=2), pga_g=0.3)
    assert abs(motion.displacement_m[-1]) < 1e-9
    assert abs(motion.velocity_m_s[-1]) < 1e-9
    assert motion.pgd_m < 0.5
    assert motion.pga_g * G_M_S2 == pytest.approx(0.3 * G_M_S2, rel=1e-9)


def test_name_and_source_carry_the_seed():
    record = synthetic_record(seed=42)
    assert record.name == "synthetic:42"
    assert "seed 42" in record.source


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"dt_s": 0.0}, "dt_s > 0"),
        ({"pga_g": -0.1}, "pga_g > 0"),
        ({"zeta_g": 0.0}, "zeta_g > 0"),
        ({"duration_s": 0.05}, "duration_s >="),
        ({"omega_g_rad_s": 200.0}, "below half the Nyquist"),
        ({"peak_fraction": 1.0}, "peak_fraction"),
        ({"end_amplitude": 0.0}, "end_amplitude"),
        ({"envelope": "boxcar"}, "unknown envelope"),
    ],
)
def test_bad_parameters_are_refused(kwargs, message):
    with pytest.raises(RecordError, match=message):
        synthetic_record(**kwargs)


@pytest.mark.parametrize(("dt", "omega_g", "zeta_g", "omega_f", "zeta_f"), [
    (0.01, 15.6, 0.6, 1.5, 0.6), (0.005, 12.0, 0.3, 2.0, 0.8), (0.002, 20.0, 1.3, 1.0, 0.6),  # the last overdamped
])
def test_the_written_out_filter_is_scipys_bilinear_clough_penzien(dt, omega_g, zeta_g, omega_f, zeta_f):
    """The sections and their filter, written out to spare the command line scipy.signal's import, against
    ``scipy.signal``'s ``bilinear_zpk``, ``zpk2sos`` and ``sosfilt`` of the same analogue filter."""
    from scipy import signal

    from harness.motions.synthetic import clough_penzien_sos, filter_sections

    zeros = np.array([-omega_g / (2 * zeta_g), 0.0, 0.0])
    poles = np.concatenate([np.roots([1, 2 * zeta_g * omega_g, omega_g**2]), np.roots([1, 2 * zeta_f * omega_f, omega_f**2])])
    reference = signal.zpk2sos(*signal.bilinear_zpk(zeros, poles, 2 * zeta_g * omega_g, fs=1.0 / dt))
    noise = np.random.default_rng(4).standard_normal(4000)
    expected = signal.sosfilt(reference, noise)
    mine = clough_penzien_sos(dt, omega_g, zeta_g, omega_f, zeta_f)
    assert np.max(np.abs(filter_sections(mine, noise) - expected)) < 1e-11 * np.max(np.abs(expected))
    assert np.array_equal(filter_sections(reference, noise), expected)  # the same recursion as sosfilt, to the bit
