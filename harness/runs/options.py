"""The command line's options folded into the profile: the one place they are resolved.

:class:`StudyOptions` holds what a command's options override (the record, its level and
length, the controller, the rate, ...); :func:`resolve_profile` folds them into the profile,
so everything downstream (the simulator, the loop, the virtual rig in its own process) reads
one frozen profile and nothing looks at the options again; :func:`prepare_motion` loads the
resolved record and checks it against the table. Every command that runs something uses them:
``harness simulate``, ``dry-run``, ``run``, ``rig``, ``identify``, ``sweep``.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from harness.control.factory import require_design
from harness.errors import ProfileError
from harness.motions import GroundMotion, check_table_limits, load_motion
from harness.profile import Profile

#: The controller option that runs the passive case alone.
NO_CONTROLLER = "none"


@dataclass(frozen=True)
class StudyOptions:
    """Command-line overrides of a profile; ``None`` keeps the profile's value."""

    record: str | None = None
    records_dir: str | None = None
    pga_g: float | None = None
    time_scale: float | None = None
    duration_s: float | None = None
    controller: str | None = None
    rate_hz: float | None = None
    friction: str | None = None
    transport_delay_s: float | None = None
    design_stiffness_scale: float | None = None
    rig_effects: bool = False
    #: A run folder whose achieved table motion drives the rig twin (``--drive-from``) in place of the record.
    drive_from: str | None = None


def resolve_profile(profile: Profile, options: StudyOptions) -> Profile:
    """The profile with the command line's options folded in: the one place they are resolved.

    Every option that has a profile key becomes that key's value, so everything downstream
    (the simulator, the loop, the virtual rig in its own process) reads one frozen profile
    and nothing looks at the options again:

    - ``record``, ``records_dir`` (resolved with ``$HARNESS_RECORDS_DIR`` and made absolute,
      like a record given as a relative path), ``pga_g``, ``time_scale``, ``duration_s``
      go to the ``record`` section;
    - ``controller`` (unless ``none``), ``friction``, ``transport_delay_s`` and
      ``design_stiffness_scale`` to ``control``;
    - ``rate_hz`` to ``control.rate_hz``, the one rate: the loop ticks at it and the profile
      hands it to the CAN section (the command's rate, and the sensors' unless ``can.sensor_rate_hz``
      sets a rate of their own).

    Parameters
    ----------
    profile : Profile
    options : StudyOptions

    Returns
    -------
    Profile
        Validated like a loaded profile (its ``__post_init__`` checks run again).
    """
    from harness.motions import records_dir_from
    from harness.motions.loading import resolve_record_name

    record = profile.record
    name = options.record if options.record is not None else record.name
    name = resolve_record_name(name, Path.cwd() if options.record is not None else profile.base_dir)
    records_dir = records_dir_from(options.records_dir, record.records_dir, base_dir=profile.base_dir)
    record = dataclasses.replace(
        record, name=name, records_dir=None if records_dir is None else str(Path(records_dir).resolve()),
        **_given(pga_g=options.pga_g, time_scale=options.time_scale, duration_s=options.duration_s),
    )
    if options.controller not in (None, NO_CONTROLLER):
        require_design(profile, options.controller)
    control = dataclasses.replace(profile.control, **_given(
        controller=None if options.controller == NO_CONTROLLER else options.controller,
        rate_hz=options.rate_hz, friction=options.friction, transport_delay_s=options.transport_delay_s,
        design_stiffness_scale=options.design_stiffness_scale,
    ))
    try:
        return dataclasses.replace(profile, record=record, control=control)
    except ValueError as err:  # a combination the profile refuses, as it would from the file
        raise ProfileError(f"{err} (with the command line's options)", profile.source_path) from err


def _given(**values) -> dict:
    """The items whose value is not None."""
    return {key: value for key, value in values.items() if value is not None}


def prepare_motion(profile: Profile, options: StudyOptions | None = None) -> GroundMotion:
    """The processed table motion of ``profile`` (with ``options`` folded in), checked against the table."""
    if options is not None:
        profile = resolve_profile(profile, options)
    record = profile.record
    motion = load_motion(record, base_dir=profile.base_dir, records_dir_flag=record.records_dir)
    if profile.table is not None:
        check_table_limits(motion, profile.table)
    return motion
