"""Standard errors of a least-squares fit to time series, and when a parameter counts as determined.

The covariance of the fitted parameters is the Gauss-Newton one, ``s^2 (J'J)^-1`` with
``s^2 = sum(r^2) / (N - p)``, inflated by the residuals' integrated autocorrelation time
``tau = 1 + 2 sum_k rho_k``: residuals of filtered time series are correlated over many
samples, so ``N`` samples hold only about ``N / tau`` independent ones, and the plain formula
would claim errors ``sqrt(tau)`` times too small. The sum runs over lags until the
autocorrelation first drops below zero (Geyer's initial positive sequence, simplified).

A parameter the data cannot determine shows as a large relative standard error (its
direction in parameter space changes the residuals little); :func:`covariance` uses the
pseudo-inverse, so a singular ``J'J`` gives large, finite variances rather than an error.
"""

from __future__ import annotations

import numpy as np

#: Lags of the autocorrelation looked at, at most.
MAX_LAG = 2000


def correlation_time(residuals: np.ndarray) -> float:
    """The integrated autocorrelation time of ``residuals`` (samples, at least 1)."""
    r = np.asarray(residuals, dtype=float)
    r = r - r.mean()
    n = len(r)
    if n < 4 or not np.any(r):
        return 1.0
    size = int(2 ** np.ceil(np.log2(2 * n)))
    spectrum = np.fft.rfft(r, size)
    autocovariance = np.fft.irfft(spectrum * np.conj(spectrum), size)[: min(n, MAX_LAG)]
    rho = autocovariance / autocovariance[0]
    negative = np.nonzero(rho[1:] <= 0.0)[0]
    end = int(negative[0]) + 1 if len(negative) else len(rho)
    return float(max(1.0, 1.0 + 2.0 * rho[1:end].sum()))


def covariance(jacobian: np.ndarray, residuals: np.ndarray, correlation_samples: float = 1.0) -> np.ndarray:
    """Covariance of the parameters of a least-squares fit (the parameters' own units).

    Parameters
    ----------
    jacobian : ndarray (N, p)
        d residual / d parameter at the solution.
    residuals : ndarray (N,)
        The residuals at the solution.
    correlation_samples : float
        The residuals' integrated autocorrelation time (:func:`correlation_time`); 1 for
        independent residuals.
    """
    n, p = jacobian.shape
    dof = max(n - p, 1)
    variance = float(residuals @ residuals) / dof
    return np.linalg.pinv(jacobian.T @ jacobian) * variance * max(correlation_samples, 1.0)


def relative_error(value: float, standard_error: float) -> float:
    """``standard_error / |value|``; infinite for a zero value with any error."""
    if value == 0.0:
        return 0.0 if standard_error == 0.0 else float("inf")
    return abs(standard_error / value)
