"""Baseline correction that keeps the table triple exact.

Three pieces, used in this order by :func:`harness.motions.processing.process_record`:

:func:`taper_window`
    Cosine (Hann) ramps at both ends of the part of the record that holds data, so
    the acceleration starts and ends at exactly 0.
:func:`highpass`
    Optional zero-phase Butterworth high-pass (``butter`` + ``sosfiltfilt``) on a
    zero-padded copy. Off by default: a zero-phase filter rings outside the record,
    and cutting that ringing off leaves end offsets that the fit below must remove
    anyway; on the real records it lowered the peak displacement little and
    changed the acceleration by up to 15 % of the PGA.
:func:`fit_rest`
    The drift remover. It adds to the acceleration a few slow half-sine bumps
    ``sum_j b_j sin(j pi t / T)``, ``j = 1..J`` (frequencies ``j / (2T)`` up to
    the corner ``corner_hz``; every bump is 0 at both ends), integrates each bump
    with the table's interpolation rule, and chooses the ``b_j`` by least squares
    so that the mean square displacement is smallest subject to ``v(T) = 0`` and
    ``x(T) = 0`` exactly (a KKT system of size ``J + 2``). It is the exact-rule
    equivalent of subtracting a low-order polynomial fit from the displacement:
    the correction touches only frequencies below the corner. The corrected
    acceleration is then integrated again with the rule, so the triple satisfies
    it to round-off, and (the rule being linear) ends at rest to round-off.

A record cut short (``duration_s`` shorter than the record) is corrected whole with the
three pieces above, so the correction does not depend on where the cut falls, and then
:func:`stop_at_rest` ends the kept part: a cosine taper of the acceleration over its last
samples, and two half-sine bumps on that same stretch that bring the table to rest
(``v = x = 0`` at the end, exactly). Before the stretch the motion is the whole record's.
"""

from __future__ import annotations

import numpy as np

from harness.motions.integration import integrate_from_rest

#: Most half-sine bumps :func:`fit_rest` uses.
MAX_BUMPS = 64


def taper_window(n_content: int, n_total: int, ramp: int) -> np.ndarray:
    """Window that is 1 inside, rises and falls over ``ramp`` samples, and is 0 after the data.

    Parameters
    ----------
    n_content : int
        Samples that hold data (the rest is zero padding).
    n_total : int
        Length of the window.
    ramp : int
        Samples in each cosine ramp (0: no taper).
    """
    window = np.ones(n_total)
    window[n_content:] = 0.0
    if ramp > 0:
        rise = 0.5 * (1.0 - np.cos(np.pi * np.arange(ramp + 1) / ramp))
        window[: ramp + 1] = rise
        window[n_content - 1 - ramp : n_content] = rise[::-1]
    return window


def highpass(accel_m_s2: np.ndarray, dt_s: float, corner_hz: float, order: int) -> np.ndarray:
    """Zero-phase Butterworth high-pass of a record that starts and ends at 0.

    The record is padded with ``3 / corner_hz`` seconds of zeros at both ends before
    filtering forward and backward (effective order ``2 * order``) and cut back.
    """
    from scipy import (
        signal,  # imported here: about 1 s at start-up, and only this filter needs it
    )

    sos = signal.butter(order, corner_hz, btype="highpass", fs=1.0 / dt_s, output="sos")
    pad = int(np.ceil(3.0 / (corner_hz * dt_s)))
    padded = np.concatenate([np.zeros(pad), accel_m_s2, np.zeros(pad)])
    return signal.sosfiltfilt(sos, padded, padtype=None)[pad : pad + accel_m_s2.size]


def bump_count(duration_s: float, corner_hz: float) -> int:
    """Number of half-sine bumps with frequency ``j / (2 T)`` up to ``corner_hz`` (at least 2)."""
    return int(min(MAX_BUMPS, max(2, np.floor(2.0 * duration_s * corner_hz + 1e-9))))


def fit_rest(
    accel_m_s2: np.ndarray, dt_s: float, corner_hz: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[float, float]]:
    """Integrate from rest and remove the drift so the table ends at rest at 0, exactly.

    Parameters
    ----------
    accel_m_s2 : numpy.ndarray
        Acceleration (m/s^2), preferably tapered to 0 at both ends.
    dt_s : float
        Sample step (s).
    corner_hz : float
        Highest frequency of the correction (Hz).

    Returns
    -------
    accel_m_s2, velocity_m_s, displacement_m : numpy.ndarray
        The corrected triple; it satisfies the rule to round-off, starts with
        ``x = v = 0`` and ends with ``x = v = 0``.
    end_offsets : tuple of float
        ``(x(T) in m, v(T) in m/s)`` of the uncorrected double integral.
    """
    n = accel_m_s2.size
    velocity, displacement = integrate_from_rest(accel_m_s2, dt_s)
    count = bump_count((n - 1) * dt_s, corner_hz)
    phase = np.pi * np.arange(n) / (n - 1)
    bumps = np.sin(np.outer(np.arange(1, count + 1), phase))
    bumps[:, 0] = bumps[:, -1] = 0.0
    bump_v = np.empty_like(bumps)
    bump_x = np.empty_like(bumps)
    for j, bump in enumerate(bumps):
        bump_v[j], bump_x[j] = integrate_from_rest(bump, dt_s)
    coefficients = _constrained_least_squares(bump_x, displacement, bump_v[:, -1], velocity[-1])
    corrected = accel_m_s2 + coefficients @ bumps
    # Re-integrate rather than add the bumps' integrals: the triple is then the rule
    # applied to the final acceleration, free of the round-off of a large cancellation.
    new_velocity, new_displacement = integrate_from_rest(corrected, dt_s)
    return corrected, new_velocity, new_displacement, (float(displacement[-1]), float(velocity[-1]))


def _constrained_least_squares(
    bump_x: np.ndarray, displacement: np.ndarray, bump_v_end: np.ndarray, velocity_end: float
) -> np.ndarray:
    """Minimise ``|x + B' b|^2`` subject to ``x(T) + B'(T) b = 0`` and ``v(T) + V'(T) b = 0``."""
    count = bump_x.shape[0]
    scale = float(np.max(np.abs(bump_x))) or 1.0
    gram = (bump_x @ bump_x.T) / scale**2
    constraints = np.vstack([bump_x[:, -1] / scale, bump_v_end / scale])
    kkt = np.block([[gram, constraints.T], [constraints, np.zeros((2, 2))]])
    rhs = np.concatenate([-(bump_x @ displacement) / scale**2, [-displacement[-1] / scale, -velocity_end / scale]])
    solution = np.linalg.lstsq(kkt, rhs, rcond=None)[0]
    return solution[:count]


#: Half-sine bumps :func:`stop_at_rest` adds over the stop: as many as the conditions it meets (v = x = 0).
STOP_BUMPS = 2


def stop_at_rest(accel_m_s2: np.ndarray, dt_s: float, n_stop: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """End a cut of a corrected record at rest over its last ``n_stop`` samples.

    The acceleration is multiplied by a cosine taper from 1 to 0 over the last ``n_stop``
    samples; then the two bumps ``b_j sin(j pi tau / L)``, ``j = 1, 2`` (``tau`` from the
    start of the stop, ``L`` its length; both 0 at its ends), are added so that the velocity
    and the displacement integrated from rest end at 0. The motion before the stop is not
    touched, and the triple satisfies the rule to round-off.

    Parameters
    ----------
    accel_m_s2 : numpy.ndarray
        The kept part of a corrected record (m/s^2), integrated from rest.
    dt_s : float
        Sample step (s).
    n_stop : int
        Samples of the stop (at least 3, at most the record's).

    Returns
    -------
    accel_m_s2, velocity_m_s, displacement_m : numpy.ndarray
        The triple; it ends with ``a = v = x = 0`` (``v`` and ``x`` to round-off).
    """
    n = accel_m_s2.size
    start = n - n_stop
    phase = np.pi * np.arange(n_stop) / (n_stop - 1)
    accel = np.array(accel_m_s2, dtype=float)
    accel[start:] *= 0.5 * (1.0 + np.cos(phase))
    velocity, displacement = integrate_from_rest(accel, dt_s)
    bumps = np.zeros((STOP_BUMPS, n))
    ends = np.empty((2, STOP_BUMPS))
    for j in range(STOP_BUMPS):
        bumps[j, start:] = np.sin((j + 1) * phase)
        bumps[j, start], bumps[j, -1] = 0.0, 0.0
        bump_v, bump_x = integrate_from_rest(bumps[j, start:], dt_s)
        ends[:, j] = bump_x[-1], bump_v[-1]
    coefficients = np.linalg.solve(ends, -np.array([displacement[-1], velocity[-1]]))
    corrected = accel + coefficients @ bumps
    new_velocity, new_displacement = integrate_from_rest(corrected, dt_s)
    return corrected, new_velocity, new_displacement
