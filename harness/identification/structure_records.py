"""The structure's identification data: base-mat acceleration in, floor accelerations out, band-passed alike.

The superstructure feels its base only through the base mat's absolute acceleration ``a_b``
(Eq. 1: the floors' equations hold the drifts, which are relative to the base mat, and
``a_j = a_b + sum_{k<=j} xddot_k``). So the response from ``a_b`` to the floor accelerations
``a_j`` is the fixed-base structure's, whatever the bearings, the actuator or the table do:
sliding, sticking and control all stay outside it. That is why any run that moves the base
mat broadly enough identifies the structure, a white-noise table motion best.

Input and outputs are filtered by the same zero-phase Butterworth band-pass (a linear filter
applied to both sides keeps the input-output relation), which removes sensor offsets and
drift below the band and noise above it, then decimated to about :data:`SAMPLES_PER_CORNER`
samples per period of the upper corner (the models are discretised exactly for any step:
:mod:`harness.identification.lti`). :func:`frf_estimate` gives the measured frequency
response for the plots and the fit's starting point.

The input is the one place where noise biases the fit. Noise on the outputs averages out of an
output-error fit; noise on the input does not: the model driven by it answers the noise too, and
the fit lowers the resonance to answer it less, overstating the damping. The input is weakest
exactly at the first fixed-base mode, where the superstructure holds the base mat still (the
base mat's antiresonance), so there the accelerometer's noise floor (0.02 m/s^2 on the shipped
rig) is a large share of ``a_b``: on the virtual rig at 1 % true damping, 0.0127 with the
accelerometer alone (60 s of 0.1 g white noise), 15 standard errors off. The base mat's velocity
sensor differentiated is far quieter at low frequency (its noise grows with frequency, the
accelerometer's does not), so :func:`base_acceleration_estimate` takes ``a_b`` from both: the
derivative of the velocity below the crossover where their noise is equal (``sigma_a / (2 pi
sigma_v)``, 16 Hz on the shipped rig), the accelerometer above it (a complementary, zero-phase
pair of filters, so the true signal passes unchanged); there the same run gives 0.0097.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import signal

#: Upper corner of the band-pass as a multiple of the band's highest frequency.
UPPER_CORNER_FACTOR = 1.5
#: Lower corner of the band-pass as a fraction of the band's lowest frequency.
LOWER_CORNER_FACTOR = 0.5
#: Samples per period of the upper corner after decimation, at least.
SAMPLES_PER_CORNER = 4


@dataclass(frozen=True)
class StructureRecord:
    """One run's input and outputs, band-passed and decimated.

    Attributes
    ----------
    label : str
    rate_hz : float
        Sample rate after decimation (Hz).
    base_acceleration : ndarray (N,)
        ``a_b`` (m/s^2).
    floor_accelerations : ndarray (n, N)
        ``a_1 .. a_n`` (m/s^2), floor 1 first.
    """

    label: str
    rate_hz: float
    base_acceleration: np.ndarray
    floor_accelerations: np.ndarray

    @property
    def dt_s(self) -> float:
        return 1.0 / self.rate_hz

    @property
    def duration_s(self) -> float:
        return (len(self.base_acceleration) - 1) / self.rate_hz


def band_passed(label: str, rate_hz: float, base: np.ndarray, floors: Sequence[np.ndarray],
                band_hz: tuple[float, float]) -> StructureRecord:
    """Filter input and outputs alike for ``band_hz`` and decimate; see the module docstring."""
    upper = min(UPPER_CORNER_FACTOR * band_hz[1], 0.4 * rate_hz)
    lower = LOWER_CORNER_FACTOR * band_hz[0]
    sos = signal.butter(4, [lower, upper], btype="bandpass", fs=rate_hz, output="sos")
    step = max(1, int(rate_hz // (SAMPLES_PER_CORNER * upper)))
    base_f = signal.sosfiltfilt(sos, np.asarray(base, dtype=float))[::step]
    floors_f = np.array([signal.sosfiltfilt(sos, np.asarray(f, dtype=float))[::step] for f in floors])
    return StructureRecord(label, rate_hz / step, np.ascontiguousarray(base_f), np.ascontiguousarray(floors_f))


def crossover_hz(acceleration_noise_m_s2: float, velocity_noise_m_s: float, rate_hz: float) -> float:
    """Where the differentiated velocity's noise equals the accelerometer's (Hz), at most 0.4 of the rate.

    0 for a noiseless accelerometer (used alone).

    White noise of standard deviation ``sigma_v`` differentiated has ``(2 pi f sigma_v)^2`` times
    the accelerometer's white density per ``sigma_a^2``: equal at ``f = sigma_a / (2 pi sigma_v)``.
    """
    if acceleration_noise_m_s2 <= 0.0:
        return 0.0
    if velocity_noise_m_s <= 0.0:
        return 0.4 * rate_hz
    return min(acceleration_noise_m_s2 / (2.0 * np.pi * velocity_noise_m_s), 0.4 * rate_hz)


def base_acceleration_estimate(rate_hz: float, acceleration: np.ndarray, velocity: np.ndarray, crossover: float) -> np.ndarray:
    """``a_b`` from the accelerometer and the velocity sensor: ``a + L (dv/dt - a)``.

    ``crossover`` (Hz) is the corner of ``L``.

    ``L`` is a first-order Butterworth run forward and back (gain ``1 / (1 + (f / f_c)^2)``, no
    phase), so ``L`` and ``1 - L`` add up to one: the true acceleration passes unchanged, the
    velocity's derivative (central differences) carries it below ``f_c`` and the accelerometer
    above. A ``crossover`` of 0 gives the accelerometer alone.
    """
    acceleration = np.asarray(acceleration, dtype=float)
    if crossover <= 0.0:
        return acceleration
    derivative = np.gradient(np.asarray(velocity, dtype=float)) * rate_hz
    sos = signal.butter(1, crossover, fs=rate_hz, output="sos")
    return acceleration + signal.sosfiltfilt(sos, derivative - acceleration)


@dataclass(frozen=True)
class MeasuredResponse:
    """The measured response from the base mat's acceleration to each floor's (H1, Welch over every record).

    Attributes
    ----------
    freq_hz : ndarray (F,)
    response : ndarray (n, F), complex
        ``H_j(f) = a_j / a_b``.
    coherence : ndarray (n, F)
    """

    freq_hz: np.ndarray
    response: np.ndarray
    coherence: np.ndarray


def frf_estimate(records: Sequence[StructureRecord], resolution_hz: float) -> MeasuredResponse:
    """H1 = sum Pxy / sum Pxx over the records (each record's spectra weighted by its length), and the coherence.

    The Welch segment is the power of two of samples nearest ``rate / resolution_hz``, cut to
    a quarter of the shortest record (at least 7 averages at 50 % overlap).
    """
    rate = records[0].rate_hz
    shortest = min(len(r.base_acceleration) for r in records)
    segment = int(2 ** round(np.log2(rate / resolution_hz)))
    segment = max(16, min(segment, int(2 ** np.floor(np.log2(shortest / 4)))))
    pxx = pyy = pxy = None
    for record in records:
        weight = len(record.base_acceleration)
        freq, xx = signal.welch(record.base_acceleration, fs=rate, nperseg=segment)
        yy = np.array([signal.welch(y, fs=rate, nperseg=segment)[1] for y in record.floor_accelerations])
        xy = np.array([signal.csd(record.base_acceleration, y, fs=rate, nperseg=segment)[1] for y in record.floor_accelerations])
        pxx = weight * xx if pxx is None else pxx + weight * xx
        pyy = weight * yy if pyy is None else pyy + weight * yy
        pxy = weight * xy if pxy is None else pxy + weight * xy
    assert pxx is not None and pyy is not None and pxy is not None
    floor = np.finfo(float).tiny
    response = pxy / np.maximum(pxx, floor)
    coherence = np.abs(pxy) ** 2 / np.maximum(pxx * pyy, floor)
    return MeasuredResponse(freq, response, np.clip(coherence, 0.0, 1.0))
