"""Standard errors of a least-squares fit to time series, and when a parameter counts as determined.

The covariance of the fitted parameters is the Gauss-Newton one, ``s^2 (J'J)^-1`` with
``s^2 = sum(r^2) / (N - p)``, inflated by the residuals' integrated autocorrelation time
``tau = 1 + 2 sum_k rho_k``: residuals of filtered time series are correlated over many
samples, so ``N`` samples hold only about ``N / tau`` independent ones, and the plain formula
would claim errors ``sqrt(tau)`` times too small. The sum runs over lags until the
autocorrelation first drops below zero (Geyer's initial positive sequence, simplified).

The Gauss-Newton covariance trusts the model and the residuals' stationarity; a fit whose
residuals hold model error or change along the record claims too little. :func:`block_covariance`
estimates it from the data instead: the record is cut into ``B`` consecutive blocks of time, each
block's score ``g_b = J_b' r_b`` is what the block pulls the parameters by, and their spread gives
the sandwich ``(J'J)^-1 (B / (B - 1) sum g_b g_b') (J'J)^-1`` (a batch-means, or block-jackknife,
estimate: blocks much longer than the residuals' correlation time are nearly independent). With
few blocks the estimate is itself uncertain, so the 95 % interval is Student's t with ``B - 1``
degrees of freedom times the standard error (:func:`interval_95`), and the standard error stated
is the larger of the two estimates (:func:`honest_standard_errors`).

A parameter the data cannot determine shows as a large relative standard error (its
direction in parameter space changes the residuals little); :func:`covariance` uses the
pseudo-inverse, so a singular ``J'J`` gives large, finite variances rather than an error.
"""

from __future__ import annotations

import numpy as np
from scipy import stats

#: Lags of the autocorrelation looked at, at most.
MAX_LAG = 2000
#: Blocks of time a record is cut into for :func:`block_covariance`.
BLOCKS = 8


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


def time_blocks(samples: int, blocks: int = BLOCKS) -> np.ndarray:
    """The block (0 .. ``blocks - 1``) of each of a record's ``samples`` samples: equal consecutive stretches of time."""
    return np.minimum(np.arange(samples) * blocks // max(samples, 1), blocks - 1)


def block_covariance(jacobian: np.ndarray, residuals: np.ndarray, block_of_residual: np.ndarray) -> np.ndarray:
    """The sandwich covariance from the blocks' scores; see the module docstring.

    Parameters
    ----------
    jacobian : ndarray (N, p)
    residuals : ndarray (N,)
    block_of_residual : ndarray (N,) of int
        Which block of time each residual belongs to (:func:`time_blocks` of each sample, laid out as the residuals are).
    """
    labels = np.unique(block_of_residual)
    scores = np.array([jacobian[block_of_residual == b].T @ residuals[block_of_residual == b] for b in labels])
    count = len(labels)
    scores = scores - scores.mean(axis=0)  # at the optimum they add up to zero; this keeps a bounded fit honest too
    middle = scores.T @ scores * count / max(count - 1, 1)
    bread = np.linalg.pinv(jacobian.T @ jacobian)
    return bread @ middle @ bread


def honest_standard_errors(
    jacobian: np.ndarray, residuals: np.ndarray, block_of_residual: np.ndarray, gradient: np.ndarray | None = None,
) -> np.ndarray:
    """Per parameter, the larger of the Gauss-Newton standard error (residuals' correlation time in) and the blocks' one.

    Parameters
    ----------
    jacobian : ndarray (N, p)
        Of the residuals with respect to the fit's parameters.
    residuals : ndarray (N,)
    block_of_residual : ndarray (N,) of int
        Which block of time each residual belongs to (:func:`time_blocks`).
    gradient : ndarray (q, p), optional
        The linear map from the fit's parameters to the values reported (their derivatives at the
        solution); both covariances go through it before the larger is taken. None: the fit's own.
    """
    model = covariance(jacobian, residuals, correlation_time(residuals))
    data = block_covariance(jacobian, residuals, block_of_residual)
    if gradient is not None:
        model, data = gradient @ model @ gradient.T, gradient @ data @ gradient.T
    return np.sqrt(np.maximum(np.maximum(np.diag(model), np.diag(data)), 0.0))


def t_factor_95(blocks: int = BLOCKS) -> float:
    """Student's t for a two-sided 95 % interval with ``blocks - 1`` degrees of freedom (2.36 for 8 blocks)."""
    return float(stats.t.ppf(0.975, max(blocks - 1, 1)))


def interval_95(value: float, standard_error: float, blocks: int = BLOCKS) -> tuple[float, float]:
    """The stated 95 % interval: ``value -/+ t_factor_95(blocks) * standard_error``."""
    half = t_factor_95(blocks) * standard_error
    return value - half, value + half


def relative_error(value: float, standard_error: float) -> float:
    """``standard_error / |value|``; infinite for a zero value with any error."""
    if value == 0.0:
        return 0.0 if standard_error == 0.0 else float("inf")
    return abs(standard_error / value)
