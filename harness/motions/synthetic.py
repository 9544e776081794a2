"""Seeded synthetic ground motion: Clough-Penzien filtered white noise in a time envelope.

So that a fresh clone runs without the real accelerograms, the harness generates a
stationary Clough-Penzien process and modulates it in time:

1. Gaussian white noise ``w_k`` from ``numpy.random.default_rng(seed)``.
2. The Kanai-Tajimi filter (soil layer, frequency ``omega_g``, damping ``zeta_g``)
   followed by the Clough-Penzien high-pass second filter (``omega_f``, ``zeta_f``),
   which removes the unbounded low-frequency content of Kanai-Tajimi so the
   ground displacement stays finite::

       H(s) = (2 zeta_g omega_g s + omega_g^2) / (s^2 + 2 zeta_g omega_g s + omega_g^2)
            * s^2 / (s^2 + 2 zeta_f omega_f s + omega_f^2)

   discretised with the bilinear transform and run as second-order sections.
3. A time envelope ``e(t)``: Saragoni-Hart ``e = (t/T)^b exp(-c t/T)`` normalised
   to 1 at ``t = eps T`` and ``eta`` at the end ``T`` (Boore 2003 form), or a
   trapezoid (quadratic rise, plateau, exponential decay to ``eta``).
4. Scaling to the target PGA.

Defaults are the firm-soil values of Der Kiureghian & Neuenhofer (1992):
``omega_g = 15 rad/s``, ``zeta_g = 0.6``, ``omega_f = 1.5 rad/s``, ``zeta_f = 0.6``.
The same seed gives the identical array; different seeds give different ones.
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2
from harness.motions.checks import MIN_SAMPLES
from harness.motions.loaders import RawRecord

Envelope = Literal["saragoni_hart", "trapezoidal"]


def synthetic_record(
    seed: int = 0,
    duration_s: float = 30.0,
    dt_s: float = 0.01,
    pga_g: float = 0.3,
    *,
    omega_g_rad_s: float = 15.0,
    zeta_g: float = 0.6,
    omega_f_rad_s: float = 1.5,
    zeta_f: float = 0.6,
    envelope: Envelope = "saragoni_hart",
    peak_fraction: float = 0.2,
    end_amplitude: float = 0.05,
) -> RawRecord:
    """Generate a seeded Clough-Penzien accelerogram.

    Parameters
    ----------
    seed : int
        Seed of ``numpy.random.default_rng``.
    duration_s : float
        Length of the record (s); it has ``round(duration_s / dt_s) + 1`` samples.
    dt_s : float
        Sample step (s).
    pga_g : float
        Peak |acceleration| of the result (g).
    omega_g_rad_s, zeta_g : float
        Kanai-Tajimi (site) frequency (rad/s) and damping ratio.
    omega_f_rad_s, zeta_f : float
        Clough-Penzien high-pass frequency (rad/s) and damping ratio.
    envelope : {"saragoni_hart", "trapezoidal"}
        Shape of the time envelope.
    peak_fraction : float
        Where the envelope reaches 1, as a fraction of the duration (0 < . < 1).
    end_amplitude : float
        Envelope value at the end of the record (0 < . < 1).

    Returns
    -------
    RawRecord
        Named ``synthetic:<seed>``; the first sample is exactly 0.
    """
    _check_parameters(duration_s, dt_s, pga_g, omega_g_rad_s, zeta_g, omega_f_rad_s, zeta_f, peak_fraction, end_amplitude)
    n = int(round(duration_s / dt_s)) + 1
    t = np.arange(n) * dt_s
    noise = np.random.default_rng(seed).standard_normal(n)
    sos = clough_penzien_sos(dt_s, omega_g_rad_s, zeta_g, omega_f_rad_s, zeta_f)
    accel = filter_sections(sos, noise) * envelope_shape(t, t[-1], envelope, peak_fraction, end_amplitude)
    accel *= pga_g * G_M_S2 / np.max(np.abs(accel))
    source = (
        f"synthetic Clough-Penzien, seed {seed}, omega_g {omega_g_rad_s:g} rad/s, zeta_g {zeta_g:g}, "
        f"omega_f {omega_f_rad_s:g} rad/s, zeta_f {zeta_f:g}, {envelope} envelope"
    )
    return RawRecord(name=f"synthetic:{seed}", dt_s=dt_s, accel_m_s2=accel, source=source)


def clough_penzien_sos(dt_s: float, omega_g: float, zeta_g: float, omega_f: float, zeta_f: float) -> np.ndarray:
    """Second-order sections ``(2, 6)`` of the bilinear-discretised Clough-Penzien filter.

    The filter (rad/s) ``H(s) = 2 zeta_g omega_g (s + omega_g / (2 zeta_g)) s^2 /
    ((s^2 + 2 zeta_g omega_g s + omega_g^2)(s^2 + 2 zeta_f omega_f s + omega_f^2))``, mapped by
    ``z = (1 + s / (2 fs)) / (1 - s / (2 fs))``; its zero at infinity goes to ``z = -1``. Written
    out here rather than taken from ``scipy.signal`` (``bilinear_zpk``, ``zpk2sos``), whose import
    costs about a second of every ``harness simulate`` that uses the synthetic record.
    """
    two_fs = 2.0 / dt_s

    def bilinear(root: complex) -> complex:
        return (two_fs + root) / (two_fs - root)

    def quadratic(roots: tuple[complex, complex]) -> tuple[float, float, float]:
        """``(1, -(r1 + r2), r1 r2)``: the real polynomial with the two roots."""
        return 1.0, -(roots[0] + roots[1]).real, (roots[0] * roots[1]).real

    def pole_pair(omega: float, zeta: float) -> tuple[complex, complex]:
        """The roots of ``s^2 + 2 zeta omega s + omega^2``: a conjugate pair, or two real ones when overdamped."""
        if zeta < 1.0:
            root = complex(-zeta * omega, omega * math.sqrt(1.0 - zeta * zeta))
            return root, root.conjugate()
        spread = omega * math.sqrt(zeta * zeta - 1.0)
        return complex(-zeta * omega - spread), complex(-zeta * omega + spread)

    s_zero = -omega_g / (2.0 * zeta_g)
    s_poles = (*pole_pair(omega_g, zeta_g), *pole_pair(omega_f, zeta_f))
    # the bilinear map's gain (as scipy.signal.bilinear_zpk):
    # k_d = k prod(2 fs - s_zeros) / prod(2 fs - s_poles), with the zeros at 0 and the one at -omega_g / (2 zeta_g)
    gain = complex(2.0 * zeta_g * omega_g * (two_fs - s_zero) * two_fs * two_fs)
    for pole in s_poles:
        gain /= two_fs - pole
    first = (*quadratic((complex(bilinear(s_zero)), complex(-1.0))), *quadratic((bilinear(s_poles[0]), bilinear(s_poles[1]))))
    second = (*quadratic((complex(1.0), complex(1.0))), *quadratic((bilinear(s_poles[2]), bilinear(s_poles[3]))))
    sections = np.array([first, second], dtype=float)
    sections[0, :3] *= gain.real
    return sections


def filter_sections(sections: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``x`` through the second-order sections in turn (direct form II transposed, zero initial state)."""
    y = np.asarray(x, dtype=float).tolist()
    for b0, b1, b2, a0, a1, a2 in sections.tolist():
        b0, b1, b2, a1, a2 = b0 / a0, b1 / a0, b2 / a0, a1 / a0, a2 / a0
        z1 = z2 = 0.0
        for k, value in enumerate(y):
            out = b0 * value + z1
            z1 = b1 * value - a1 * out + z2
            z2 = b2 * value - a2 * out
            y[k] = out
    return np.array(y)


def envelope_shape(t_s: np.ndarray, end_s: float, kind: Envelope, peak_fraction: float, end_amplitude: float) -> np.ndarray:
    """Time envelope, 0 at ``t = 0``, 1 at its peak, ``end_amplitude`` at ``end_s``."""
    u = t_s / end_s
    if kind == "saragoni_hart":
        eps, eta = peak_fraction, end_amplitude
        b = -eps * np.log(eta) / (1.0 + eps * (np.log(eps) - 1.0))
        c = b / eps
        return (np.e / eps) ** b * u**b * np.exp(-c * u)
    if kind == "trapezoidal":
        rise = 0.5 * peak_fraction
        decay = -np.log(end_amplitude) / (1.0 - peak_fraction)
        shape = np.ones_like(u)
        shape[u < rise] = (u[u < rise] / rise) ** 2
        late = u > peak_fraction
        shape[late] = np.exp(-decay * (u[late] - peak_fraction))
        return shape
    raise RecordError(f"unknown envelope {kind!r}; expected 'saragoni_hart' or 'trapezoidal'")


def _check_parameters(
    duration_s: float,
    dt_s: float,
    pga_g: float,
    omega_g: float,
    zeta_g: float,
    omega_f: float,
    zeta_f: float,
    peak_fraction: float,
    end_amplitude: float,
) -> None:
    positive = {
        "dt_s": dt_s,
        "pga_g": pga_g,
        "omega_g_rad_s": omega_g,
        "zeta_g": zeta_g,
        "omega_f_rad_s": omega_f,
        "zeta_f": zeta_f,
    }
    for key, value in positive.items():
        if not (np.isfinite(value) and value > 0):
            raise RecordError(f"synthetic record: expected {key} > 0, found {value!r}")
    if not (np.isfinite(duration_s) and duration_s >= MIN_SAMPLES * dt_s):
        raise RecordError(
            f"synthetic record: expected duration_s >= {MIN_SAMPLES * dt_s:g} s ({MIN_SAMPLES} steps), found {duration_s!r}"
        )
    nyquist_rad_s = np.pi / dt_s
    if max(omega_g, omega_f) >= 0.5 * nyquist_rad_s:
        raise RecordError(
            "synthetic record: filter frequencies must be below half the Nyquist frequency "
            f"{0.5 * nyquist_rad_s:g} rad/s for dt_s={dt_s:g}"
        )
    for key, value in {"peak_fraction": peak_fraction, "end_amplitude": end_amplitude}.items():
        if not 0.0 < value < 1.0:
            raise RecordError(f"synthetic record: expected 0 < {key} < 1, found {value!r}")
