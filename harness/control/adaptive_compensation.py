"""The adaptive time-series compensator (``control.compensation: adaptive``).

After the adaptive time series (ATS) compensator of Chae, Kazemibidokhti & Ricles (2013) for
real-time hybrid simulation: the command is a short series in the target and its
derivatives whose coefficients are fitted online, by least squares over a moving window, from
the commands sent and the responses measured. Here the actuator's response is the load cell's
force ``u`` and the series is of first order (the force loop is first order below ``w_f``,
(C1) of harness/control/compensation.py, and a second derivative of a load cell through 16
bits is noise), with the sliding velocity added as a third term for the natural velocity
feedback, which no series in the force alone can express:

    u_c = a0 r + a1 r' + a2 xdot_b,                                                   (C5)

``r`` the reference of (C2) (the controller's force through a lag of ``tau_r``, so ``r'`` is
exact). On the model (C1) the exact inverse is ``a0 = 1``, ``a1 = 1 / w_f``,
``a2 = k_h / w_f``; the compensator is told none of them.

Fit
---
The same relation holds between what was sent and what was measured,
``u_c = a0 u + a1 u' + a2 xdot_b``, and it still holds after passing every signal through the
same low-pass ``F`` (a first-order lag of ``tau_f``), which also gives the derivative without
differencing: ``F(u') = (u - F(u)) / tau_f``. Each tick adds the sample

    phi = (F(u), (u - F(u)) / tau_f, F(xdot_b)),   y = F(u_c sent on the previous tick)

to a preallocated ring of the last ``window_s``, whose normal equations ``R a = b``
(``R = sum phi phi^T``, ``b = sum phi y``) are kept as running sums (the oldest sample leaves as
the newest enters). The coefficients are solved for when the window is at least half full and
its normalized determinant ``det(D^-1/2 R D^-1/2)`` (1 for uncorrelated regressors, 0 for
collinear ones; ``D = diag(R)``) is at least ``min_excitation``; otherwise the last ones are
held (at rest nothing is learnt and nothing is forgotten). They start at ``(1, 0, 0)``, the
command equal to the force (``start: none``), or at the model's inverse ``(1, 1 / w_f, k_h / w_f)``
of ``rig.actuator`` (``start: model``), which spares the run the first half window as ``none``
and the step when the first fit arrives.

Bounds
------
Each coefficient is held to its stated range (``gain_bounds``, ``lead_bounds_s``,
``flow_bounds_Ns_per_m``). The defaults: ``a0`` 0.8-1.25 (a proportional force loop on its own
load cell has a static gain of 1 less its leakage, a few per mille); ``a1`` 0-20 ms (``1 /
w_f`` is 8 ms on the shipped rig, 1.6-32 ms for the 5-100 Hz a lab tunes, plus 1-2 ms of
delays); ``a2`` 0-200 kN s/m (twice the shipped rig's ``k_h / w_f``: the valve's orifice makes
the bleed grow with the load pressure as ``1 / sqrt(1 - p_L / p_s)``, harmless in (C1) but 1.73
times at the 10 kN clamp, two thirds of the supply: 163 kN s/m). A fit outside its range
is clipped to it and reported :attr:`~AdaptiveCompensator.pinned`: the actuator is not one the
compensator was stated to adapt to, or the adaptation ran away (the supervisor's
``compensation_fault`` trips when it lasts ``tracking_time_s``). A solution that is not finite
is never taken; the state stays finite by construction, and :attr:`diverged` reports a sum
that is not (it cannot become so from finite inputs; non-finite inputs are not added).
"""

from __future__ import annotations

import math

import numpy as np

from drivers.measurements import Measurements
from harness.control.compensation import AdaptiveCompensationConfig, reference_step
from harness.errors import ModelError

#: Columns of the window's ring: the three regressors and the filtered command.
_P0, _P1, _P2, _Y = range(4)
#: The running sums: R00, R01, R02, R11, R12, R22, b0, b1, b2.
_R00, _R01, _R02, _R11, _R12, _R22, _B0, _B1, _B2 = range(9)


def solve_normalized(sums: np.ndarray, min_excitation: float) -> tuple[float, float, float] | None:
    """``a`` of ``R a = b`` from the running sums, or None when the window is not excited enough.

    The system is scaled by ``D^-1/2`` on both sides (``D = diag(R)``), its determinant compared
    with ``min_excitation`` and solved by Cramer's rule; plain floats, nothing allocated.
    """
    d0, d1, d2 = sums[_R00], sums[_R11], sums[_R22]
    if not (d0 > 0.0 and d1 > 0.0 and d2 > 0.0):
        return None
    s0, s1, s2 = 1.0 / math.sqrt(d0), 1.0 / math.sqrt(d1), 1.0 / math.sqrt(d2)
    c01, c02, c12 = sums[_R01] * s0 * s1, sums[_R02] * s0 * s2, sums[_R12] * s1 * s2
    det = 1.0 + 2.0 * c01 * c02 * c12 - c01 * c01 - c02 * c02 - c12 * c12
    if not det >= min_excitation:
        return None
    b0, b1, b2 = sums[_B0] * s0, sums[_B1] * s1, sums[_B2] * s2
    x0 = (b0 * (1.0 - c12 * c12) - c01 * (b1 - c12 * b2) + c02 * (c12 * b1 - b2)) / det
    x1 = ((b1 - c12 * b2) - b0 * (c01 - c12 * c02) + c02 * (c01 * b2 - c02 * b1)) / det
    x2 = ((b2 - c12 * b1) - c01 * (c01 * b2 - c02 * b1) + b0 * (c01 * c12 - c02)) / det
    return x0 * s0, x1 * s1, x2 * s2


class AdaptiveCompensator:
    """The ATS compensator with a flow term, (C5), its coefficients fitted over a moving window.

    Parameters
    ----------
    settings : AdaptiveCompensationConfig
    period_s : float
        The loop's period (s): sizes the window's ring (``window_s / period_s`` samples).
    start : tuple of float, optional
        ``(a0, a1, a2)`` before the first fit (1, s, N s/m); default ``(1, 0, 0)``, the command
        equal to the force. Must lie within the bounds.

    Attributes
    ----------
    coefficients : ndarray (3,)
        ``(a0, a1, a2)`` in use (1, s, N s/m).
    fits : int
        Fits taken (windows excited enough).
    """

    name = "adaptive"

    __slots__ = (
        "settings", "coefficients", "fits", "reference_N", "command_N", "pinned", "diverged", "bound_value",
        "_ring", "_size", "_head", "_count", "_sums", "_low", "_high", "_tau", "_tau_f", "_u_f", "_v_f", "_y_f",
        "_primed", "_start",
    )

    def __init__(self, settings: AdaptiveCompensationConfig, period_s: float,
                 start: tuple[float, float, float] = (1.0, 0.0, 0.0)):
        self.settings = settings
        self._size = max(2, int(round(settings.window_s / period_s)))
        self._ring = np.zeros((self._size, 4))
        self._sums = np.zeros(9)
        self.coefficients = np.zeros(3)
        self._low = (settings.gain_bounds[0], settings.lead_bounds_s[0], settings.flow_bounds_Ns_per_m[0])
        self._high = (settings.gain_bounds[1], settings.lead_bounds_s[1], settings.flow_bounds_Ns_per_m[1])
        self._tau = settings.reference_time_constant_s
        self._tau_f = settings.filter_time_constant_s
        for i, value in enumerate(start):
            if not self._low[i] <= value <= self._high[i]:
                raise ModelError(f"the adaptive compensator's start {start} is outside its bounds {self._low}..{self._high}")
        self._start = tuple(float(value) for value in start)
        self.reset()

    def reset(self) -> None:
        """Empty window, coefficients at their start, zero reference and filters."""
        self._ring[:] = 0.0
        self._sums[:] = 0.0
        self._head = self._count = 0
        self.coefficients[:] = self._start
        self.fits = 0
        self.reference_N = self.command_N = self.bound_value = 0.0
        self._u_f = self._v_f = self._y_f = 0.0
        self._primed = False
        self.pinned = self.diverged = False

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """The command (N) of (C5); first the window learns from the previous command and this tick's response."""
        if math.isfinite(dt) and dt > 0.0:
            self._learn(dt, meas.actuator_force_N, meas.sliding_velocity_m_s, applied_N)
        if not math.isfinite(force_N) or not math.isfinite(dt) or dt <= 0.0:
            self.command_N = math.nan
            return self.command_N
        self.reference_N, rate = reference_step(self.reference_N, force_N, dt, self._tau)  # (C2)
        a = self.coefficients
        self.command_N = float(a[0] * self.reference_N + a[1] * rate + a[2] * meas.sliding_velocity_m_s)  # (C5)
        return self.command_N

    def _learn(self, dt: float, force_N: float, velocity_m_s: float, applied_N: float) -> None:
        """Filter the sample, put it in the window, and fit when the window is excited enough."""
        if not (math.isfinite(force_N) and math.isfinite(velocity_m_s) and math.isfinite(applied_N)):
            return
        if not self._primed:  # the filters start at the first sample (no step from zero)
            self._u_f, self._v_f, self._y_f, self._primed = force_N, velocity_m_s, applied_N, True
        alpha = 1.0 - math.exp(-dt / self._tau_f)
        self._u_f += alpha * (force_N - self._u_f)
        self._v_f += alpha * (velocity_m_s - self._v_f)
        self._y_f += alpha * (applied_N - self._y_f)
        self._push(self._u_f, (force_N - self._u_f) / self._tau_f, self._v_f, self._y_f)
        if 2 * self._count >= self._size:
            self._fit()

    def _push(self, p0: float, p1: float, p2: float, y: float) -> None:
        """Add a sample to the ring and the running sums; the oldest leaves when the ring is full."""
        sums, row = self._sums, self._ring[self._head]
        if self._count == self._size:
            self._accumulate(sums, row[_P0], row[_P1], row[_P2], row[_Y], -1.0)
        else:
            self._count += 1
        row[_P0], row[_P1], row[_P2], row[_Y] = p0, p1, p2, y
        self._accumulate(sums, p0, p1, p2, y, 1.0)
        self._head = (self._head + 1) % self._size

    @staticmethod
    def _accumulate(sums: np.ndarray, p0: float, p1: float, p2: float, y: float, sign: float) -> None:
        """Add (sign 1) or remove (sign -1) one sample's products from the running sums."""
        sums[_R00] += sign * p0 * p0
        sums[_R01] += sign * p0 * p1
        sums[_R02] += sign * p0 * p2
        sums[_R11] += sign * p1 * p1
        sums[_R12] += sign * p1 * p2
        sums[_R22] += sign * p2 * p2
        sums[_B0] += sign * p0 * y
        sums[_B1] += sign * p1 * y
        sums[_B2] += sign * p2 * y

    def _fit(self) -> None:
        """Solve the window's normal equations; clip to the bounds; report pinned and diverged."""
        self.diverged = not all(math.isfinite(value) for value in self._sums)
        if self.diverged:
            return
        solution = solve_normalized(self._sums, self.settings.min_excitation)
        if solution is None or not all(math.isfinite(value) for value in solution):
            return  # not excited enough: hold the last coefficients
        self.fits += 1
        pinned = False
        for i, value in enumerate(solution):
            clipped = min(max(value, self._low[i]), self._high[i])
            if clipped != value:
                pinned = True
                self.bound_value = value
            self.coefficients[i] = clipped
        self.pinned = pinned
