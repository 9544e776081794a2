"""Controller designs as profile entries, and building a controller from one.

A profile's ``control.designs`` maps names (``FSF-I``, ``OF-I``, ``phi``) to one of
the design dataclasses below, told apart by ``kind``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from harness.control.controllers import Controller, PhiSMC, StateFeedbackSMC
from harness.control.surfaces import lqr_surface, pole_surface, q_diagonal_from_groups
from harness.errors import ModelError
from harness.model.building import BuildingConfig, state_space
from harness.schema import quantity

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


ControllerDesign = FullStateDesign | StaticOutputDesign | SimpleOutputDesign | PhiDesign


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


def build_controller(name: str, design: ControllerDesign, design_building: BuildingConfig) -> Controller:
    """Make the controller ``name`` from its design, using ``design_building`` as the controller's model.

    ``design_building`` may differ from the plant's building (e.g. stiffness off by
    -30 % for the robustness study of SPEC 6a).
    """
    if isinstance(design, (SimpleOutputDesign, PhiDesign)):
        phi = 1.0 if isinstance(design, SimpleOutputDesign) else design.phi
        return PhiSMC(
            name, design_building.base_mass_kg, design_building.restoring_stiffness_N_per_m, design.p1_per_s, phi, design.delta
        )
    p_row = _surface(design.surface, design_building)
    model = state_space(design_building)
    mask = _measured_mask(design.measured, design_building.n_stories) if isinstance(design, StaticOutputDesign) else None
    return StateFeedbackSMC(name, model, p_row, design.delta, design.alpha_star, mask)
