"""The table-motion interpolation rule and the exact integration that matches it.

Inside a sample interval the table acceleration is piecewise linear (SPEC section 4;
the rule the simulator's integration kernel uses). For ``tau`` in ``[0, dt)``::

    a(t_k + tau) = a_k + (a_{k+1} - a_k) tau / dt
    v(t_k + tau) = v_k + a_k tau + (a_{k+1} - a_k) tau^2 / (2 dt)
    x(t_k + tau) = x_k + v_k tau + a_k tau^2 / 2 + (a_{k+1} - a_k) tau^3 / (6 dt)

so that, at the samples,

    v_{k+1} = v_k + dt (a_k + a_{k+1}) / 2
    x_{k+1} = x_k + dt v_k + dt^2 (a_k / 3 + a_{k+1} / 6)

The table displacement enters the plant through the spring term
``E(t) = B k_b x_0(t)`` (Eq. 6-7) and the controller through ``x_0`` and
``xdot_0`` (Eq. 22-23), so both see the same exact triple.

A triple ``(x, v, a)`` built with :func:`integrate_from_rest` satisfies these to
round-off, and so does any linear combination of such triples, which is what keeps
scaling and baseline correction exact.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike


def integrate_from_rest(accel_m_s2: np.ndarray, dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Velocity and displacement from acceleration by the piecewise-linear rule, from rest.

    Parameters
    ----------
    accel_m_s2 : numpy.ndarray
        Acceleration samples (m/s^2).
    dt_s : float
        Sample step (s).

    Returns
    -------
    velocity_m_s, displacement_m : numpy.ndarray
        Same length as ``accel_m_s2``, both 0 at the first sample.
    """
    a = np.asarray(accel_m_s2, dtype=float)
    velocity = np.zeros_like(a)
    displacement = np.zeros_like(a)
    np.cumsum(0.5 * dt_s * (a[:-1] + a[1:]), out=velocity[1:])
    increments = dt_s * velocity[:-1] + dt_s * dt_s * (a[:-1] / 3.0 + a[1:] / 6.0)
    np.cumsum(increments, out=displacement[1:])
    return velocity, displacement


def rule_residuals(
    accel_m_s2: np.ndarray, velocity_m_s: np.ndarray, displacement_m: np.ndarray, dt_s: float
) -> tuple[np.ndarray, np.ndarray]:
    """How far a triple is from the rule, per interval.

    Returns
    -------
    velocity_residual_m_s, displacement_residual_m : numpy.ndarray
        ``v_{k+1} - v_k - dt (a_k + a_{k+1})/2`` and
        ``x_{k+1} - x_k - dt v_k - dt^2 (a_k/3 + a_{k+1}/6)``, length ``n - 1``.
    """
    a, v, x = (np.asarray(arr, dtype=float) for arr in (accel_m_s2, velocity_m_s, displacement_m))
    rv = np.diff(v) - 0.5 * dt_s * (a[:-1] + a[1:])
    rx = np.diff(x) - dt_s * v[:-1] - dt_s * dt_s * (a[:-1] / 3.0 + a[1:] / 6.0)
    return rv, rx


def interpolate(
    t_s: ArrayLike,
    dt_s: float,
    accel_m_s2: np.ndarray,
    velocity_m_s: np.ndarray,
    displacement_m: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Table state ``(x, v, a)`` at time(s) ``t_s`` (s from the first sample) by the rule.

    Before the first sample the first sample's state is returned and after the
    last sample the last one's (the table waits at rest before and after a record).
    """
    t = np.asarray(t_s, dtype=float)
    last = accel_m_s2.size - 1
    k = np.clip(np.floor(t / dt_s), 0, last - 1).astype(np.intp)
    tau = np.clip(t - k * dt_s, 0.0, dt_s)
    after = t >= last * dt_s
    tau = np.where(after, 0.0, tau)
    k = np.where(after, last, k)
    k1 = np.minimum(k + 1, last)
    a0, v0, x0 = accel_m_s2[k], velocity_m_s[k], displacement_m[k]
    slope = (accel_m_s2[k1] - a0) / dt_s
    a = a0 + slope * tau
    v = v0 + a0 * tau + slope * tau**2 / 2.0
    x = x0 + v0 * tau + a0 * tau**2 / 2.0 + slope * tau**3 / 6.0
    return x, v, a


def interpolate_scalar(
    t_s: float, dt_s: float, accel_m_s2: np.ndarray, velocity_m_s: np.ndarray, displacement_m: np.ndarray
) -> tuple[float, float, float]:
    """Scalar :func:`interpolate` for a loop tick: no temporary arrays, plain floats out."""
    last = accel_m_s2.shape[0] - 1
    if t_s >= last * dt_s:
        return float(displacement_m[last]), float(velocity_m_s[last]), float(accel_m_s2[last])
    k = min(max(int(t_s // dt_s), 0), last - 1)
    tau = min(max(t_s - k * dt_s, 0.0), dt_s)
    a0 = float(accel_m_s2[k])
    v0 = float(velocity_m_s[k])
    slope = (float(accel_m_s2[k + 1]) - a0) / dt_s
    x = float(displacement_m[k]) + v0 * tau + a0 * tau * tau / 2.0 + slope * tau**3 / 6.0
    return x, v0 + a0 * tau + slope * tau * tau / 2.0, a0 + slope * tau
