"""Controllers built from a profile's named designs: for simulation, and for a rig.

Each builder reads the sections it needs (:class:`~harness.control.sections.ControlSections`:
a :class:`~harness.profile.Profile` is one), so the control package does not import the profile.

One place builds a controller and its friction estimator, so ``harness simulate``, the simulated twin, a dry run
and a run on the real rig all get the same design from the same profile.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from harness.control.actuator_aware import (
    ActuatorModel,
    ActuatorOutputSMC,
    ActuatorStateFeedbackSMC,
    actuator_lqr_surface,
    augmented_model,
    robust_sliding_margin,
)
from harness.control.adaptive_compensation import AdaptiveCompensator
from harness.control.compensation import Compensator, NoCompensation
from harness.control.controllers import Controller, PhiSMC, StateFeedbackSMC
from harness.control.designs import (
    ControllerDesign,
    OutputActuatorDesign,
    PhiDesign,
    SimpleOutputDesign,
    StateFeedbackActuatorDesign,
    StaticOutputDesign,
    SurfaceConfig,
)
from harness.control.estimator import FrictionEstimator
from harness.control.estimator_margin import estimator_yield_displacement_m
from harness.control.model_compensation import ModelCompensator
from harness.control.sections import ControlSections
from harness.control.surfaces import lqr_surface, pole_surface, q_diagonal_from_groups
from harness.errors import ModelError, ProfileError
from harness.model.building import BuildingConfig, state_space


def make_friction_estimator(profile: ControlSections) -> FrictionEstimator:
    """The friction estimator of ``profile``'s controller (SPEC 3, Eq. 3-5).

    The design bearing (``bearing``, never ``rig.truth``) with the estimator's own yield
    displacement (``control.estimator.yield_displacement_m``, the bearing's ``D_y`` if none;
    harness/control/estimator_margin.py derives the shipped value), carrying ``mbar g``.
    """
    bearing = dataclasses.replace(profile.bearing, yield_displacement_m=estimator_yield_displacement_m(profile))
    return FrictionEstimator(bearing, profile.structure.total_weight_N)


def require_design(profile: ControlSections, name: str) -> None:
    """Refuse a controller name that is not a design of ``profile``.

    Raises
    ------
    ProfileError
        Naming the designs the profile has.
    """
    designs = profile.control.designs
    if name not in designs:
        raise ProfileError(
            f"unknown controller {name!r}; this profile has {', '.join(designs)} (or 'none' for passive only)",
            profile.source_path,
            "control.designs",
        )


def designed_with_actuator(profile: ControlSections, name: str) -> bool:
    """The design ``name`` is actuator-aware: it needs a plant with the actuator and its load cell."""
    return isinstance(profile.control.designs.get(name), (StateFeedbackActuatorDesign, OutputActuatorDesign))


def make_controller(profile: ControlSections, name: str, design_stiffness_scale: float = 1.0) -> Controller:
    """Build the named design of ``profile`` on its (possibly mis-scaled) design model.

    Parameters
    ----------
    profile : ControlSections
    name : str
        A key of ``control.designs``.
    design_stiffness_scale : float
        The design model's story stiffnesses are the profile's times this (robustness studies).

    Raises
    ------
    ProfileError
        If the profile has no such design, or an actuator-aware design's ``rig.actuator``
        is not a model it can be designed on.
    """
    designs = profile.control.designs
    require_design(profile, name)
    design_building = profile.structure
    if design_stiffness_scale != 1.0:
        design_building = design_building.with_stiffness_scale(design_stiffness_scale)
    design = designs[name]
    if not designed_with_actuator(profile, name):
        return build_controller(name, design, design_building)
    try:
        actuator = ActuatorModel.from_rig_actuator(profile.rig.actuator)
    except ModelError as err:
        raise ProfileError(str(err), profile.source_path, "rig.actuator.model") from err
    return build_controller(name, design, design_building, actuator)


def build_controller_for_rig(profile: ControlSections, name: str, design_stiffness_scale: float = 1.0) -> Controller:
    """The named design (designed on story stiffnesses scaled by ``design_stiffness_scale``),
    refused if it needs states a rig does not measure.

    Raises
    ------
    ProfileError
        For a full-state design: a rig measures only x_0, xdot_0, y_b and ydot_b.
    """
    controller = make_controller(profile, name, design_stiffness_scale)
    if controller.needs_full_state:
        raise ProfileError(
            f"controller {name!r} needs the full state Z; a rig measures only x_0, xdot_0, y_b, ydot_b. "
            "Use a phi, simple_output or output_actuator design on the table (full-state designs are for harness simulate)",
            profile.source_path, "control.controller",
        )
    return controller


def make_compensator(profile: ControlSections, method: str | None = None, controller: str | None = None) -> Compensator:
    """The force-tracking compensator ``method`` (default ``control.compensation``) of ``profile``.

    The adaptive compensator fits its coefficients online within ``control.compensator.adaptive``'s
    bounds, its window sized at ``control.rate_hz``. The model-based compensator takes ``k_h`` and
    ``w_f`` from ``rig.actuator`` (or its identified overlay) through :class:`ActuatorModel`, as
    the actuator-aware designs do.

    Parameters
    ----------
    profile : ControlSections
    method : str, optional
        ``none``, ``model`` or ``adaptive``; default ``control.compensation``.
    controller : str, optional
        The design the compensator will serve: an actuator-aware design already inverts the
        actuator in its own command (A7, A12 of harness/control/actuator_aware.py), so a
        compensation on top of it would cancel the velocity feedback twice and is refused.

    Raises
    ------
    ProfileError
        If ``controller`` is actuator-aware and the method is not ``none``; if ``rig.actuator``
        is not a model the compensator can invert, or if the load-cell
        correction's bound is not below ``safety.force.tracking_tolerance_N`` (the tracking check
        must still see an actuator the correction cannot pull back: docs/SAFETY.md,
        "Force-tracking compensation").
    """
    method = profile.control.compensation if method is None else method
    if method == "none":
        return NoCompensation()
    if controller is not None and designed_with_actuator(profile, controller):
        raise ProfileError(
            f"controller {controller!r} is designed with the actuator: its command already carries the inverse and the flow "
            f"term, and compensation {method!r} would add them again; use control.compensation=none with it",
            profile.source_path, "control.compensation",
        )
    if method == "adaptive":
        adaptive = profile.control.compensator.adaptive
        start = (1.0, 0.0, 0.0, 0.0)
        if adaptive.start == "model":
            model = _actuator_model(profile)
            start = (1.0, 1.0 / model.bandwidth_rad_s, model.loop_damping_Ns_per_m, 0.0)
        learn_above_m_s = profile.bearing.yield_displacement_m / adaptive.filter_time_constant_s  # (C8)
        try:
            return AdaptiveCompensator(adaptive, 1.0 / profile.control.rate_hz, start, learn_above_m_s)
        except ModelError as err:
            raise ProfileError(str(err), profile.source_path, "control.compensator.adaptive.start") from err
    if method != "model":
        raise ProfileError(f"unknown compensation {method!r}; expected none, model or adaptive", profile.source_path,
                           "control.compensation")
    settings = profile.control.compensator.model
    tolerance_N = profile.safety.force.tracking_tolerance_N
    if not settings.correction_limit_N < tolerance_N:
        raise ProfileError(
            f"found {settings.correction_limit_N:g} N, expected below safety.force.tracking_tolerance_N = {tolerance_N:g} N",
            profile.source_path, "control.compensator.model.correction_limit_N",
        )
    try:
        return ModelCompensator(_actuator_model(profile), settings)
    except ModelError as err:
        raise ProfileError(str(err), profile.source_path, "control.compensator.model") from err


def _actuator_model(profile: ControlSections) -> ActuatorModel:
    """``k_h`` and ``w_f`` of ``rig.actuator``; ProfileError for a model (A1) does not describe."""
    try:
        return ActuatorModel.from_rig_actuator(profile.rig.actuator)
    except ModelError as err:
        raise ProfileError(str(err), profile.source_path, "rig.actuator.model") from err


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
