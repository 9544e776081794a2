"""Elastic response spectra of a ground motion: the peak response of damped single-degree oscillators.

For each natural period ``T`` (``omega = 2 pi / T``) and damping ratio ``zeta``, the oscillator
``u'' + 2 zeta omega u' + omega^2 u = -a_g(t)`` is integrated exactly for an acceleration that
is linear between samples (Nigam & Jennings 1969; Chopra, *Dynamics of Structures*, Table
5.2.1), all periods at once. The spectra are the peak relative displacement ``Sd`` (m), the
pseudo-velocity ``Sv = omega Sd`` (m/s) and the pseudo-acceleration ``Sa = omega^2 Sd`` (m/s^2).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The damping ratio of the usual design spectrum.
DEFAULT_DAMPING = 0.05
#: Periods of the default spectrum (s): logarithmically spaced.
DEFAULT_PERIODS_S = np.geomspace(0.02, 5.0, 90)


@dataclass(frozen=True)
class ResponseSpectrum:
    """Peak responses of damped oscillators, one per period.

    Attributes
    ----------
    periods_s : ndarray
        Natural periods (s).
    damping : float
        Damping ratio (-).
    sd_m : ndarray
        Peak relative displacement (m).
    """

    periods_s: np.ndarray
    damping: float
    sd_m: np.ndarray

    @property
    def sa_m_s2(self) -> np.ndarray:
        """Pseudo-acceleration ``omega^2 Sd`` (m/s^2)."""
        return (2 * np.pi / self.periods_s) ** 2 * self.sd_m

    @property
    def sv_m_s(self) -> np.ndarray:
        """Pseudo-velocity ``omega Sd`` (m/s)."""
        return 2 * np.pi / self.periods_s * self.sd_m

    def sa_at(self, period_s: float) -> float:
        """Pseudo-acceleration at ``period_s`` (m/s^2), interpolated on log period."""
        return float(np.interp(np.log(period_s), np.log(self.periods_s), self.sa_m_s2))

    def peak(self) -> tuple[float, float]:
        """The largest pseudo-acceleration (m/s^2) and its period (s)."""
        k = int(np.argmax(self.sa_m_s2))
        return float(self.sa_m_s2[k]), float(self.periods_s[k])


def _coefficients(omega: np.ndarray, zeta: float, dt: float) -> tuple[np.ndarray, ...]:
    """The eight recurrence coefficients of the piecewise-linear exact method, per frequency (unit mass)."""
    root = np.sqrt(1.0 - zeta**2)
    omega_d = omega * root
    decay = np.exp(-zeta * omega * dt)
    sine, cosine = np.sin(omega_d * dt), np.cos(omega_d * dt)
    k = omega**2
    a = decay * (zeta / root * sine + cosine)
    b = decay * sine / omega_d
    c = (2 * zeta / (omega * dt) + decay * (((1 - 2 * zeta**2) / (omega_d * dt) - zeta / root) * sine
                                           - (1 + 2 * zeta / (omega * dt)) * cosine)) / k
    d = (1 - 2 * zeta / (omega * dt) + decay * ((2 * zeta**2 - 1) / (omega_d * dt) * sine
                                               + 2 * zeta / (omega * dt) * cosine)) / k
    a_v = -decay * omega / root * sine
    b_v = decay * (cosine - zeta / root * sine)
    c_v = (-1 / dt + decay * ((omega / root + zeta / (dt * root)) * sine + cosine / dt)) / k
    d_v = (1 - decay * (zeta / root * sine + cosine)) / (k * dt)
    return a, b, c, d, a_v, b_v, c_v, d_v


def response_spectrum(
    accel_m_s2: np.ndarray, dt_s: float, periods_s: np.ndarray = DEFAULT_PERIODS_S, damping: float = DEFAULT_DAMPING,
) -> ResponseSpectrum:
    """The elastic response spectrum of a ground acceleration sampled every ``dt_s``.

    Parameters
    ----------
    accel_m_s2 : ndarray
        Ground acceleration (m/s^2).
    dt_s : float
        Sample step (s).
    periods_s : ndarray
        Natural periods (s), all > 0.
    damping : float
        Damping ratio, in [0, 1).

    Returns
    -------
    ResponseSpectrum
    """
    periods = np.asarray(periods_s, dtype=float)
    if not 0.0 <= damping < 1.0:
        raise ValueError(f"found damping ratio {damping!r}, expected 0 <= damping < 1")
    if periods.size == 0 or np.any(periods <= 0):
        raise ValueError("expected periods > 0 s")
    a, b, c, d, a_v, b_v, c_v, d_v = _coefficients(2 * np.pi / periods, damping, float(dt_s))
    force = -np.asarray(accel_m_s2, dtype=float)
    u = np.zeros_like(periods)
    v = np.zeros_like(periods)
    peak = np.zeros_like(periods)
    for p_now, p_next in zip(force[:-1], force[1:], strict=True):
        u, v = a * u + b * v + c * p_now + d * p_next, a_v * u + b_v * v + c_v * p_now + d_v * p_next
        np.maximum(peak, np.abs(u), out=peak)
    return ResponseSpectrum(periods, damping, peak)
