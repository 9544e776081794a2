"""The H1 estimate (harness/identification/frf.py) on synthetic data with a known transfer function."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import signal

from harness.identification.excitation import excitation_signal
from harness.identification.excitation_settings import Excitation
from harness.identification.frf import FRF_COLUMNS, FrequencyResponse, h1_estimate, read_frf_csv, write_frf_csv

RATE_HZ = 500.0
SEGMENT = 1024  # 0.49 Hz resolution


def _second_order(natural_hz: float = 8.0, damping: float = 0.2):
    """A unit-gain second-order low-pass, discretised with a zero-order hold at RATE_HZ (so the reference is exact)."""
    wn = 2 * np.pi * natural_hz
    continuous = signal.lti([wn**2], [1.0, 2 * damping * wn, wn**2])
    return continuous.to_ss().to_discrete(1.0 / RATE_HZ, method="zoh")


def _band_noise(n: int, low_hz: float, high_hz: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    freq = np.fft.rfftfreq(n, 1.0 / RATE_HZ)
    spectrum[(freq < low_hz) | (freq > high_hz)] = 0.0
    x = np.fft.irfft(spectrum, n)
    return x / x.std()


def _respond(system, x: np.ndarray) -> np.ndarray:
    numerator, denominator = signal.ss2tf(system.A, system.B, system.C, system.D)
    return signal.lfilter(numerator[0], denominator, x)  # the state space's response from rest, as dlsim gives it


def _reference(system, freq_hz: np.ndarray) -> np.ndarray:
    """H(z) = C (zI - A)^-1 B + D on the unit circle, straight from the state space."""
    a, b, c, d = system.A, system.B, system.C, system.D
    z = np.exp(2j * np.pi * freq_hz / RATE_HZ)
    return np.array([(c @ np.linalg.solve(zk * np.eye(len(a)) - a, b) + d)[0, 0] for zk in z])


def test_h1_recovers_a_second_order_system_with_noise_on_the_output():
    system = _second_order()
    x = _band_noise(60_000, 0.5, 60.0, seed=1)
    y = _respond(system, x)
    y_noisy = y + 0.05 * y.std() * np.random.default_rng(2).standard_normal(len(y))
    response = h1_estimate(x, y_noisy, RATE_HZ, SEGMENT).within(1.0, 40.0)
    truth = _reference(system, response.freq_hz)
    magnitude_error = np.abs(response.magnitude / np.abs(truth) - 1.0)
    phase_error = np.abs(response.phase_deg - np.degrees(np.unwrap(np.angle(truth))))
    # Stated tolerances: 5 % in magnitude and 3 degrees in phase, where coherence says the estimate is good.
    good = response.coherence > 0.9
    assert good[response.freq_hz < 20.0].all()  # above, the output's noise meets the roll-off (|H| < 0.2)
    assert magnitude_error[good].max() < 0.05, magnitude_error[good].max()
    assert phase_error[good].max() < 3.0, phase_error[good].max()
    # The resonance's phase: -90 degrees at the natural frequency, close to -180 at 40 Hz.
    assert np.interp(8.0, response.freq_hz, response.phase_deg) == pytest.approx(-90.0, abs=5.0)
    assert response.phase_deg[-1] < -150.0
    assert np.median(response.coherence) > 0.98


def test_h1_is_not_biased_by_output_noise_but_coherence_drops_with_it():
    system = _second_order()
    x = _band_noise(400_000, 0.5, 60.0, seed=3)
    y = _respond(system, x)
    noisy = y + 3.0 * y.std() * np.random.default_rng(4).standard_normal(len(y))  # noise stronger than the signal
    clean = h1_estimate(x, y, RATE_HZ, SEGMENT).within(1.0, 6.0)
    loud = h1_estimate(x, noisy, RATE_HZ, SEGMENT).within(1.0, 6.0)
    truth = np.abs(_reference(system, loud.freq_hz))
    assert np.median(np.abs(loud.magnitude / truth - 1.0)) < 0.06  # averaged out of Pxy
    assert np.median(loud.coherence) < 0.6 < 0.99 < np.median(clean.coherence)


def test_coherence_drops_where_noise_dominates():
    system = _second_order()
    x = _band_noise(60_000, 1.0, 20.0, seed=5)  # no input above 20 Hz
    y = _respond(system, x) + 0.02 * np.random.default_rng(6).standard_normal(len(x))
    response = h1_estimate(x, y, RATE_HZ, SEGMENT)
    in_band = (response.freq_hz > 2.0) & (response.freq_hz < 18.0)
    noise_only = (response.freq_hz > 40.0) & (response.freq_hz < 200.0)
    assert response.coherence[in_band].min() > 0.95
    assert np.median(response.coherence[noise_only]) < 0.2


def test_a_chirp_is_estimated_up_to_the_top_of_its_band():
    """The chirp's highest frequencies are its last samples: none may be dropped by the segmenting."""
    excitation = Excitation("chirp", 1000.0, (1.0, 30.0), 20.0, resolution_hz=0.25)
    x = excitation_signal(excitation, RATE_HZ)
    y = np.concatenate([[0.0], x[:-1]])  # one sample of delay: |H| = 1, phase -360 f / RATE_HZ
    response = h1_estimate(x, y, RATE_HZ, excitation.segment_samples(RATE_HZ)).within(1.0, 30.0)
    top = response.freq_hz > 25.0
    assert top.any()
    assert response.coherence[top].min() > 0.99
    assert np.abs(response.magnitude[top] - 1.0).max() < 0.02
    expected_phase = -360.0 * response.freq_hz / RATE_HZ
    assert np.abs(response.phase_deg - expected_phase).max() < 1.0


def test_within_keeps_the_band_and_unwraps_from_its_bottom():
    freq = np.linspace(0.0, 100.0, 401)
    wrapped = np.degrees(np.angle(np.exp(-1j * 2 * np.pi * freq * 0.05)))  # a 50 ms delay, wrapped to +-180
    response = FrequencyResponse(freq, np.ones_like(freq), wrapped, np.ones_like(freq)).within(10.0, 60.0)
    assert response.freq_hz[0] == 10.0 and response.freq_hz[-1] == 60.0
    assert np.all(np.diff(response.phase_deg) < 0)  # monotonic lag, no jumps of 360
    assert response.phase_deg[-1] - response.phase_deg[0] == pytest.approx(-360.0 * 50.0 * 0.05)


def test_the_csv_has_the_four_columns_and_reads_back(tmp_path):
    freq = np.array([1.0, 2.0, 4.0])
    response = FrequencyResponse(freq, np.array([1.0, 0.9, 0.5]), np.array([-5.0, -20.0, -80.0]), np.array([1.0, 0.99, 0.9]))
    path = write_frf_csv(tmp_path / "frf.csv", response)
    assert path.read_text().splitlines()[0] == ",".join(FRF_COLUMNS) == "freq_hz,magnitude,phase_deg,coherence"
    back = read_frf_csv(path)
    np.testing.assert_allclose(back.phase_deg, response.phase_deg)
    np.testing.assert_allclose(back.magnitude, response.magnitude)
    (tmp_path / "other.csv").write_text("f,m\n1,2\n")
    with pytest.raises(ValueError, match="expected"):
        read_frf_csv(tmp_path / "other.csv")


def test_h1_refuses_signals_of_different_lengths():
    with pytest.raises(ValueError, match="same length"):
        h1_estimate(np.zeros(100), np.zeros(99), RATE_HZ, 64)
