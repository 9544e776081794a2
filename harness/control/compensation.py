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
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol

from drivers.measurements import Measurements
from harness.config.schema import quantity

if TYPE_CHECKING:
    from harness.safety.health import TickHealth
    from harness.safety.supervisor import SupervisedCommand

#: The methods of ``control.compensation``.
CompensationName = Literal["none", "model", "adaptive"]
COMPENSATION_NAMES: tuple[str, ...] = ("none", "model", "adaptive")

#: A command the supervisor sent within this of the compensator's own (N) went out unchanged:
#: no clamp, ramp, rate limit or fade acted on it (the command frame's resolution is coarser).
UNCHANGED_TOLERANCE_N = 1.0


@dataclass(frozen=True)
class ModelCompensationConfig:
    """Settings of the model-based compensator (``control.compensator.model``).

    The actuator's ``k_h`` and ``w_f`` are not settings: they come from ``rig.actuator``
    (or an identified overlay of it), as for the actuator-aware designs.
    """

    reference_time_constant_s: float = quantity(
        0.004, unit="s", gt=0.0, le=0.1,
        doc="tau_r: the force the actuator is made to follow is f_d through a first-order lag of tau_r (the inverse's roll-off)",
    )
    correction_rate_per_s: float = quantity(
        10.0, unit="1/s", ge=0.0, le=100.0, doc="k_c: integral gain of the load-cell correction (0: no correction)",
    )
    correction_limit_N: float = quantity(
        1000.0, unit="N", gt=0.0, doc="|load-cell correction| bound; below safety.force.tracking_tolerance_N",
    )


@dataclass(frozen=True)
class AdaptiveCompensationConfig:
    """Settings of the adaptive time-series compensator (``control.compensator.adaptive``).

    The command is ``u_c = a0 r + a1 r' + a2 xdot_b + a3 xddot_b``; the bounds state the range of actuators
    it may adapt to (harness/control/adaptive_compensation.py derives the defaults).
    """

    reference_time_constant_s: float = quantity(
        0.004, unit="s", gt=0.0, le=0.1, doc="tau_r: the force is made to follow f_d through a first-order lag of tau_r",
    )
    start: Literal["none", "model"] = field(default="model", metadata={
        "doc": "the coefficients before the first fit: none (1, 0, 0, 0) or model (1, 1 / w_f, k_h / w_f of rig.actuator, 0)",
    })
    window_s: float = quantity(2.0, unit="s", gt=0.0, le=10.0, doc="length of the moving window the coefficients are fitted over")
    filter_time_constant_s: float = quantity(
        0.01, unit="s", gt=0.0, le=0.1, doc="tau_f of the low-pass applied alike to every signal of the fit",
    )
    min_excitation: float = quantity(
        1.0e-3, gt=0.0, lt=1.0, doc="smallest normalized determinant of the window's normal matrix for a new fit",
    )
    gain_bounds: tuple[float, ...] = quantity(
        (0.8, 1.25), gt=0.0, min_len=2, doc="[low, high] of a0, the static gain of the force loop's inverse",
    )
    lead_bounds_s: tuple[float, ...] = quantity(
        (0.0, 0.02), unit="s", ge=0.0, min_len=2, doc="[low, high] of a1, the inverse's lead (1 / w_f and the delays)",
    )
    flow_bounds_Ns_per_m: tuple[float, ...] = quantity(
        (0.0, 200_000.0), unit="N*s/m", ge=0.0, min_len=2, doc="[low, high] of a2, the flow term's gain (k_h / w_f)",
    )
    acceleration_bounds_kg: tuple[float, ...] = quantity(
        (-400.0, 4000.0), unit="kg", min_len=2,
        doc="[low, high] of a3, the sliding acceleration's gain: what a lagging feed-forward leaves, a sample's lead (C6)",
    )
    clip_tolerance_N: float = quantity(
        1.0, unit="N", gt=0.0, doc="a clip of the fit that changes the window's command by more than this RMS is pinned (C7)",
    )

    def __post_init__(self) -> None:
        for name in ("gain_bounds", "lead_bounds_s", "flow_bounds_Ns_per_m", "acceleration_bounds_kg"):
            bounds = getattr(self, name)
            if len(bounds) != 2 or not bounds[0] < bounds[1]:
                raise ValueError(f"{name} must be [low, high] with low < high, found {list(bounds)}")
        if not self.gain_bounds[0] <= 1.0 <= self.gain_bounds[1]:
            raise ValueError(f"gain_bounds must hold 1 (the start: the command is the force), found {list(self.gain_bounds)}")
        if self.window_s < 10.0 * self.filter_time_constant_s:
            raise ValueError(f"window_s ({self.window_s:g} s) must be at least 10 filter time constants "
                             f"({10.0 * self.filter_time_constant_s:g} s)")


@dataclass(frozen=True)
class CompensatorSettings:
    """Settings of each compensation method (``control.compensator``)."""

    model: ModelCompensationConfig = field(default_factory=ModelCompensationConfig)
    adaptive: AdaptiveCompensationConfig = field(default_factory=AdaptiveCompensationConfig)


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
