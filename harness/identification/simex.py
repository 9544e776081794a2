"""Simulation-extrapolation (SIMEX) for a fit whose input is measured with noise, and the noise's estimate.

A fit whose *input* carries noise (errors in variables) is biased, and least squares does not
average the bias out. SIMEX (Cook & Stefanski, "Simulation-extrapolation estimation in
parametric measurement error models", JASA 89(428), 1994; Carroll, Ruppert, Stefanski &
Crainiceanu, "Measurement Error in Nonlinear Models", 2nd ed., 2006, ch. 5) measures the bias
instead of modelling it: the input is given *more* noise, of variance ``lambda sigma^2`` on top
of the ``sigma^2`` it has, the fit is repeated, and the estimate is followed as a function of
``lambda`` (the total noise variance is ``(1 + lambda) sigma^2``). A quadratic in ``lambda``
through the averaged estimates (the usual extrapolant, Carroll et al. section 5.3.2),
extrapolated to ``lambda = -1`` (no noise), is the corrected estimate.

Here: :func:`noise_std` estimates a sensor's noise from its own samples, and :func:`extrapolate`
turns the estimates at each ``lambda`` into the corrected value and the extrapolation's own
(Monte Carlo) standard error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Order of the differences of :func:`noise_std`.
DIFFERENCE_ORDER = 3
#: MAD of a standard normal variable: the median of |Z|.
_MAD_NORMAL = 0.6744897501960817
#: Differences beyond this many robust standard deviations are the motion's, not the noise's.
OUTLIER_SIGMAS = 5.0


def noise_std(samples: np.ndarray, order: int = DIFFERENCE_ORDER) -> float:
    """The standard deviation of a signal's white noise, from its own samples (its unit).

    The ``order``-th difference of the samples, ``sum_i (-1)^i C(order, i) y[k - i]``, removes a
    smooth signal (a polynomial of degree below ``order`` exactly; a motion well below the
    sample rate to ``(2 pi f dt)^order`` of its size), and keeps the white noise with the
    variance ``C(2 order, order) sigma^2``. The few differences where the motion is not smooth
    (a friction reversal's kink, a stick's start) are left out: those beyond
    :data:`OUTLIER_SIGMAS` times a robust first estimate (the median absolute difference over
    0.6745, the MAD of a normal variable). The estimate is the root mean square of the rest (a
    normal variable cut at 5 standard deviations keeps all but 1e-5 of its variance). The MAD
    alone is not the estimate: of quantized samples (a sensor's counts) the differences are
    whole counts, and so is their median, which would put the estimate on steps of a count over
    ``0.6745 sqrt(C(2 order, order))``. A differences-based estimator needs no at-rest stretch,
    which a record that slides from its first samples does not have; it measures the samples'
    whole white part, quantization included (what the fit's input carries).

    Parameters
    ----------
    samples : ndarray
        Uniformly sampled signal, at least ``order + 2`` samples.
    order : int
        Order of the differences; 3 by default (the motion's acceleration passes a second difference).

    Returns
    -------
    float
        Estimated noise standard deviation, in the samples' unit.
    """
    y = np.asarray(samples, dtype=float)
    if len(y) < order + 2:
        raise ValueError(f"{len(y)} samples, expected at least {order + 2} for differences of order {order}")
    differences = np.diff(y, n=order)
    robust = np.median(np.abs(differences)) / _MAD_NORMAL
    if robust == 0.0:
        return 0.0
    kept = differences[np.abs(differences) <= OUTLIER_SIGMAS * robust]
    return float(np.sqrt(np.mean(kept**2) / math.comb(2 * order, order)))


@dataclass(frozen=True)
class Extrapolation:
    """The SIMEX extrapolation of one or more estimates.

    Attributes
    ----------
    lambdas : ndarray
        The added noise variances over the measured one, ``0`` first (the plain fit).
    means : ndarray
        Per ``lambda`` (rows) the estimates averaged over the replicates (columns: the parameters).
    value : ndarray
        The quadratic extrapolant at ``lambda = -1``, per parameter.
    standard_error : ndarray
        The Monte Carlo standard error of ``value``: the spread of the replicates' own
        extrapolations over the square root of their number (the plain fit's own error is not in it).
    """

    lambdas: np.ndarray
    means: np.ndarray
    value: np.ndarray
    standard_error: np.ndarray


def extrapolation_weights(lambdas: Sequence[float], degree: int = 2, at: float = -1.0) -> np.ndarray:
    """Weights ``w`` with ``sum_l w_l y_l`` the least-squares polynomial of ``degree`` through ``(lambda_l, y_l)`` at ``at``.

    Parameters
    ----------
    lambdas : sequence of float
        At least ``degree + 1`` distinct values.
    degree : int
        Of the extrapolant (2: quadratic).
    at : float
        Where the polynomial is evaluated (-1: no noise).
    """
    x = np.asarray(lambdas, dtype=float)
    design = np.vander(x, degree + 1, increasing=True)
    return np.vander(np.array([at]), degree + 1, increasing=True)[0] @ np.linalg.pinv(design)


def extrapolate(plain: np.ndarray, lambdas: Sequence[float], replicates: np.ndarray) -> Extrapolation:
    """The quadratic SIMEX extrapolation to ``lambda = -1``.

    The replicates are expected with common random numbers: replicate ``b`` adds
    ``sqrt(lambda) sigma Z_b`` at every ``lambda``, with the same ``Z_b``. Each replicate's
    estimates then lie on a smooth curve in ``lambda``, which is extrapolated on its own; the
    SIMEX value is the mean of these extrapolations (the extrapolant of the means: it is linear
    in them) and its Monte Carlo standard error their standard deviation over ``sqrt(B)``. The
    common numbers leave the value's expectation as it is and take out most of the Monte Carlo
    spread, which a quadratic's extrapolation would otherwise multiply (its weights at
    ``lambda = -1`` over a grid 0-2 are several times one).

    Parameters
    ----------
    plain : ndarray
        The plain fit's estimates (``lambda = 0``), one per parameter.
    lambdas : sequence of float
        The added noise variances (in units of the measured one), each > 0.
    replicates : ndarray
        Estimates with the noise added: replicates x lambdas x parameters.

    Returns
    -------
    Extrapolation
    """
    grid = np.concatenate([[0.0], np.asarray(lambdas, dtype=float)])
    estimates = np.asarray(replicates, dtype=float)
    plain = np.asarray(plain, dtype=float)
    curves = np.concatenate([np.broadcast_to(plain, (estimates.shape[0], 1, plain.size)), estimates], axis=1)
    weights = extrapolation_weights(grid.tolist())
    extrapolated = np.einsum("l,blp->bp", weights, curves)
    spread = extrapolated.std(axis=0, ddof=1) / math.sqrt(len(extrapolated)) if len(extrapolated) > 1 else np.zeros(plain.size)
    return Extrapolation(grid, curves.mean(axis=0), extrapolated.mean(axis=0), spread)
