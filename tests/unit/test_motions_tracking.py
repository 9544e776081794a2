"""Tracking of the table's drive: delay from the cross-correlation, RMS and peak error, amplitude ratio."""

from __future__ import annotations

import numpy as np
import pytest

from harness.motions.tracking import cross_correlation_delay, tracking

DT = 0.002


def _record(seconds: float = 20.0, seed: int = 4) -> np.ndarray:
    """A band-limited random 'record' (a few Hz), smooth enough to shift by a fraction of a sample."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, DT)
    return sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 6.28)) for f in rng.uniform(0.3, 6.0, 25))


@pytest.mark.parametrize("delay_s", [0.0, 0.007, 0.0133, -0.004])
def test_the_delay_and_amplitude_of_a_shifted_scaled_copy_are_found(delay_s: float) -> None:
    drive = _record()
    t = np.arange(drive.size) * DT
    achieved = 0.9 * np.interp(t - delay_s, t, drive)
    measured = tracking(achieved, drive, DT)
    assert measured.delay_s == pytest.approx(delay_s, abs=0.2 * DT)  # a fraction of a sample
    assert measured.amplitude_ratio == pytest.approx(0.9, rel=0.01)
    assert measured.correlation > 0.99


def test_rms_and_peak_errors_in_the_signals_unit_and_percent() -> None:
    drive = np.sin(np.linspace(0, 20 * np.pi, 5000))
    achieved = drive + 0.1
    measured = tracking(achieved, drive, DT)
    assert measured.rms_error == pytest.approx(0.1) and measured.peak_error == pytest.approx(0.1)
    assert measured.rms_error_percent == pytest.approx(100 * 0.1 / np.sqrt(0.5), rel=1e-3)
    assert measured.peak_error_percent == pytest.approx(10.0, rel=1e-3)


def test_a_different_record_correlates_poorly_whatever_the_lag() -> None:
    _, correlation = cross_correlation_delay(_record(seed=1), _record(seed=2), DT, 0.1)
    assert abs(correlation) < 0.5


def test_signals_of_different_lengths_are_refused() -> None:
    with pytest.raises(ValueError, match="one length"):
        tracking(np.zeros(10), np.zeros(11), DT)
