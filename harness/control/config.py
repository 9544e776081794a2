"""The ``control:`` section of a profile: sample rate, friction source and named designs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from harness.config.input_limits import (
    DEFAULT_RATE_HZ,
    MAX_DELAY_S,
    MAX_RATE_HZ,
    MAX_STIFFNESS_SCALE,
    MIN_STIFFNESS_SCALE,
)
from harness.config.schema import quantity
from harness.control.designs import ControllerDesign

#: The methods of ``control.compensation``.
CompensationName = Literal["none", "model", "adaptive"]
COMPENSATION_NAMES: tuple[str, ...] = ("none", "model", "adaptive")

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


@dataclass(frozen=True)
class EstimatorSettings:
    """The friction estimator's own design values (``control.estimator``; SPEC 3, Eq. 3-5)."""

    yield_displacement_m: float | None = quantity(
        None, unit="m", gt=0,
        doc="the estimator's pre-sliding (Bouc-Wen yield) displacement; none: the bearing's D_y "
            "(docs/SAFETY.md, 'The friction estimator's loop')",
    )


@dataclass(frozen=True)
class ControlConfig:
    """Controller sampling and the named controller designs of a profile."""

    controller: str = quantity(doc="name of the design used by default (a key of designs)")
    designs: Mapping[str, ControllerDesign] = quantity(doc="named controller designs")
    # Bounds shared with the command line; harness/config/input_limits.py gives the reasons.
    rate_hz: float = quantity(
        DEFAULT_RATE_HZ, unit="Hz", gt=0, le=MAX_RATE_HZ,
        doc="the one rate: the controller's sample rate f_s, the loop's tick and the actuator command's rate",
    )
    transport_delay_s: float = quantity(
        0.0, unit="s", ge=0, le=MAX_DELAY_S, doc="further sensor-to-force delay in simulation"
    )
    friction: Literal["estimator", "model"] = "estimator"
    design_stiffness_scale: float = quantity(
        1.0, ge=MIN_STIFFNESS_SCALE, le=MAX_STIFFNESS_SCALE, doc="story stiffness of the controller's model / plant's"
    )
    compensation: CompensationName = field(default="none", metadata={
        "doc": "force-tracking compensation between the controller's force and the supervisor: none or model "
               "(harness/control/compensation.py)",
    })
    compensator: CompensatorSettings = field(default_factory=CompensatorSettings)
    estimator: EstimatorSettings = field(default_factory=EstimatorSettings)

    def __post_init__(self) -> None:
        if not self.designs:
            raise ValueError("designs is empty; expected at least one named controller design")
        if self.controller not in self.designs:
            raise ValueError(f"controller {self.controller!r} is not one of the designs: {', '.join(self.designs)}")


@dataclass(frozen=True)
class SimulationConfig:
    """Integration settings of the offline simulator and the virtual rig's plant."""

    rtol: float = quantity(1e-6, gt=0, lt=1e-2, doc="relative tolerance of the integration kernel")
