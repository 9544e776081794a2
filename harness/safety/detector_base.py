"""The detector contract and the small preallocated helpers detectors share.

A detector is fed once per tick with ``update(t, dt, health)`` and returns True
on every tick its condition holds (the supervisor acts and records an event on
the rising edge). It never reads a clock, never does I/O and allocates nothing
per tick; :meth:`Detector.detail` builds a string only when the supervisor
records an event.
"""

from __future__ import annotations

import math

from harness.safety.events import Action
from harness.safety.health import TickHealth

#: sqrt(2), the Butterworth damping of :class:`HighPass`.
SQRT2 = math.sqrt(2.0)

#: Tolerance on time comparisons (s), so that a persistence of exactly N ticks is N ticks.
TIME_EPS_S = 1e-9


class Detector:
    """Base class: a named fault check with an action.

    Subclasses set :attr:`NAME`, :attr:`ACTION` (default action), :attr:`DETECTS`,
    :attr:`BOUND`, :attr:`RESET` and implement :meth:`update` and :meth:`detail`.

    Parameters
    ----------
    action : Action, optional
        Overrides the default action (used for the detectors whose action is configurable).
    """

    NAME = ""
    ACTION = Action.TRIP
    DETECTS = ""
    BOUND = ""
    RESET = "explicit reset"

    __slots__ = ("action",)

    def __init__(self, action: Action | None = None) -> None:
        self.action = self.ACTION if action is None else action

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """Advance one tick; True while the fault condition holds."""
        raise NotImplementedError

    def detail(self, health: TickHealth) -> str:
        """What was seen and what was expected (called only when an event is recorded)."""
        raise NotImplementedError

    def present(self, health: TickHealth) -> str:
        """Non-empty description if the condition is visibly still present in ``health``.

        Used to refuse a reset. Returns "" when the condition is gone or cannot be
        known from a single sample (jumps, stuck values, tracking errors, ...).
        """
        return ""

    def reset(self) -> None:
        """Forget all history (called on arm and on reset)."""


class Persistence:
    """Time a condition has held: fires once it has held for ``limit_s``.

    The condition's onset is the first tick it holds; it fires on the first tick
    with ``t - onset >= limit_s`` (within :data:`TIME_EPS_S`), and restarts when
    the condition clears.
    """

    __slots__ = ("limit_s", "onset_s", "active")

    def __init__(self, limit_s: float) -> None:
        self.limit_s = limit_s
        self.onset_s = 0.0
        self.active = False

    def update(self, t: float, condition: bool) -> bool:
        """Feed this tick's condition; True once it has persisted for ``limit_s``."""
        if not condition:
            self.active = False
            return False
        if not self.active:
            self.active = True
            self.onset_s = t
        return t - self.onset_s >= self.limit_s - TIME_EPS_S

    def held_s(self, t: float) -> float:
        """How long the condition has held at ``t`` (s; 0 if not active)."""
        return t - self.onset_s if self.active else 0.0

    def reset(self) -> None:
        """Forget the onset."""
        self.active = False


class WindowCounter:
    """More than ``max_count`` events within a sliding window of ``window_s``, from a cumulative counter.

    Event times are the tick times at which the counter was seen to increase,
    kept in a preallocated ring of ``max_count + 1`` slots. It fires while the
    ring is full and its oldest entry is no older than ``window_s``. A counter that
    goes backwards (driver restart) is re-synchronised without counting.
    """

    __slots__ = ("max_count", "window_s", "_times", "_head", "_n", "_last_total", "_primed")

    def __init__(self, max_count: int, window_s: float) -> None:
        self.max_count = max_count
        self.window_s = window_s
        self._times = [0.0] * (max_count + 1)
        self._head = 0
        self._n = 0
        self._last_total = 0
        self._primed = False

    def _push(self, t: float) -> None:
        size = len(self._times)
        if self._n == size:
            self._times[self._head] = t
            self._head = (self._head + 1) % size
        else:
            self._times[(self._head + self._n) % size] = t
            self._n += 1

    def update(self, t: float, total: int) -> bool:
        """Feed the cumulative counter at tick time ``t``; True while over the limit."""
        if not self._primed:
            self._primed = True
            self._last_total = total
            return False
        new = total - self._last_total
        self._last_total = total
        for _ in range(min(max(new, 0), len(self._times))):
            self._push(t)
        return self.count(t) > self.max_count

    def count(self, t: float) -> int:
        """Events remembered within the window ending at ``t`` (at most ``max_count + 1``)."""
        size = len(self._times)
        inside = 0
        for k in range(self._n):
            if t - self._times[(self._head + k) % size] <= self.window_s + TIME_EPS_S:
                inside += 1
        return inside

    def reset(self) -> None:
        """Forget all events; the next update only primes the counter."""
        self._n = 0
        self._head = 0
        self._primed = False


class LowPass:
    """First-order low-pass ``y += dt / (tau + dt) * (u - y)``, primed by its first input."""

    __slots__ = ("tau_s", "y", "primed")

    def __init__(self, tau_s: float) -> None:
        self.tau_s = tau_s
        self.y = 0.0
        self.primed = False

    def update(self, u: float, dt: float) -> float:
        """Filter one sample taken ``dt`` seconds after the previous one."""
        if not self.primed:
            self.primed = True
            self.y = u
        else:
            self.y += dt / (self.tau_s + dt) * (u - self.y)
        return self.y

    def reset(self, value: float = 0.0, primed: bool = False) -> None:
        """Set the output to ``value``; unprimed filters take their next input as is."""
        self.y = value
        self.primed = primed


class HighPass:
    """Second-order Butterworth high-pass at ``corner_hz``, by the trapezoidal rule on states in the input's unit.

    ``H(s) = s^2 / (s^2 + sqrt(2) w_c s + w_c^2)`` is ``y = u - z - sqrt(2) v`` with ``z`` the
    Butterworth low-pass of ``u`` and ``v = z' / w_c``: ``z' = w_c v``, ``v' = w_c y``. Both states are
    in the input's unit and mean the same thing whatever the step, so a step that changes (a
    stall, then the period again) changes only how far they move, never what they hold. The
    direct-form biquad this replaced kept past inputs and outputs whose combination is right only
    for the step they were taken at: after a stall its output ran away (a 2 Hz force in the
    controller's band, in a 2 kHz loop with stalls of 1-10 ms, read millions of newtons above the
    corner; tests/unit/test_force_oscillation.py).

    Each step is the trapezoidal rule with ``a = w_c dt / 2`` pre-warped to ``a = tan(pi f_c dt)``:
    at a constant ``dt`` exactly the bilinear transform of ``H`` with its corner at ``f_c``. A step
    longer than :attr:`max_step_s` (a quarter period at the corner: a stall) is taken as that long
    (``a`` at most 1). Primed by its first input at rest (``z = u``, ``v = 0``: a constant input gives 0).
    """

    __slots__ = ("corner_hz", "max_step_s", "_u", "_z", "_v", "primed")

    def __init__(self, corner_hz: float) -> None:
        self.corner_hz = corner_hz
        self.max_step_s = 0.25 / corner_hz
        self._u = self._z = self._v = 0.0
        self.primed = False

    def update(self, u: float, dt: float) -> float:
        """Filter one sample taken ``dt`` seconds after the previous one."""
        if not self.primed:
            self.primed = True
            self._u, self._z, self._v = u, u, 0.0
        a = math.tan(math.pi * self.corner_hz * min(dt, self.max_step_s))
        # (I - a M) x_new = (I + a M) x + a (u_old + u) [0, 1], M = [[0, 1], [-1, -sqrt(2)]]
        r1 = self._z + a * self._v
        r2 = -a * self._z + (1.0 - SQRT2 * a) * self._v + a * (self._u + u)
        det = 1.0 + SQRT2 * a + a * a
        self._z = ((1.0 + SQRT2 * a) * r1 + a * r2) / det
        self._v = (r2 - a * r1) / det
        self._u = u
        return u - self._z - SQRT2 * self._v

    def reset(self) -> None:
        """Unprime: the next input starts the filter at rest."""
        self.primed = False
