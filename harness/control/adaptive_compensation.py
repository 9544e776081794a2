"""The adaptive time-series compensator (``control.compensation: adaptive``).

After the adaptive time series (ATS) compensator of Chae, Kazemibidokhti & Ricles (2013) for
real-time hybrid simulation: the command is a short series in the target and its
derivatives whose coefficients are fitted online, by least squares over a moving window, from
the commands sent and the responses measured. Here the actuator's response is the load cell's
force ``u`` and the series is of first order (the force loop is first order below ``w_f``,
(C1) of harness/control/compensation.py, and a second derivative of a load cell through 16
bits is noise), with the sliding velocity added as a third term for the natural velocity
feedback, which no series in the force alone can express, and the sliding acceleration as a
fourth for what the servo controller's velocity feed-forward leaves of it:

    u_c = a0 r + a1 r' + a2 xdot_b + a3 xddot_b,                                      (C5)

``r`` the reference of (C2) (the controller's force through a lag of ``tau_r``, so ``r'`` is
exact) and ``xddot_b`` the derivative of the measured sliding velocity through ``F`` (below). On
the model (C1) the exact inverse is ``a0 = 1``, ``a1 = 1 / w_f``, ``a2 = k_h / w_f``, ``a3 = 0``;
the compensator is told none of them. The fourth term: a servo controller's feed-forward cancels
the bleed ``c xdot_b`` (``c = k_h / w_f``) with a velocity it reads through a filter and a delay,
``tau_v`` in all, so the bleed it leaves is ``c (xdot_b - xdot_b(t - tau_v)) ~ c tau_v xddot_b``: a
force proportional to the sliding acceleration, 0.55-0.83 t on the shipped rig (benchmarks/README.md,
"The adaptive compensator's trips"), which (C5) without it made up for by pulling ``a0`` below its
range in strong motion.

Fit
---
The same relation holds between what was sent and what was measured,
``u_c = a0 u + a1 u' + a2 xdot_b + a3 xddot_b``, and it still holds after passing every signal through the
same low-pass ``F`` (a first-order lag of ``tau_f``), which also gives the derivative without
differencing: ``F(u') = (u - F(u)) / tau_f``. Each tick adds the sample

    phi = (F(u), (u - F(u)) / tau_f, F(xdot_b), (xdot_b - F(xdot_b)) / tau_f),
    y = F(u_c sent on the previous tick)

to a preallocated ring of the last ``window_s``, whose normal equations ``R a = b``
(``R = sum phi phi^T``, ``b = sum phi y``) are kept as running sums (the oldest sample leaves as
the newest enters). The coefficients are solved for when the window is at least half full and
its normalized determinant ``det(D^-1/2 R D^-1/2)`` (1 for uncorrelated regressors, 0 for
collinear ones; ``D = diag(R)``) is at least ``min_excitation``; otherwise the last ones are
held (at rest nothing is learnt and nothing is forgotten). They start at ``(1, 0, 0, 0)``, the
command equal to the force (``start: none``), or at the model's inverse ``(1, 1 / w_f, k_h / w_f, 0)``
of ``rig.actuator`` (``start: model``), which spares the run the first half window as ``none``
and the step when the first fit arrives.

**Only a sliding base mat is learnt from** (C8). A sample enters the window only while the filtered
sliding velocity is at least ``v_learn``. While the bearing sticks the base mat moves only within
its elastic range, ``|x| <= D_y``, and ``F`` of that motion at any frequency ``w`` is at most
``w D_y / sqrt(1 + (w tau_f)^2) < D_y / tau_f``: ``v_learn = D_y / tau_f`` (the bearing's
``yield_displacement_m``; 2.54 mm/s on the shipped rig) is the smallest filtered velocity a stuck
bearing cannot show. Below it the load cell answers the bearing's elastic creep, not the
actuator's flow, and the flow term and the lead trade one for the other (the fits that left their
range in the quiet tail of the records); nothing is learnt and nothing is forgotten.

Bounds
------
Each coefficient is held to its stated range (``gain_bounds``, ``lead_bounds_s``,
``flow_bounds_Ns_per_m``). The defaults: ``a0`` 0.8-1.25 (a proportional force loop on its own
load cell has a static gain of 1 less its leakage, a few per mille); ``a1`` 0-20 ms (``1 /
w_f`` is 8 ms on the shipped rig, 1.6-32 ms for the 5-100 Hz a lab tunes, plus 1-2 ms of
delays); ``a2`` 0-200 kN s/m (twice the shipped rig's ``k_h / w_f``: the valve's orifice makes
the bleed grow with the load pressure as ``1 / sqrt(1 - p_L / p_s)``, harmless in (C1) but 1.73
times at the 10 kN clamp, two thirds of the supply: 163 kN s/m); ``a3`` -400 to 4000 kg (C6).
Above: the residual ``c tau_v xddot_b`` of a feed-forward whose velocity lags by ``tau_v`` has
``c`` at most the flow term's bound and ``tau_v`` at most the lead's, 200 kN s/m x 20 ms. Below:
the load cell is read a period after the velocity that drove it (the loop samples, then the
actuator moves for a period), which the fit sees as the flow term leading by up to a period,
``a3 = -c T``: at most 200 kN s/m x 2 ms at the shipped 500 Hz (on the known first-order plant
without feed-forward, 94 kN s/m, the fit gives -208 kg, ``-c`` x 2.2 ms).

A fit outside its range is clipped to it. The clip is a fault, reported
:attr:`~AdaptiveCompensator.pinned`, when it changes the window's command by more than
``clip_tolerance_N`` RMS (C7), ``sqrt(d^T R d / n)`` for the clip ``d`` of the coefficients over
the window's ``n`` samples: the actuator is not one the compensator was stated to adapt to, or
the adaptation ran away (the supervisor's ``compensation_fault`` trips when it lasts
``tracking_time_s``). The default, 1 N, is about one count of the shipped 25 kN load cell through
16 bits (0.76 N): a clip the load cell cannot see is the fit's noise at a bound that holds (a
plain force loop's ``a3`` of 0 fitted at a few kg below it), not an actuator outside it. A solution that is not finite
is never taken; the state stays finite by construction, and :attr:`diverged` reports a sum
that is not (it cannot become so from finite inputs; non-finite inputs are not added).
"""

from __future__ import annotations

import math

import numpy as np

from drivers.measurements import Measurements
from harness.control.compensation import reference_step
from harness.control.config import AdaptiveCompensationConfig
from harness.errors import ModelError

#: Regressors of (C5): F(u), F(u'), F(xdot_b), F(xddot_b); the ring's last column is the filtered command.
TERMS = 4


def solve_normalized(normal, right, min_excitation: float, work, solution) -> bool:
    """Solve ``R a = b`` into ``solution``; False, and ``solution`` untouched, when the window is not excited enough.

    The system is scaled by ``D^-1/2`` on both sides (``D = diag(R)``), the scaled matrix's
    determinant (1 for uncorrelated regressors, 0 for collinear ones) compared with
    ``min_excitation``, and solved by Gaussian elimination with partial pivoting in ``work``
    (``n`` rows of ``n + 2``, preallocated; the last column holds ``R_ii^-1/2`` while the system is
    scaled): plain floats, nothing allocated.

    Parameters
    ----------
    normal : sequence of n rows of n floats
        ``R``, symmetric (lists or an ndarray; the tick's are lists, which index faster).
    right : sequence of n floats
        ``b``.
    min_excitation : float
        The smallest normalized determinant for a solution.
    work : n mutable rows of n + 2 floats
        Scratch space, overwritten.
    solution : mutable sequence of n floats
        Receives ``a`` when True is returned.
    """
    n = len(right)
    for i in range(n):
        if not normal[i][i] > 0.0:
            return False
    scale = n + 1
    for i in range(n):
        work[i][scale] = 1.0 / math.sqrt(normal[i][i])
    for i in range(n):
        row, si = work[i], work[i][scale]
        for j in range(n):
            row[j] = normal[i][j] * si * work[j][scale]
        row[n] = right[i] * si
    det = 1.0
    for k in range(n):
        pivot = k
        for i in range(k + 1, n):
            if abs(work[i][k]) > abs(work[pivot][k]):
                pivot = i
        if pivot != k:
            work[k], work[pivot] = work[pivot], work[k]
            det = -det
        top = work[k]
        det *= top[k]
        if top[k] == 0.0:
            return False
        for i in range(k + 1, n):
            row = work[i]
            factor = row[k] / top[k]
            for j in range(k, n + 1):
                row[j] -= factor * top[j]
    if not det >= min_excitation:
        return False
    for i in range(n - 1, -1, -1):
        row = work[i]
        total = row[n]
        for j in range(i + 1, n):
            total -= row[j] * work[j][n]
        row[n] = total / row[i]
    for i in range(n):
        value = work[i][n] / math.sqrt(normal[i][i])  # column i's scale (the rows, and their last column, were swapped)
        if not math.isfinite(value):
            return False
        work[i][n] = value
    for i in range(n):
        solution[i] = work[i][n]
    return True


class AdaptiveCompensator:
    """The ATS compensator with a flow and an acceleration term, (C5), its coefficients fitted over a moving window.

    Parameters
    ----------
    settings : AdaptiveCompensationConfig
    period_s : float
        The loop's period (s): sizes the window's ring (``window_s / period_s`` samples).
    start : tuple of float, optional
        ``(a0, a1, a2, a3)`` before the first fit (1, s, N s/m, kg); default ``(1, 0, 0, 0)``, the
        command equal to the force. Must lie within the bounds.
    learn_above_m_s : float, optional
        ``v_learn`` of (C8) (m/s): samples enter the window only while the filtered sliding
        velocity is at least this; default 0, every sample (the factory gives ``D_y / tau_f``).

    Attributes
    ----------
    coefficients : ndarray (4,)
        ``(a0, a1, a2, a3)`` in use (1, s, N s/m, kg).
    fits : int
        Fits taken (windows excited enough).
    clip_N : float
        The last fit's clip, as the RMS change of the window's command (N, (C7)).
    """

    name = "adaptive"

    __slots__ = (
        "settings", "coefficients", "fits", "reference_N", "command_N", "pinned", "diverged", "bound_value", "clip_N",
        "_ring", "_size", "_head", "_count", "_normal", "_right", "_work", "_solution", "_low", "_high", "_tau",
        "_tau_f", "_u_f", "_v_f", "_y_f", "_primed", "_start", "_learn_above",
    )

    def __init__(self, settings: AdaptiveCompensationConfig, period_s: float,
                 start: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0), learn_above_m_s: float = 0.0):
        self.settings = settings
        self._size = max(2, int(round(settings.window_s / period_s)))
        self._ring = np.zeros((self._size, TERMS + 1))
        # the normal equations, scratch and solution as lists of floats: the tick indexes them, and
        # a list's item is several times faster to read and write than an ndarray's
        self._normal = [[0.0] * TERMS for _ in range(TERMS)]
        self._right = [0.0] * TERMS
        self._work = [[0.0] * (TERMS + 2) for _ in range(TERMS)]
        self._solution = [0.0] * TERMS
        self.coefficients = np.zeros(TERMS)
        self._low = (settings.gain_bounds[0], settings.lead_bounds_s[0], settings.flow_bounds_Ns_per_m[0],
                     settings.acceleration_bounds_kg[0])
        self._high = (settings.gain_bounds[1], settings.lead_bounds_s[1], settings.flow_bounds_Ns_per_m[1],
                      settings.acceleration_bounds_kg[1])
        self._tau = settings.reference_time_constant_s
        self._tau_f = settings.filter_time_constant_s
        if len(start) != TERMS or not all(self._low[i] <= value <= self._high[i] for i, value in enumerate(start)):
            raise ModelError(f"the adaptive compensator's start {start} is outside its bounds {self._low}..{self._high}")
        if not (math.isfinite(learn_above_m_s) and learn_above_m_s >= 0.0):
            raise ModelError(f"the sliding velocity the adaptive compensator learns above must be >= 0 m/s, "
                             f"found {learn_above_m_s}")
        self._start = tuple(float(value) for value in start)
        self._learn_above = float(learn_above_m_s)
        self.reset()

    def reset(self) -> None:
        """Empty window, coefficients at their start, zero reference and filters."""
        self._ring[:] = 0.0
        for i in range(TERMS):
            self._normal[i][:] = [0.0] * TERMS
        self._right[:] = [0.0] * TERMS
        self._head = self._count = 0
        self.coefficients[:] = self._start
        self.fits = 0
        self.reference_N = self.command_N = self.bound_value = self.clip_N = 0.0
        self._u_f = self._v_f = self._y_f = 0.0
        self._primed = False
        self.pinned = self.diverged = False

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """The command (N) of (C5); first the window learns from the previous command and this tick's response."""
        velocity = meas.sliding_velocity_m_s
        if math.isfinite(dt) and dt > 0.0:
            self._learn(dt, meas.actuator_force_N, velocity, applied_N)
        if not math.isfinite(force_N) or not math.isfinite(dt) or dt <= 0.0:
            self.command_N = math.nan
            return self.command_N
        self.reference_N, rate = reference_step(self.reference_N, force_N, dt, self._tau)  # (C2)
        a = self.coefficients
        acceleration = (velocity - self._v_f) / self._tau_f  # F(xddot_b)
        self.command_N = float(a[0] * self.reference_N + a[1] * rate + a[2] * velocity + a[3] * acceleration)  # (C5)
        return self.command_N

    def _learn(self, dt: float, force_N: float, velocity_m_s: float, applied_N: float) -> None:
        """Filter the sample, put it in the window while the base mat slides (C8), and fit when excited enough."""
        if not (math.isfinite(force_N) and math.isfinite(velocity_m_s) and math.isfinite(applied_N)):
            return
        if not self._primed:  # the filters start at the first sample (no step from zero)
            self._u_f, self._v_f, self._y_f, self._primed = force_N, velocity_m_s, applied_N, True
        alpha = 1.0 - math.exp(-dt / self._tau_f)
        self._u_f += alpha * (force_N - self._u_f)
        self._v_f += alpha * (velocity_m_s - self._v_f)
        self._y_f += alpha * (applied_N - self._y_f)
        if abs(self._v_f) < self._learn_above:
            return  # (C8): a stuck bearing's creep, not the actuator's flow
        tau_f = self._tau_f
        self._push(self._u_f, (force_N - self._u_f) / tau_f, self._v_f, (velocity_m_s - self._v_f) / tau_f, self._y_f)
        if 2 * self._count >= self._size:
            self._fit()

    def _push(self, p0: float, p1: float, p2: float, p3: float, y: float) -> None:
        """Add a sample to the ring and the running sums; the oldest leaves when the ring is full."""
        row = self._ring[self._head]
        if self._count == self._size:
            self._accumulate(row[0], row[1], row[2], row[3], row[TERMS], -1.0)
        else:
            self._count += 1
        row[0], row[1], row[2], row[3], row[TERMS] = p0, p1, p2, p3, y
        self._accumulate(p0, p1, p2, p3, y, 1.0)
        self._head = (self._head + 1) % self._size

    def _accumulate(self, p0: float, p1: float, p2: float, p3: float, y: float, sign: float) -> None:
        """Add (sign 1) or remove (sign -1) one sample's products from the normal equations' sums."""
        r0, r1, r2, r3 = self._normal
        right = self._right
        r0[0] += sign * p0 * p0
        r0[1] += sign * p0 * p1
        r0[2] += sign * p0 * p2
        r0[3] += sign * p0 * p3
        r1[1] += sign * p1 * p1
        r1[2] += sign * p1 * p2
        r1[3] += sign * p1 * p3
        r2[2] += sign * p2 * p2
        r2[3] += sign * p2 * p3
        r3[3] += sign * p3 * p3
        r1[0], r2[0], r3[0], r2[1], r3[1], r3[2] = r0[1], r0[2], r0[3], r1[2], r1[3], r2[3]
        right[0] += sign * p0 * y
        right[1] += sign * p1 * y
        right[2] += sign * p2 * y
        right[3] += sign * p3 * y

    def _fit(self) -> None:
        """Solve the window's normal equations; clip to the bounds; report the clip (C7) and a non-finite state."""
        # the diagonal and the right-hand side suffice: |R_ij| <= sqrt(R_ii R_jj) bounds the rest
        r0, r1, r2, r3 = self._normal
        right = self._right
        self.diverged = not math.isfinite(r0[0] + r1[1] + r2[2] + r3[3] + right[0] + right[1] + right[2] + right[3])
        if self.diverged:
            return
        solution = self._solution
        if not solve_normalized(self._normal, self._right, self.settings.min_excitation, self._work, solution):
            return  # not excited enough: hold the last coefficients
        self.fits += 1
        first_clipped = -1
        for i in range(TERMS):
            value = solution[i]
            clipped = min(max(value, self._low[i]), self._high[i])
            if clipped != value and first_clipped < 0:
                first_clipped = i
            solution[i] = value - clipped  # the clip d
            self.coefficients[i] = clipped
        self.clip_N = self._clip_rms_N(solution)
        self.pinned = self.clip_N > self.settings.clip_tolerance_N
        if first_clipped >= 0:
            self.bound_value = self.coefficients[first_clipped] + solution[first_clipped]

    def _clip_rms_N(self, clip: list[float]) -> float:
        """``sqrt(d^T R d / n)`` (N): the RMS change of the window's command made by the clip ``d`` (C7)."""
        total = 0.0
        for i in range(TERMS):
            row = self._normal[i]
            for j in range(TERMS):
                total += clip[i] * row[j] * clip[j]
        return math.sqrt(max(total, 0.0) / self._count)

