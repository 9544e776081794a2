"""``rig.truth``: the virtual rig's own true building and bearing, where they are not the design.

A real rig is not the model its controller was designed on: the bearing's friction varies
with pressure, temperature and wear, and stiffnesses are identified with error (SPEC 7c).
``rig.truth`` gives the virtual rig its own values. It has two subsections shaped like the
profile's top-level ``structure`` and ``bearing`` sections, and ``actuator`` with the control
actuator's hydraulics (:class:`ActuatorTruth`, over ``rig.actuator.hydraulics``); every field
is optional and overrides the believed value for the rig only::

    rig:
      truth:
        bearing: {mu_max: 0.075}
        structure: {story_stiffness_N_per_m: [0.6e6, 2.1e6, 1.5e6]}

Who sees which values:

- the truth (the merge of the top-level sections and ``rig.truth``): the virtual rig's plant
  (``harness dry-run``, ``harness rig``), the offline rig twin (``harness simulate
  --rig-effects``), and the passive reference each of them is compared with, because a
  passive test on the same rig is what a lab compares its controlled test with: a reduction
  then measures the controller on that rig, not the model's error;
- the design (the top-level sections alone): the controller and its design model, the
  friction estimator, the safety supervisor, the ideal simulation (``harness simulate``
  without ``--rig-effects``), and the carried weight ``total_weight_N`` of a run's
  ``metadata.json`` that forces are reported against (the lab's own figure).

Quantities derived from the building follow the true building: the carried weight in the
bearing's friction (Eq. 3), and stiffness-proportional damping (``first_mode_damping_ratio``)
from the true stiffness. A truth that gives one of ``story_damping_Ns_per_m`` and
``first_mode_damping_ratio`` replaces the design's damping, whichever of the two the design
gives. The true building must have as many stories as the design.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from harness.errors import ProfileError
from harness.hydraulics.config import HydraulicActuatorConfig
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig, fixed_base_modes
from harness.rig.config import ActuatorTruth, BearingTruth, StructureTruth, TruthConfig

#: Key path of the section in a profile, for messages.
TRUTH_KEY = "rig.truth"
#: Damping is given one way or the other (BuildingConfig): a truth giving either replaces both.
_DAMPING_KEYS = ("story_damping_Ns_per_m", "first_mode_damping_ratio")
#: Fields that describe the values rather than being one (never a difference).
_NOT_PHYSICS = ("assumptions",)


def true_hydraulics(believed: HydraulicActuatorConfig, truth: ActuatorTruth | None) -> HydraulicActuatorConfig:
    """The control actuator's true hydraulics: ``rig.actuator.hydraulics`` with ``truth``'s fields replaced.

    Raises
    ------
    ProfileError
        At ``rig.truth.actuator`` when the merge is not a valid actuator.
    """
    if truth is None:
        return believed
    changes = given(truth)
    bandwidth_hz = changes.pop("force_loop_bandwidth_hz", believed.force_loop_bandwidth_hz)  # the loop's; the rest the cylinder's
    feedforward_gain = changes.pop("feedforward_gain", believed.feedforward.gain)
    try:
        return dataclasses.replace(believed, force_loop_bandwidth_hz=bandwidth_hz,
                                   feedforward=dataclasses.replace(believed.feedforward, gain=feedforward_gain),
                                   cylinder=dataclasses.replace(believed.cylinder, **changes))
    except ValueError as err:
        raise ProfileError(str(err), None, f"{TRUTH_KEY}.actuator") from err


def _believed_value(believed: HydraulicActuatorConfig, key: str) -> Any:
    if key == "feedforward_gain":
        return believed.feedforward.gain
    return getattr(believed, key) if key == "force_loop_bandwidth_hz" else getattr(believed.cylinder, key)


def given(override: StructureTruth | BearingTruth | ActuatorTruth) -> dict[str, Any]:
    """The fields an override section sets (name -> value), in declaration order."""
    return {f.name: getattr(override, f.name) for f in dataclasses.fields(override) if getattr(override, f.name) is not None}


def true_building(design: BuildingConfig, truth: StructureTruth) -> BuildingConfig:
    """The rig's true building: the design with ``truth``'s fields replaced.

    Raises
    ------
    ProfileError
        At ``rig.truth.structure`` (no source: the loader adds it) when the merge is not a
        valid building, with the message the top-level section would give, or when it has
        another number of stories than the design.
    """
    changes = given(truth)
    if any(key in changes for key in _DAMPING_KEYS):
        changes = {key: None for key in _DAMPING_KEYS} | changes
    key_path = f"{TRUTH_KEY}.structure"
    try:
        building = dataclasses.replace(design, **changes)
    except ValueError as err:
        raise ProfileError(str(err), None, key_path) from err
    if building.n_stories != design.n_stories:
        raise ProfileError(
            f"the true building has {building.n_stories} stories, expected the design's {design.n_stories} "
            "(the controller, the sensors and the protocol are the design's)", None, key_path,
        )
    return building


def true_bearing(design: BearingConfig, truth: BearingTruth) -> BearingConfig:
    """The rig's true bearing: the design with ``truth``'s fields replaced.

    Raises
    ------
    ProfileError
        At ``rig.truth.bearing`` when the merge is not a valid bearing (the top-level message).
    """
    try:
        return dataclasses.replace(design, **given(truth))
    except ValueError as err:
        raise ProfileError(str(err), None, f"{TRUTH_KEY}.bearing") from err


@dataclass(frozen=True)
class TruthDifference:
    """One value the rig's truth gives that differs from the design.

    Attributes
    ----------
    key : str
        ``section.field``, e.g. ``bearing.mu_max``.
    true_value, design_value : float or tuple of float
        SI, in the unit the key names. The design's damping is its resolved value when the
        design gives damping the other way.
    """

    key: str
    true_value: Any
    design_value: Any

    def text(self) -> str:
        """``bearing.mu_max 0.075 (design 0.06)``."""
        return f"{self.key} {_value_text(self.true_value)} (design {_value_text(self.design_value)})"

    def as_dict(self) -> dict[str, Any]:
        """For ``metadata.json``: key, true and design values (lists for tuples)."""
        return {"key": self.key, "true": _plain(self.true_value), "design": _plain(self.design_value)}


@dataclass(frozen=True)
class RigTruth:
    """The rig's true building and bearing, and how they differ from the design.

    Attributes
    ----------
    building, bearing : BuildingConfig, BearingConfig
        What the virtual rig's plant is built from.
    differences : tuple of TruthDifference
        Empty when the rig is the design.
    """

    building: BuildingConfig
    bearing: BearingConfig
    differences: tuple[TruthDifference, ...]


def resolve_truth(
    building: BuildingConfig, bearing: BearingConfig, truth: TruthConfig | None,
    hydraulics: HydraulicActuatorConfig | None = None,
) -> RigTruth:
    """The rig's truth from the design's ``structure`` and ``bearing`` and the ``rig.truth`` section.

    Parameters
    ----------
    building, bearing : BuildingConfig, BearingConfig
        The design: the profile's top-level sections.
    truth : TruthConfig or None
        ``rig.truth`` (None: no overrides).
    hydraulics : HydraulicActuatorConfig, optional
        ``rig.actuator.hydraulics``, what the lab believes of its actuator: the actuator's
        differences are listed against it.

    Raises
    ------
    ProfileError
        When a merged section is invalid (see :func:`true_building`, :func:`true_bearing`).
    """
    if truth is None:
        return RigTruth(building, bearing, ())
    true_b, true_f = true_building(building, truth.structure), true_bearing(bearing, truth.bearing)
    differences = [
        TruthDifference(f"structure.{key}", value, _design_value(building, key))
        for key, value in given(truth.structure).items() if key not in _NOT_PHYSICS
    ] + [TruthDifference(f"bearing.{key}", value, getattr(bearing, key)) for key, value in given(truth.bearing).items()]
    if hydraulics is not None:
        differences += [TruthDifference(f"actuator.{key}", value, _believed_value(hydraulics, key))
                        for key, value in given(truth.actuator).items()]
    return RigTruth(true_b, true_f, tuple(d for d in differences if not _same(d.true_value, d.design_value)))


def truth_summary(differences: Sequence[TruthDifference]) -> str:
    """One line for the console, the report and the outcome; "" when the rig is the design.

    e.g. ``rig truth differs from design: bearing.mu_max 0.075 (design 0.06)``.
    """
    if not differences:
        return ""
    return "rig truth differs from design: " + "; ".join(d.text() for d in differences)


def _design_value(building: BuildingConfig, key: str) -> Any:
    """The design's value of a structure key; damping resolved when the design gives it the other way."""
    value = getattr(building, key)
    if value is not None or key not in _DAMPING_KEYS:
        return value
    if key == "story_damping_Ns_per_m":
        return tuple(float(c) for c in building.story_damping())
    return float(fixed_base_modes(building)[1][0])


def _same(a: Any, b: Any) -> bool:
    if isinstance(a, tuple) and isinstance(b, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-12, abs_tol=0.0)
    return bool(a == b)


def _value_text(value: Any) -> str:
    if isinstance(value, (tuple, list)):
        return "[" + ", ".join(_value_text(v) for v in value) + "]"
    return f"{value:.6g}" if isinstance(value, float) else str(value)


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


#: The ``metadata.json`` key of a run whose rig's truth differs from the design.
METADATA_KEY = "rig_truth"


def truth_metadata(differences: Sequence[TruthDifference]) -> dict[str, Any]:
    """``{"rig_truth": {"summary": ..., "differences": [...]}}`` for ``metadata.json``; ``{}`` when the rig is the design."""
    if not differences:
        return {}
    return {METADATA_KEY: {"summary": truth_summary(differences), "differences": [d.as_dict() for d in differences]}}
