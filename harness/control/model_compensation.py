"""The model-based force-tracking compensator (``control.compensation: model``).

Built on the first-order actuator model (C1) of :mod:`harness.control.compensation`,
``udot = w_f (u_c - u) - k_h xdot_b``, with ``k_h`` and ``w_f`` from the profile's
``rig.actuator`` (or an identified overlay) through
:class:`harness.control.actuator_aware.ActuatorModel`, as the actuator-aware designs take them.

Reference model
---------------
The controller's force ``f_d`` may step (a sliding-mode controller's force does); the
inverse of a lag cannot follow a step. The actuator is made to follow the reference

    r' = (f_d - r) / tau_r,                                                          (C2)

``f_d`` through a first-order lag of ``tau_r`` (4 ms by default, half the actuator's own
``1 / w_f`` = 8 ms on the shipped rig): ``r`` and its rate ``r'`` are both known exactly, so
the inverse needs no differentiation. Each tick ``r`` advances by the exact step of (C2) for
``f_d`` held over ``dt``.

Command
-------
Inverting (C1) for ``u = r``:

    u_c = r + r' / w_f  +  (k_h / w_f) xdot_b  +  e_c                                 (C3)

- ``r + r' / w_f``: the inverse dynamics as feedforward (the lag's inverse on the reference);
- ``(k_h / w_f) xdot_b``: the flow term, with the measured sliding velocity, which cancels
  the natural velocity feedback (the force lost while the piston strokes);
- ``e_c``: the correction from the load cell, an integral of the tracking error,

    e_c' = k_c (r - u),   |e_c| <= e_max,                                            (C4)

  which takes out what the model gets wrong slowly (a ``k_h / w_f`` off by a share, a leak).
  It integrates only on ticks whose previous command went out as the compensator computed it
  (no clamp, ramp, rate limit or fade acted: conditional integration, no wind-up against the
  supervisor's limits) and only on finite errors. ``k_c`` is below ``w_f / 4`` (the loop
  ``k_c w_f / (s (s + w_f))`` is then critically damped or slower).

With (C3) on the model (C1) the tracking error ``e = u - r`` obeys ``e' = -w_f e + w_f e_c``:
it decays at the actuator's own rate ``w_f`` whatever the sliding velocity, so a constant
sliding velocity leaves no force deficit (without the flow term the deficit is
``(k_h / w_f) xdot_b``).

What the clamp bounds
---------------------
``u_c`` is the supervisor's input, so ``safety.force.max_force_N`` bounds the command: the
force the cylinder gives against a blocked piston, whatever share of it is flow term or
correction (docs/SAFETY.md, "Force-tracking compensation" derives why this is the bound to
keep). The high-frequency gain of the feedforward is ``1 / (w_f tau_r)`` (2 on the shipped
rig): the rate limit acts on it, as on any command.
"""

from __future__ import annotations

import math

from drivers.measurements import Measurements
from harness.control.actuator_aware import ActuatorModel
from harness.control.compensation import UNCHANGED_TOLERANCE_N, reference_step
from harness.control.config import ModelCompensationConfig
from harness.errors import ModelError


class ModelCompensator:
    """Inverse dynamics, flow term and load-cell correction on the actuator model, (C2)-(C4).

    Parameters
    ----------
    actuator : ActuatorModel
        ``k_h`` (N/m) and ``w_f`` (rad/s) of (C1).
    settings : ModelCompensationConfig
        ``tau_r`` (s), ``k_c`` (1/s) and ``e_max`` (N).

    Attributes
    ----------
    reference_N : float
        ``r`` of (C2) after the last update (N).
    feedforward_N : float
        ``r + r' / w_f`` of the last update (N).
    flow_N : float
        ``(k_h / w_f) xdot_b`` of the last update (N).
    correction_N : float
        ``e_c`` of (C4) (N); :attr:`pinned` while ``|e_c| = e_max``.
    """

    name = "model"

    __slots__ = (
        "actuator", "settings", "_w_f", "_damping", "_tau", "_gain", "_limit",
        "reference_N", "feedforward_N", "flow_N", "correction_N", "command_N", "pinned", "diverged", "bound_value",
    )

    def __init__(self, actuator: ActuatorModel, settings: ModelCompensationConfig):
        if settings.correction_rate_per_s > actuator.bandwidth_rad_s / 4.0:
            raise ModelError(
                f"the load-cell correction's gain k_c must be at most w_f / 4 = {actuator.bandwidth_rad_s / 4.0:.4g} 1/s, "
                f"found {settings.correction_rate_per_s:g} 1/s"
            )
        self.actuator = actuator
        self.settings = settings
        self._w_f = actuator.bandwidth_rad_s
        self._damping = actuator.loop_damping_Ns_per_m
        self._tau = settings.reference_time_constant_s
        self._gain = settings.correction_rate_per_s
        self._limit = settings.correction_limit_N
        self.reset()

    def reset(self) -> None:
        """Zero reference, zero correction, not pinned."""
        self.reference_N = 0.0
        self.feedforward_N = 0.0
        self.flow_N = 0.0
        self.correction_N = 0.0
        self.command_N = 0.0
        self.pinned = False
        self.diverged = False
        self.bound_value = 0.0

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """The command (N) of (C3) for the controller's force ``force_N`` (N).

        A non-finite force or measurement gives a non-finite command (the supervisor trips on
        it) and leaves the compensator's state as it was.
        """
        self._correct(dt, meas.actuator_force_N, applied_N)
        if not math.isfinite(force_N) or not math.isfinite(dt) or dt <= 0.0:
            self.command_N = math.nan
            return self.command_N
        self.reference_N, rate = reference_step(self.reference_N, force_N, dt, self._tau)  # (C2)
        self.feedforward_N = self.reference_N + rate / self._w_f
        self.flow_N = self._damping * meas.sliding_velocity_m_s
        self.command_N = self.feedforward_N + self.flow_N + self.correction_N  # (C3)
        return self.command_N

    def _correct(self, dt: float, measured_N: float, applied_N: float) -> None:
        """Advance ``e_c`` of (C4) on the error of the reference the actuator was following."""
        if self._gain > 0.0 and abs(applied_N - self.command_N) <= UNCHANGED_TOLERANCE_N:
            error = self.reference_N - measured_N
            step = self._gain * error * dt
            if math.isfinite(step):
                self.correction_N = min(max(self.correction_N + step, -self._limit), self._limit)
        self.pinned = abs(self.correction_N) >= self._limit
        self.bound_value = self.correction_N
