"""How well the table followed its drive: error, delay and amplitude (SPEC 7b).

The measures of the real-time hybrid simulation benchmark's evaluation (Silva et al.,
2020), applied to the shaking table: the delay at which the cross-correlation of the
achieved motion with the drive peaks, the RMS and the peak of achieved minus drive, and
the amplitude ratio of the achieved motion to the drive shifted by that delay.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Tracking:
    """Achieved against drive, one signal.

    Attributes
    ----------
    rms_error, peak_error : float
        RMS and largest ``|achieved - drive|`` (the signal's unit).
    rms_error_percent, peak_error_percent : float
        The same, in % of the drive's RMS and peak (NaN for a drive of zero).
    delay_s : float
        Where the cross-correlation peaks (s); positive when the achieved motion lags.
        Found to a fraction of a sample by a parabola through the peak.
    amplitude_ratio : float
        Least-squares gain of the achieved motion on the drive shifted by the delay
        (1: right size; NaN for a drive of zero).
    correlation : float
        Normalized cross-correlation at the delay (1: same shape).
    """

    rms_error: float
    peak_error: float
    rms_error_percent: float
    peak_error_percent: float
    delay_s: float
    amplitude_ratio: float
    correlation: float


def _percent(value: float, reference: float) -> float:
    return 100.0 * value / reference if reference > 0.0 else math.nan


def cross_correlation_delay(achieved: np.ndarray, drive: np.ndarray, dt_s: float, max_lag_s: float) -> tuple[float, float]:
    """Delay of ``achieved`` behind ``drive`` (s) and the normalized correlation there.

    Parameters
    ----------
    achieved, drive : ndarray
        The two signals on one time grid of step ``dt_s`` (s).
    max_lag_s : float
        Lags searched, each way (s).
    """
    a = np.asarray(achieved, dtype=float) - np.mean(achieved)
    d = np.asarray(drive, dtype=float) - np.mean(drive)
    max_lag = max(1, min(int(round(max_lag_s / dt_s)), len(a) - 2))
    lags = np.arange(-max_lag, max_lag + 1)
    scores = np.empty(len(lags))
    for i, lag in enumerate(lags):  # sum over n of a[n] d[n - lag]
        scores[i] = np.dot(a[lag:], d[: len(d) - lag]) if lag >= 0 else np.dot(a[: len(a) + lag], d[-lag:])
    norm = math.sqrt(float(np.dot(a, a)) * float(np.dot(d, d)))
    best, shift = correlation_peak(scores)
    return (float(lags[best]) + shift) * dt_s, float(scores[best] / norm) if norm > 0.0 else math.nan


def correlation_peak(scores: np.ndarray) -> tuple[int, float]:
    """Where a cross-correlation peaks: the index of its largest score and a fraction of a lag step.

    The fraction (in ``(-0.5, 0.5)``) is the vertex of the parabola through the peak and its two
    neighbours; 0 at either end of the lags searched, or where the three do not curve down.

    Parameters
    ----------
    scores : ndarray
        The cross-correlation at consecutive lags (any scale).
    """
    best = int(np.argmax(scores))
    shift = 0.0
    if 0 < best < len(scores) - 1:
        left, mid, right = float(scores[best - 1]), float(scores[best]), float(scores[best + 1])
        curvature = left - 2.0 * mid + right
        shift = 0.5 * (left - right) / curvature if curvature < 0.0 else 0.0
    return best, shift


def tracking(achieved: np.ndarray, drive: np.ndarray, dt_s: float, max_lag_s: float = 0.1) -> Tracking:
    """Achieved against drive (both on one time grid of step ``dt_s``, s).

    Parameters
    ----------
    achieved, drive : ndarray
        Same length, same unit.
    dt_s : float
        Sample step (s).
    max_lag_s : float
        Largest delay searched each way (s).
    """
    achieved = np.asarray(achieved, dtype=float)
    drive = np.asarray(drive, dtype=float)
    if achieved.shape != drive.shape or achieved.size < 3:
        raise ValueError(f"tracking needs two signals of one length of 3 samples or more, got {achieved.shape} and {drive.shape}")
    error = achieved - drive
    rms, peak = float(np.sqrt(np.mean(error**2))), float(np.max(np.abs(error)))
    delay_s, correlation = cross_correlation_delay(achieved, drive, dt_s, max_lag_s)
    shifted = np.interp(np.arange(drive.size) * dt_s - delay_s, np.arange(drive.size) * dt_s, drive)
    energy = float(np.dot(shifted, shifted))
    ratio = float(np.dot(achieved, shifted)) / energy if energy > 0.0 else math.nan
    return Tracking(
        rms_error=rms, peak_error=peak,
        rms_error_percent=_percent(rms, float(np.sqrt(np.mean(drive**2)))),
        peak_error_percent=_percent(peak, float(np.max(np.abs(drive)))),
        delay_s=delay_s, amplitude_ratio=ratio, correlation=correlation,
    )
