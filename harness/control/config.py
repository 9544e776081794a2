"""The ``control:`` section of a profile: sample rate, friction source and named designs."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

from harness.config.input_limits import (
    MAX_DELAY_S,
    MAX_RATE_HZ,
    MAX_STIFFNESS_SCALE,
    MIN_STIFFNESS_SCALE,
)
from harness.config.schema import quantity
from harness.control.compensation import CompensationName, CompensatorSettings
from harness.control.designs import ControllerDesign


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
    rate_hz: float = quantity(500.0, unit="Hz", gt=0, le=MAX_RATE_HZ, doc="controller sample rate f_s")
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
