"""Force-tracking compensation: what stands between the controller's force and the supervisor.

A controller asks for the force ``f_d`` it wants on the base mat. A servo-hydraulic actuator
under a proportional force loop does not give it: below its loop bandwidth ``w_f`` its force
obeys (SPEC 7a, harness/hydraulics/cylinder.py)

    udot = w_f (u_c - u) - k_h xdot_b,                                               (C1)

a first-order lag of the command ``u_c`` less the natural velocity feedback ``(k_h / w_f)
xdot_b`` (the force bleeds while the piston strokes). A compensator turns ``f_d`` into the
command ``u_c`` so that the load cell's ``u`` follows ``f_d``:

- ``none`` (:class:`NoCompensation`): ``u_c = f_d``, the harness before compensation;
- ``model`` (:class:`harness.control.model_compensation.ModelCompensator`): the inverse of
  (C1) on the profile's (or identified) actuator model, a flow term and a load-cell correction;
- ``adaptive`` (:class:`harness.control.adaptive_compensation.AdaptiveCompensator`): the
  adaptive time-series compensator of Chae, Kazemibidokhti & Ricles (2013), its coefficients
  fitted online over a moving window, within stated bounds.

The compensator's command is the supervisor's input, beside the controller's force (the
setpoint): the force clamp bounds the setpoint by ``safety.force.max_force_N`` and what the
compensator added by ``safety.force.max_flow_term_N``; the rate limit, the stroke fade, the
stopping ramp and every interlock act on the sum (docs/SAFETY.md, "What max_force_N must bound").
The loop owns time: :meth:`Compensator.update`
takes ``t`` and ``dt``, reads no clock, allocates nothing.

A compensator reports its own health on every update: :attr:`Compensator.pinned` while a bounded
parameter sits at its bound, :attr:`Compensator.diverged` once its state is not finite; the loop
copies both into :class:`harness.safety.health.TickHealth` and the supervisor's
``compensation_fault`` check acts on them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

from drivers.measurements import Measurements

if TYPE_CHECKING:
    from harness.safety.health import TickHealth
    from harness.safety.supervisor import SupervisedCommand

#: A command the supervisor sent within this of the compensator's own (N) went out unchanged:
#: no clamp, ramp, rate limit or fade acted on it (the command frame's resolution is coarser).
UNCHANGED_TOLERANCE_N = 1.0


class Compensator(Protocol):
    """What the loop and the twin need of a compensator.

    Attributes
    ----------
    name : str
        The ``control.compensation`` method.
    command_N : float
        The command of the last update (N), before the supervisor.
    pinned : bool
        A bounded parameter (a correction, a coefficient) sat at its bound after the last update.
    diverged : bool
        The compensator's state is not finite (latched until :meth:`reset`).
    bound_value : float
        The parameter :attr:`pinned` or :attr:`diverged` refers to (its unit is the parameter's), for the record.
    """

    name: str
    command_N: float
    pinned: bool
    diverged: bool
    bound_value: float

    def reset(self) -> None:
        """Back to the state before the first update (zero force, no correction)."""

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """The actuator command (N) for the controller's force ``force_N`` (N) at ``t`` (s).

        ``dt`` (s) is the time since the previous update; ``meas`` this tick's measurements
        (``sliding_velocity_m_s`` and the load cell's ``actuator_force_N``); ``applied_N`` the
        command the supervisor sent on the previous tick (0 while the drive was disabled).
        Never reads a clock, never allocates.
        """
        ...


class NoCompensation:
    """``control.compensation: none``: the command is the controller's force."""

    name = "none"

    __slots__ = ("command_N", "pinned", "diverged", "bound_value")

    def __init__(self) -> None:
        self.command_N = 0.0
        self.pinned = False
        self.diverged = False
        self.bound_value = 0.0

    def reset(self) -> None:
        """Nothing to clear but the last command."""
        self.command_N = 0.0

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """``force_N`` unchanged (N)."""
        self.command_N = force_N
        return force_N


def reference_step(reference_N: float, force_N: float, dt: float, tau_s: float) -> tuple[float, float]:
    """One step of the reference (C2) for ``force_N`` held over ``dt``: the new ``r`` (N) and its rate ``r'`` (N/s).

    ``r' = (f_d - r) / tau_r`` after the exact step of the lag, so the inverse needs no differencing.
    """
    reference_N += (1.0 - math.exp(-dt / tau_s)) * (force_N - reference_N)
    return reference_N, (force_N - reference_N) / tau_s


def compensate(
    compensator: Compensator, t: float, dt: float, force_N: float, meas: Measurements, previous: SupervisedCommand,
    health: TickHealth,
) -> float:
    """The compensator's command (N) for the controller's force ``force_N`` (N); its health into ``health``.

    What the loop's tick and the rig twin both do between the controller and the supervisor. The
    compensator is told the command the supervisor sent the tick before (``previous``; 0 while
    the drive was disabled), so that its correction does not wind up against the supervisor's limits.
    """
    command_N = compensator.update(t, dt, force_N, meas, previous.force_N if previous.enable else 0.0)
    health.compensation_pinned = compensator.pinned
    health.compensation_diverged = compensator.diverged
    health.compensation_value = compensator.bound_value
    return command_N
