"""Controller designs as profile entries: settings only (:mod:`harness.control.factory` builds a controller from one).

A profile's ``control.designs`` maps names (``FSF-I``, ``OF-I``, ``phi``) to one of
the design dataclasses below, told apart by ``kind``. The two ``*_actuator`` kinds are
designed on the building augmented with the actuator's force state
(:mod:`harness.control.actuator_aware`) and take the actuator model from ``rig.actuator``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from harness.config.schema import quantity

DELTA_DOC = "sliding margin delta >= 0 in N kg s/m (SI, with P B = 1/m_b)"


@dataclass(frozen=True)
class LqrWeights:
    """Diagonal LQR weights of Eq. 9 by named group (SPEC 6a)."""

    drifts: float = quantity(ge=0, doc="weight on every story drift")
    base_displacement: float = quantity(ge=0, doc="weight on y_b")
    velocities: float = quantity(gt=0, doc="weight on every velocity")


@dataclass(frozen=True)
class SurfaceConfig:
    """How P is chosen: LQR on the regular form (default) or pole assignment."""

    method: Literal["lqr", "poles"] = "lqr"
    q: LqrWeights | None = None
    poles_per_s: tuple[float, ...] | None = quantity(None, unit="1/s", lt=0, doc="N-1 real sliding-mode poles")

    def __post_init__(self) -> None:
        if self.method == "lqr" and self.q is None:
            raise ValueError("surface method 'lqr' needs q: {drifts, base_displacement, velocities}")
        if self.method == "poles" and self.poles_per_s is None:
            raise ValueError("surface method 'poles' needs poles_per_s")


@dataclass(frozen=True)
class FullStateDesign:
    """Full-state feedback with an LQR or pole-assignment surface (Eq. 13, 15)."""

    kind: Literal["full_state"]
    surface: SurfaceConfig
    delta: float = quantity(0.0, ge=0, doc=DELTA_DOC)
    alpha_star: float = quantity(1.0, ge=0, le=1, doc="partial compensation alpha* (Eq. 15)")


@dataclass(frozen=True)
class StaticOutputDesign:
    """Static output feedback: Z with unmeasured entries set to zero (Eq. 16-17)."""

    kind: Literal["static_output"]
    surface: SurfaceConfig
    measured: tuple[str, ...] = quantity(doc="measured states by name: x_1..x_n, y_b, xdot_1..xdot_n, ydot_b")
    delta: float = quantity(0.0, ge=0, doc=DELTA_DOC)
    alpha_star: float = quantity(1.0, ge=0, le=1, doc="partial compensation alpha*")


@dataclass(frozen=True)
class SimpleOutputDesign:
    """Simple output feedback S = p1 y_b + ydot_b (Eq. 18-21)."""

    kind: Literal["simple_output"]
    p1_per_s: float = quantity(unit="1/s", gt=0, doc="pole of the sliding surface")
    delta: float = quantity(0.0, ge=0, doc=DELTA_DOC)


@dataclass(frozen=True)
class PhiDesign:
    """Partial restraint cancellation (Eq. 22-23), the shaking-table controller."""

    kind: Literal["phi"]
    p1_per_s: float = quantity(unit="1/s", gt=0, doc="pole of the sliding surface (1/s; the source's 'per mm' does not fit)")
    phi: float = quantity(ge=0, le=1, doc="share of the restraining springs cancelled")
    delta: float = quantity(0.0, ge=0, doc=DELTA_DOC)


REACHING_DOC = "rate eta at which the actuator force reaches its surface (1/s); default the actuator model's w_f"


@dataclass(frozen=True)
class ActuatorLqrWeights(LqrWeights):
    """Diagonal LQR weights on the augmented state (Z, v): the groups of SPEC 6a and the net force."""

    force: float = quantity(gt=0, doc="weight q_v on the net base force v (1/N^2 on the scale of the others)")


@dataclass(frozen=True)
class StateFeedbackActuatorDesign:
    """Full-state sliding-mode control designed with the actuator's force state (offline only)."""

    kind: Literal["state_feedback_actuator"]
    q: ActuatorLqrWeights
    reaching_rate_per_s: float | None = quantity(None, unit="1/s", gt=0, doc=REACHING_DOC)


@dataclass(frozen=True)
class OutputActuatorDesign:
    """The phi surface (Eq. 22-23) with the actuator's force as a state: base mat, table and load cell."""

    kind: Literal["output_actuator"]
    p1_per_s: float = quantity(unit="1/s", gt=0, doc="pole of the phi surface")
    phi: float = quantity(ge=0, le=1, doc="share of the restraining springs cancelled")
    delta: float = quantity(0.0, ge=0, doc=DELTA_DOC + "; second sliding pole p2 = delta / m_b^2")
    reaching_rate_per_s: float | None = quantity(None, unit="1/s", gt=0, doc=REACHING_DOC)
    actuator_uncertainty: float = quantity(
        0.3, ge=0, lt=1, doc="relative error a of k_h and of w_f the design must survive; adds the margin of (A13)",
    )


ControllerDesign = (
    FullStateDesign | StaticOutputDesign | SimpleOutputDesign | PhiDesign | StateFeedbackActuatorDesign | OutputActuatorDesign
)
