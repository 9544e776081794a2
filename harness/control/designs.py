"""Controller designs as profile entries, and building a controller from one.

A profile's ``control.designs`` maps names (``FSF-I``, ``OF-I``, ``phi``) to one of
the design dataclasses below, told apart by ``kind``. The two ``*_actuator`` kinds are
designed on the building augmented with the actuator's force state
(:mod:`harness.control.actuator_aware`) and take the actuator model from ``rig.actuator``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from harness.config.schema import quantity
from harness.control.actuator_aware import (
    ActuatorModel,
    ActuatorOutputSMC,
    ActuatorStateFeedbackSMC,
    actuator_lqr_surface,
    augmented_model,
    robust_sliding_margin,
)
from harness.control.controllers import Controller, PhiSMC, StateFeedbackSMC
from harness.control.surfaces import lqr_surface, pole_surface, q_diagonal_from_groups
from harness.errors import ModelError
from harness.model.building import BuildingConfig, state_space

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


def state_names(n_stories: int) -> list[str]:
    """Names of the entries of Z in order."""
    return (
        [f"x_{j}" for j in range(1, n_stories + 1)]
        + ["y_b"]
        + [f"xdot_{j}" for j in range(1, n_stories + 1)]
        + ["ydot_b"]
    )


def _surface(surface: SurfaceConfig, design_building: BuildingConfig) -> np.ndarray:
    model = state_space(design_building)
    if surface.method == "lqr":
        q = surface.q
        assert q is not None, "SurfaceConfig.__post_init__: lqr needs q"
        return lqr_surface(model, q_diagonal_from_groups(model.n_stories, q.drifts, q.base_displacement, q.velocities))
    return pole_surface(model, np.asarray(surface.poles_per_s))


def _measured_mask(measured: tuple[str, ...], n_stories: int) -> np.ndarray:
    names = state_names(n_stories)
    unknown = [m for m in measured if m not in names]
    if unknown:
        raise ModelError(f"unknown measured state {unknown[0]!r}; expected names from {', '.join(names)}")
    return np.array([name in measured for name in names])


def build_controller(
    name: str, design: ControllerDesign, design_building: BuildingConfig, actuator: ActuatorModel | None = None,
) -> Controller:
    """Make the controller ``name`` from its design, using ``design_building`` as the controller's model.

    ``design_building`` may differ from the plant's building (e.g. stiffness off by
    -30 % for the robustness study of SPEC 6a). ``actuator`` is the actuator's design model,
    needed by the ``*_actuator`` kinds only.

    Raises
    ------
    ModelError
        An actuator-aware design without an actuator model, or a surface that is not stable.
    """
    if isinstance(design, (StateFeedbackActuatorDesign, OutputActuatorDesign)):
        if actuator is None:
            raise ModelError(f"design {name!r} ({design.kind}) needs the actuator's model (rig.actuator)")
        return _build_actuator_aware(name, design, design_building, actuator)
    if isinstance(design, (SimpleOutputDesign, PhiDesign)):
        phi = 1.0 if isinstance(design, SimpleOutputDesign) else design.phi
        return PhiSMC(
            name, design_building.base_mass_kg, design_building.restoring_stiffness_N_per_m, design.p1_per_s, phi, design.delta
        )
    p_row = _surface(design.surface, design_building)
    model = state_space(design_building)
    mask = _measured_mask(design.measured, design_building.n_stories) if isinstance(design, StaticOutputDesign) else None
    return StateFeedbackSMC(name, model, p_row, design.delta, design.alpha_star, mask)


def _build_actuator_aware(
    name: str, design: StateFeedbackActuatorDesign | OutputActuatorDesign, design_building: BuildingConfig,
    actuator: ActuatorModel,
) -> Controller:
    eta = actuator.bandwidth_rad_s if design.reaching_rate_per_s is None else design.reaching_rate_per_s
    if isinstance(design, OutputActuatorDesign):
        delta = design.delta + robust_sliding_margin(design_building.base_mass_kg, actuator, design.actuator_uncertainty)
        return ActuatorOutputSMC(
            name, design_building.base_mass_kg, design_building.restoring_stiffness_N_per_m, design.p1_per_s, design.phi,
            delta, actuator, eta,
        )
    model = augmented_model(state_space(design_building), actuator)
    q = design.q
    q_state = q_diagonal_from_groups(design_building.n_stories, q.drifts, q.base_displacement, q.velocities)
    return ActuatorStateFeedbackSMC(name, model, actuator_lqr_surface(model, q_state, q.force), eta)
