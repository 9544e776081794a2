"""A short, spectrum-relevant summary of a ground motion, for ``harness records``; and the
facts of a record that run folders and ``harness simulate --json`` keep (:func:`motion_facts`).

- Peak values PGA (g), PGV (m/s), PGD (m) of the processed triple.
- Arias intensity ``I_a = pi / (2 g) * integral a^2 dt`` (m/s) and the 5-95 %
  significant duration (time between 5 % and 95 % of ``I_a``, Trifunac & Brady 1975).
- Predominant period: the period of the peak of the Fourier amplitude spectrum
  after smoothing it with a running mean ``smoothing_hz`` wide.
- Mean period ``T_m = sum(C_i^2 / f_i) / sum(C_i^2)`` over 0.25-20 Hz
  (Rathje et al. 1998), a steadier measure of the frequency content.

Times and frequencies are in the motion's own (possibly compressed) time axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2
from harness.motions.processing import GroundMotion

#: Band of the mean period (Hz), after Rathje et al. (1998).
MEAN_PERIOD_BAND_HZ = (0.25, 20.0)


@dataclass(frozen=True)
class MotionSummary:
    """Summary figures of a ground motion (SI units; times in the motion's time axis)."""

    name: str
    dt_s: float
    duration_s: float
    pga_g: float
    pgv_m_s: float
    pgd_m: float
    arias_intensity_m_s: float
    significant_duration_s: float
    t5_s: float
    t95_s: float
    predominant_period_s: float
    mean_period_s: float


def arias_history(accel_m_s2: np.ndarray, dt_s: float) -> np.ndarray:
    """Cumulative Arias intensity (m/s) at each sample (trapezoidal integral of a^2)."""
    squared = np.asarray(accel_m_s2, dtype=float) ** 2
    cumulative = np.zeros_like(squared)
    np.cumsum(0.5 * dt_s * (squared[:-1] + squared[1:]), out=cumulative[1:])
    return np.pi / (2.0 * G_M_S2) * cumulative


def fourier_amplitude(accel_m_s2: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """One-sided Fourier amplitude spectrum: frequencies (Hz) and ``|A(f)|`` (m/s)."""
    spectrum = np.abs(np.fft.rfft(accel_m_s2)) * dt_s
    return np.fft.rfftfreq(accel_m_s2.size, dt_s), spectrum


def predominant_period(accel_m_s2: np.ndarray, dt_s: float, smoothing_hz: float = 0.1) -> float:
    """Period (s) of the peak of the smoothed Fourier amplitude spectrum (excluding f = 0)."""
    freqs, amplitude = fourier_amplitude(accel_m_s2, dt_s)
    width = max(1, int(round(smoothing_hz / freqs[1])))
    smoothed = np.convolve(amplitude, np.ones(width) / width, mode="same")
    peak = 1 + int(np.argmax(smoothed[1:]))
    return float(1.0 / freqs[peak])


def mean_period(accel_m_s2: np.ndarray, dt_s: float) -> float:
    """Mean period (s) over :data:`MEAN_PERIOD_BAND_HZ` (limited to the Nyquist frequency)."""
    freqs, amplitude = fourier_amplitude(accel_m_s2, dt_s)
    band = (freqs >= MEAN_PERIOD_BAND_HZ[0]) & (freqs <= MEAN_PERIOD_BAND_HZ[1])
    power = amplitude[band] ** 2
    if not band.any() or power.sum() == 0.0:
        raise RecordError("mean period: the record has no content between 0.25 and 20 Hz")
    return float(np.sum(power / freqs[band]) / np.sum(power))


def summarize(motion: GroundMotion, *, smoothing_hz: float = 0.1) -> MotionSummary:
    """Summarise a processed ground motion.

    Parameters
    ----------
    motion : GroundMotion
        The processed motion.
    smoothing_hz : float
        Width of the running mean applied to the Fourier spectrum (Hz).
    """
    accel = motion.accel_m_s2
    husid = arias_history(accel, motion.dt_s)
    total = float(husid[-1])
    t5, t95 = np.interp([0.05 * total, 0.95 * total], husid, motion.t_s)
    return MotionSummary(
        name=motion.name,
        dt_s=motion.dt_s,
        duration_s=motion.duration_s,
        pga_g=motion.pga_g,
        pgv_m_s=motion.pgv_m_s,
        pgd_m=motion.pgd_m,
        arias_intensity_m_s=total,
        significant_duration_s=float(t95 - t5),
        t5_s=float(t5),
        t95_s=float(t95),
        predominant_period_s=predominant_period(accel, motion.dt_s, smoothing_hz),
        mean_period_s=mean_period(accel, motion.dt_s),
    )


def motion_facts(motion: GroundMotion) -> dict:
    """The facts of a record that a run folder's metadata and ``harness simulate --json`` keep, by key.

    Name, PGA (g), PGV (m/s), PGD (m), time scale, duration (s) and the share of Arias
    intensity the cut left out.
    """
    return {
        "name": motion.name,
        "pga_g": motion.pga_g,
        "pgv_m_s": motion.pgv_m_s,
        "pgd_m": motion.pgd_m,
        "time_scale": motion.time_scale,
        "duration_s": motion.duration_s,
        "arias_left_out": motion.arias_left_out,
    }
