"""How well the table follows its drive, measured online: the cross-correlation accumulated sample by sample.

The same measures as :func:`harness.motions.tracking.tracking` (the delay at which the
cross-correlation of the achieved motion with the drive peaks, the normalized correlation
there, and the least-squares amplitude ratio of the achieved motion on the drive shifted by
that delay), over the window from the first sample to the latest, for a control loop:

- :meth:`OnlineTracking.add` takes one achieved sample and adds its product with the drive
  at every lag searched to running sums: O(lags), no allocation (a compiled kernel);
- :meth:`OnlineTracking.evaluate` turns the running sums into the measures: O(lags), from
  prefix sums of the drive computed once before the run; never O(samples).

The drive is known before the run (the record the table was told to play); before its
first sample and after its last, the drive is at rest (zero), as a table's velocity drive is
while it holds. The sums run over the samples added; the means are removed as
:func:`~harness.motions.tracking.cross_correlation_delay` removes them, and the peak is
refined by the same parabola (:func:`~harness.motions.tracking.correlation_peak`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from harness.motions.tracking import correlation_peak


@numba.njit(cache=True, nogil=True)
def accumulate_products(sums: np.ndarray, padded_drive: np.ndarray, start: int, value: float) -> None:
    """``sums[k] += value * padded_drive[start + k]`` for every ``k`` of ``sums`` (in place, no allocation)."""
    for k in range(sums.size):
        sums[k] += value * padded_drive[start + k]


class OnlineTracking:
    """Achieved against a known drive, one sample at a time.

    Parameters
    ----------
    drive : ndarray
        The drive on the sample grid (sample ``n`` at ``n * dt_s``; the signal's unit).
    dt_s : float
        Sample step (s).
    max_lag_s : float
        Largest delay searched each way (s); at least one step.

    Attributes
    ----------
    count : int
        Samples added (the next one is sample ``count``).
    delay_s, correlation, amplitude_ratio : float
        The last :meth:`evaluate`'s measures (NaN before it, or where undefined): the delay of the
        achieved motion behind the drive (s), the normalized cross-correlation there, and the
        least-squares gain of the achieved motion on the drive shifted by that delay.
    at_edge : bool
        The last evaluation's peak lay at the end of the lags searched (no peak inside them).
    """

    __slots__ = (
        "dt_s", "max_lag", "length", "count", "delay_s", "correlation", "amplitude_ratio", "at_edge",
        "_padded", "_prefix", "_prefix_squares", "_products", "_drive_sums", "_drive_squares", "_scores",
        "_sum", "_sum_squares",
    )

    def __init__(self, drive: np.ndarray, dt_s: float, max_lag_s: float) -> None:
        drive = np.asarray(drive, dtype=float)
        if drive.ndim != 1 or drive.size < 3 or not np.all(np.isfinite(drive)):
            raise ValueError(f"online tracking needs a finite drive of 3 samples or more, got shape {drive.shape}")
        if not (dt_s > 0.0 and max_lag_s > 0.0):
            raise ValueError(f"online tracking needs dt_s > 0 and max_lag_s > 0, got {dt_s!r} and {max_lag_s!r}")
        self.dt_s = float(dt_s)
        lag = self.max_lag = max(1, int(round(max_lag_s / dt_s)))
        self.length = drive.size
        padded = np.zeros(drive.size + 2 * lag + 1)  # at rest before and after the drive
        padded[lag : lag + drive.size] = drive
        self._padded = padded
        self._prefix = np.concatenate(([0.0], np.cumsum(padded)))
        self._prefix_squares = np.concatenate(([0.0], np.cumsum(padded**2)))
        width = 2 * lag + 1
        # _products[k] = sum over n of achieved[n] * padded[n + k] = sum of achieved[n] * drive[n - (lag - k)]
        self._products = np.zeros(width)
        self._drive_sums = np.zeros(width)
        self._drive_squares = np.zeros(width)
        self._scores = np.zeros(width)
        self.reset()

    def reset(self) -> None:
        """Forget every sample added."""
        self._products[:] = 0.0
        self.count = 0
        self._sum = 0.0
        self._sum_squares = 0.0
        self.delay_s = self.correlation = self.amplitude_ratio = math.nan
        self.at_edge = False

    def add(self, achieved: float) -> bool:
        """Add the achieved value of sample :attr:`count`; False (nothing added) past the drive's end."""
        n = self.count
        if n >= self.length:
            return False
        accumulate_products(self._products, self._padded, n, achieved)
        self._sum += achieved
        self._sum_squares += achieved * achieved
        self.count = n + 1
        return True

    def drive_rms(self) -> float:
        """RMS of the drive over the samples added so far (0 before any)."""
        n, lag = self.count, self.max_lag
        if n == 0:
            return 0.0
        return math.sqrt(max(0.0, (self._prefix_squares[n + lag] - self._prefix_squares[lag]) / n))

    def evaluate(self) -> None:
        """Set :attr:`delay_s`, :attr:`correlation`, :attr:`amplitude_ratio` and :attr:`at_edge` from the samples so far."""
        n, lag = self.count, self.max_lag
        width = 2 * lag + 1
        if n < 3:
            self.delay_s = self.correlation = self.amplitude_ratio = math.nan
            self.at_edge = False
            return
        sums, squares, scores = self._drive_sums, self._drive_squares, self._scores
        np.subtract(self._prefix[n : n + width], self._prefix[:width], out=sums)  # sum of drive[n - lag'] per lag'
        np.subtract(self._prefix_squares[n : n + width], self._prefix_squares[:width], out=squares)
        mean = self._sum / n
        drive_mean = sums[lag] / n  # over the window itself (lag 0)
        # sum of (a - mean)(d_lag - drive_mean) = products - mean * sums (the drive_mean terms cancel: sum(a) = n mean)
        np.multiply(sums, -mean, out=scores)
        scores += self._products
        variance = self._sum_squares - n * mean * mean
        drive_variance = squares[lag] - n * drive_mean * drive_mean
        # _products is indexed by k = lag - (delay in samples): reversed, the delays ascend
        best_k, shift = correlation_peak(scores[::-1])
        best = width - 1 - best_k  # back to k
        self.at_edge = best_k in (0, width - 1)
        self.delay_s = (best_k - lag + shift) * self.dt_s
        norm = math.sqrt(variance * drive_variance) if variance > 0.0 and drive_variance > 0.0 else 0.0
        self.correlation = float(scores[best]) / norm if norm > 0.0 else math.nan
        neighbour = best - 1 if shift > 0.0 else best + 1  # a larger delay is a smaller k
        weight = abs(shift) if 0 <= neighbour < width else 0.0
        products = (1.0 - weight) * self._products[best] + (weight * self._products[neighbour] if weight else 0.0)
        energy = (1.0 - weight) * squares[best] + (weight * squares[neighbour] if weight else 0.0)
        self.amplitude_ratio = float(products / energy) if energy > 0.0 else math.nan
