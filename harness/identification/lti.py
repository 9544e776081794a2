"""Linear time-invariant systems driven by a sampled input: exact discretisation and a compiled simulation.

The structure's identification compares measured floor accelerations with those of a model
driven by the measured base-mat acceleration, sample by sample. Between samples the input is
taken as linear (first-order hold, the rule the table's record follows), and the model
``x' = A x + B u, y = C x + D u`` is discretised exactly for that input
(:func:`first_order_hold`): with ``u`` linear over a step the result is the continuous
solution at the samples, whatever the step, so a decimated signal is simulated as exactly as
the original. :func:`simulate` runs the recursion compiled (numba).
"""

from __future__ import annotations

import numba
import numpy as np
from scipy import linalg


def first_order_hold(a_matrix: np.ndarray, b_vector: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Ad, B0, B1)`` with ``x[k+1] = Ad x[k] + B0 u[k] + B1 u[k+1]`` exact for ``u`` linear between samples.

    From the exponential of the augmented matrix ``[[A dt, B dt, 0], [0, 0, 1], [0, 0, 0]]``
    (Franklin, Powell & Workman, Digital Control, the triangle-hold equivalent).
    """
    n = a_matrix.shape[0]
    augmented = np.zeros((n + 2, n + 2))
    augmented[:n, :n] = a_matrix * dt_s
    augmented[:n, n] = b_vector * dt_s
    augmented[n, n + 1] = 1.0
    exponential = linalg.expm(augmented)
    gamma_1, gamma_2 = exponential[:n, n], exponential[:n, n + 1]
    return exponential[:n, :n], gamma_1 - gamma_2, gamma_2


@numba.njit(cache=True, nogil=True)
def _run(ad: np.ndarray, b0: np.ndarray, b1: np.ndarray, c: np.ndarray, d: np.ndarray, u: np.ndarray) -> np.ndarray:
    n_states = ad.shape[0]
    n_out = c.shape[0]
    n = u.shape[0]
    y = np.empty((n_out, n))
    x = np.zeros(n_states)
    following = np.zeros(n_states)
    for k in range(n):
        for o in range(n_out):
            acc = d[o] * u[k]
            for i in range(n_states):
                acc += c[o, i] * x[i]
            y[o, k] = acc
        if k + 1 < n:
            for i in range(n_states):
                acc = b0[i] * u[k] + b1[i] * u[k + 1]
                for j in range(n_states):
                    acc += ad[i, j] * x[j]
                following[i] = acc
            x, following = following, x
    return y


def simulate(a_matrix: np.ndarray, b_vector: np.ndarray, c_matrix: np.ndarray, d_vector: np.ndarray, u: np.ndarray,
             dt_s: float) -> np.ndarray:
    """The outputs ``y = C x + D u`` (one row per output) from rest, for ``u`` sampled every ``dt_s``."""
    ad, b0, b1 = first_order_hold(a_matrix, b_vector, dt_s)
    return _run(np.ascontiguousarray(ad), b0, b1, np.ascontiguousarray(c_matrix, dtype=float),
                np.asarray(d_vector, dtype=float), np.ascontiguousarray(u, dtype=float))


def delayed(u: np.ndarray, delay_s: float, dt_s: float) -> np.ndarray:
    """``u(t - delay_s)`` on the same samples (linear between them; zero before the start)."""
    t = np.arange(len(u)) * dt_s
    return np.interp(t - delay_s, t, u, left=0.0)
