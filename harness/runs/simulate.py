"""``harness simulate``: passive and controlled cases of one profile and record, side by side.

From the profile with the command line's options folded in (:mod:`harness.runs.options`):
the table motion, the controller with its design model, the sampling settings, and the
results in the JSON layout of the issue tracker (SI).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from harness.control.factory import (
    build_controller_for_rig,
    designed_with_actuator,
    make_compensator,
    make_controller,
    make_friction_estimator,
)
from harness.errors import ProfileError
from harness.model.plant import Plant, TableMotion
from harness.motions import GroundMotion
from harness.motions.summary import motion_facts
from harness.profile import Profile
from harness.recording import strict_json
from harness.report.force_tracking import ForceTracking, run_force_tracking
from harness.rig.truth import TruthDifference, truth_metadata
from harness.runs.options import NO_CONTROLLER, StudyOptions, prepare_motion, resolve_profile
from harness.signals.columns import FORCE_COMMAND, FORCE_RAW
from harness.simulation.case import CaseResult, SamplingSettings, run_case


@dataclass
class StudyResult:
    """Both cases of a study and what they were run with."""

    profile: Profile
    motion: GroundMotion
    controller_name: str
    settings: SamplingSettings
    design_stiffness_scale: float
    rig_effects: bool = False
    cases: dict[str, CaseResult] = field(default_factory=dict)

    def truth_differences(self) -> tuple[TruthDifference, ...]:
        """Where the simulated rig differs from the design: ``rig.truth``, with rig effects only (else none)."""
        return self.profile.rig_truth().differences if self.rig_effects else ()

    def to_json(self) -> dict:
        """The JSON document of ``harness simulate --json`` (SI units)."""
        motion = self.motion
        controlled = self.cases.get("controlled", self.cases["passive"])
        return {
            "profile": self.profile.name,
            "record": motion_facts(motion),
            "controller": self.controller_name,
            "sampling": {
                "rate_hz": self.settings.rate_hz,
                "transport_delay_s": self.settings.transport_delay_s,
                "friction_source": self.settings.friction_source,
                "design_stiffness_scale": self.design_stiffness_scale,
                "rig_effects": self.rig_effects,
                "compensation": controlled.extra.get("compensation", "none"),
                "controller_state": controlled.extra.get("state_source", "measured" if self.rig_effects else "model"),
            },
            "total_weight_N": self.profile.structure.total_weight_N,
            "cases": {"passive": self.cases["passive"].peaks.as_json(), "controlled": controlled.peaks.as_json()},
            **(self._tracking_json() if self.rig_effects and "controlled" in self.cases else {}),
            **truth_metadata(self.truth_differences()),
        }

    def force_tracking(self) -> dict[str, ForceTracking | None]:
        """The controlled case's force tracking (:mod:`harness.report.force_tracking`).

        Returns
        -------
        dict
            ``controller_force``: the load cell against the controller's force; ``command``:
            against the command sent. None for a case without a load cell (no rig effects).
        """
        columns = self.cases["controlled"].columns
        return {"controller_force": run_force_tracking(columns, FORCE_RAW),
                "command": run_force_tracking(columns, FORCE_COMMAND)}

    def _tracking_json(self) -> dict:
        """``force_tracking``: each :class:`ForceTracking` as a dict; ``force_tracking_rms_N``: their RMS errors (N)."""
        tracked = self.force_tracking()
        return {"force_tracking_rms_N": {name: math.nan if value is None else value.rms_error_N
                                         for name, value in tracked.items()},
                "force_tracking": {name: None if value is None else value.as_json() for name, value in tracked.items()}}

    def write_json(self, path: str | Path) -> None:
        """Write :meth:`to_json` to ``path``."""
        Path(path).write_text(strict_json.dumps(self.to_json(), indent=2) + "\n")


def sampling_settings(profile: Profile) -> SamplingSettings:
    """Controller sampling of a resolved profile."""
    control = profile.control
    return SamplingSettings(rate_hz=control.rate_hz, transport_delay_s=control.transport_delay_s,
                            friction_source=control.friction)


def _study_motion(profile: Profile, options: StudyOptions) -> tuple[GroundMotion, Profile]:
    """The table motion of a study and the profile it runs on.

    The profile's record, processed and checked against the table; or, with ``options.drive_from``,
    the table motion that run achieved (:mod:`harness.simulation.drive`), which the twin's table
    then follows exactly (a motion source).
    """
    if options.drive_from is None:
        return prepare_motion(profile), profile
    from harness.simulation.drive import DriveFromError, achieved_motion, driven_profile

    if not options.rig_effects:
        raise DriveFromError(f"--drive-from {options.drive_from} drives the rig twin with the table motion a run "
                             "achieved, expected --rig-effects with it (the ideal simulation has no rig)")
    motion = achieved_motion(options.drive_from, profile.control.rate_hz, options.duration_s, profile.name)
    return motion, driven_profile(profile)


def run_study(profile: Profile, options: StudyOptions, progress: Callable[[str, float], None] | None = None) -> StudyResult:
    """Simulate the passive case and (unless the controller is 'none') the controlled case.

    The ideal simulation is the design's world: plant and controller both use ``structure``
    and ``bearing``, and the controller's force acts as it is (no actuator, so no compensation:
    ``control.compensation`` shapes the rig's actuator command, with ``--rig-effects``). With
    ``options.rig_effects`` both cases run on the virtual rig's truth (``rig.truth``,
    :mod:`harness.rig.truth`), while the controller and the friction estimator keep the design;
    the controlled case's command goes through the profile's compensation.

    Parameters
    ----------
    profile : Profile
    options : StudyOptions
    progress : callable, optional
        ``progress(case_name, fraction)``.

    Raises
    ------
    DriveFromError
        ``options.drive_from`` names a folder that cannot drive the twin (with the reason and what
        was expected), or is given without ``options.rig_effects``.
    """
    profile = resolve_profile(profile, options)
    motion, profile = _study_motion(profile, options)
    settings = sampling_settings(profile)
    scale = profile.control.design_stiffness_scale
    name = NO_CONTROLLER if options.controller == NO_CONTROLLER else profile.control.controller
    if name != NO_CONTROLLER and designed_with_actuator(profile, name) and not options.rig_effects:
        raise ProfileError(
            f"controller {name!r} is designed with the rig's actuator (its force a state, read from the load cell); "
            "the ideal simulation has no actuator: run it with --rig-effects",
            profile.source_path, "control.controller",
        )
    controller = None if name == NO_CONTROLLER else make_controller(profile, name, scale)
    table = TableMotion.from_motion(motion)
    # With rig effects the passive case runs on the rig's truth (rig.truth), like the twin it is compared with.
    truth = profile.rig_truth() if options.rig_effects else None
    building, bearing = (truth.building, truth.bearing) if truth is not None else (profile.structure, profile.bearing)
    plant = Plant(building, bearing, table, rtol=profile.simulation.rtol)
    result = StudyResult(profile, motion, name, settings, scale, options.rig_effects)
    duration = motion.duration_s

    def reporter(case: str):
        return None if progress is None else (lambda fraction: progress(case, fraction))

    result.cases["passive"] = run_case("passive", plant, duration, settings, progress=reporter("passive"))
    if controller is not None and options.rig_effects:
        from harness.simulation.twin import run_rig_twin

        # The same design as the ideal case. A full-state design reads the twin's true plant state:
        # an offline design study (labelled in the case's extra["state_source"]); a rig refuses it.
        offline = controller.needs_full_state
        rig_controller = make_controller(profile, name, scale) if offline else build_controller_for_rig(profile, name, scale)
        result.cases["controlled"] = run_rig_twin(
            profile, motion, settings.rate_hz, rig_controller, asynchronous_delay_s=settings.transport_delay_s,
            offline_true_state=offline, compensator=make_compensator(profile, controller=name),
        )
    elif controller is not None:
        estimator = make_friction_estimator(profile)
        result.cases["controlled"] = run_case(
            "controlled", plant, duration, settings, controller, estimator, progress=reporter("controlled")
        )
    return result
