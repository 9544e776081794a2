"""The H1 frequency-response estimate with Welch averaging, its coherence, and its CSV file.

``H1(f) = Pxy(f) / Pxx(f)``: the cross-spectral density of input and output over the
input's power spectral density (:func:`scipy.signal.csd`, :func:`scipy.signal.welch`),
averaged over Hann-windowed segments overlapping by half. Noise on the output averages
out of ``Pxy``, so H1 is unbiased by output noise. The coherence
``|Pxy|^2 / (Pxx Pyy)`` (:func:`scipy.signal.coherence`, the same segments) is the share
of the output's power that the input explains linearly: near 1 where the estimate can be
trusted, lower where noise, nonlinearity or leakage dominate.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import signal

#: Fewest frequencies of an estimate within the band an identification accepts: a fit of a model's parameters,
#: and a Bode plot, need a response over a band, not a point (the SPEC 7a fit frees up to five parameters, the
#: structure's up to two per story; ten bins, each a complex value, leave every one of them overdetermined).
MIN_BAND_BINS = 10
#: The columns of ``frf.csv``: frequency (Hz), |H| (output unit per input unit), phase (deg, unwrapped), coherence (0..1).
FRF_COLUMNS = ("freq_hz", "magnitude", "phase_deg", "coherence")


@dataclass(frozen=True)
class FrequencyResponse:
    """A frequency response on a grid of frequencies.

    Attributes
    ----------
    freq_hz : ndarray
        Frequencies (Hz), ascending.
    magnitude : ndarray
        ``|H|`` (output unit per input unit; N/N for the actuator).
    phase_deg : ndarray
        Phase of H (deg), unwrapped from the lowest frequency up.
    coherence : ndarray
        Ordinary coherence, 0..1.
    """

    freq_hz: np.ndarray
    magnitude: np.ndarray
    phase_deg: np.ndarray
    coherence: np.ndarray

    def within(self, low_hz: float, high_hz: float) -> FrequencyResponse:
        """The part between ``low_hz`` and ``high_hz`` (inclusive), its phase unwrapped again from ``low_hz``."""
        keep = (self.freq_hz >= low_hz) & (self.freq_hz <= high_hz)
        phase = np.degrees(np.unwrap(np.radians(self.phase_deg[keep])))
        return FrequencyResponse(self.freq_hz[keep], self.magnitude[keep], phase, self.coherence[keep])

    @property
    def magnitude_db(self) -> np.ndarray:
        """``20 log10 |H|`` (dB)."""
        return 20.0 * np.log10(np.maximum(self.magnitude, 1e-300))


def h1_estimate(x: np.ndarray, y: np.ndarray, rate_hz: float, segment_samples: int) -> FrequencyResponse:
    """The H1 estimate of the response from ``x`` (input) to ``y`` (output), with its coherence.

    Parameters
    ----------
    x, y : ndarray
        Input and output, sampled together at ``rate_hz`` (same length).
    rate_hz : float
        Sample rate (Hz).
    segment_samples : int
        Samples per Welch segment (the resolution is ``rate_hz / segment_samples``); capped at
        the signals' length. Segments overlap by half and are Hann-windowed, with their mean removed;
        both signals are padded with zeros to fill the last segment, so no sample is left out.

    Returns
    -------
    FrequencyResponse
        From 0 Hz to the Nyquist frequency; the phase is unwrapped from 0 Hz.
    """
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    if x.shape != y.shape or x.ndim != 1:
        raise ValueError(f"expected input and output of the same length, found shapes {x.shape} and {y.shape}")
    nperseg = min(int(segment_samples), len(x))
    hop = nperseg - nperseg // 2
    # Welch drops the samples after the last whole segment: pad both with zeros up to a whole hop instead
    # (a chirp's highest frequencies are its last samples).
    pad = (-(len(x) - nperseg)) % hop
    x, y = np.pad(x, (0, pad)), np.pad(y, (0, pad))
    welch = {"fs": rate_hz, "window": "hann", "nperseg": nperseg, "noverlap": nperseg // 2, "detrend": "constant"}
    freq, pxx = signal.welch(x, **welch)
    _, pxy = signal.csd(x, y, **welch)
    _, coherence = signal.coherence(x, y, **welch)
    with np.errstate(divide="ignore", invalid="ignore"):
        h = np.where(pxx > 0, pxy / np.where(pxx > 0, pxx, 1.0), np.nan)
    phase = np.degrees(np.unwrap(np.nan_to_num(np.angle(h))))
    return FrequencyResponse(freq, np.abs(h), phase, np.clip(coherence, 0.0, 1.0))


def write_frf_csv(path: Path, response: FrequencyResponse) -> Path:
    """Write ``response`` as CSV with the header :data:`FRF_COLUMNS`; returns ``path``."""
    table = np.column_stack([response.freq_hz, response.magnitude, response.phase_deg, response.coherence])
    np.savetxt(path, table, delimiter=",", header=",".join(FRF_COLUMNS), comments="", fmt="%.9g")
    return path


def read_frf_csv(path: Path) -> FrequencyResponse:
    """Read a file :func:`write_frf_csv` wrote.

    Raises
    ------
    ValueError
        If its header is not :data:`FRF_COLUMNS`.
    """
    with open(path, encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
    if tuple(header) != FRF_COLUMNS:
        raise ValueError(f"{path}: found columns {header}, expected {list(FRF_COLUMNS)}")
    table = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    return FrequencyResponse(table[:, 0], table[:, 1], table[:, 2], table[:, 3])
