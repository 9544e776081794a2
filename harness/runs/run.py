"""``harness run``: a control session against the real rig, from the resolved profile to its result.

The command (:mod:`harness.commands.run`) parses the options, asks the operator and prints;
this module decides what the run is and runs it:

- the run's table link (``table.link``): :func:`prepare_rig_run` gives a
  :class:`~harness.loop.table_link.CanTableLink` when the harness starts and stops the table
  over CAN, none when the table is started at its own console (:data:`NO_TABLE_LINK` says
  what that means for the run);
- arming: the question the operator answers before the actuator is armed
  (:func:`arm_question`), and which answers arm it (:func:`answer_arms`);
- the session: its settings (:func:`session_settings`; the table check only where record
  time is the table's) and the session itself (:func:`run_on_rig`), the same as a dry run's
  without the virtual rig.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from harness.canbus.config import CanConfig
from harness.loop.preflight import HostTiming
from harness.loop.table_link import CanTableLink
from harness.motions import GroundMotion
from harness.motions.summary import motion_facts
from harness.profile import Profile
from harness.runs.options import prepare_motion
from harness.runs.session import SessionResult, SessionSettings, run_session

#: What the run does with the table when ``table.link`` is ``can`` (said before arming).
TABLE_LINK_CAN = (
    "table: RIG_CONTROL start at RUNNING, stop at the end and on a trip; record time counts from the table "
    "controller's RIG_STATUS table_running (table.link: can)"
)
#: What ``table.link: none`` means for a run (said before arming).
NO_TABLE_LINK = (
    "table.link is none: the table controller is not on the CAN bus. The harness will not start or stop the "
    "table: start it yourself once the run is RUNNING; record time follows the harness's clock, not the table's; "
    "a trip cannot stop the table (stop_table trip actions are skipped), stop it at its own console."
)
#: Why a run without a table link has no table check (metadata.json, the outcome).
NO_TABLE_CHECK = "table.link is none: record time follows the harness's clock, not the table's"
#: Answers to :func:`arm_question` that arm the actuator (case and surrounding space ignored); anything else does not.
ARMING_ANSWERS = ("y", "yes")


@dataclass(frozen=True)
class RigRun:
    """A run of the real rig, resolved before anything is opened.

    Attributes
    ----------
    profile : Profile
        With the command line's options folded in (:func:`harness.runs.options.resolve_profile`).
    motion : GroundMotion
        The record as the table will play it, checked against the table.
    can : CanConfig
        The profile's can section with the command line's interface and channel.
    table_link : CanTableLink or None
        The table over CAN (``table.link: can``), or None (``none``: the table is started by hand).
    """

    profile: Profile
    motion: GroundMotion
    can: CanConfig
    table_link: CanTableLink | None

    @property
    def table_link_note(self) -> str:
        """What the run does with the table: :data:`TABLE_LINK_CAN` or :data:`NO_TABLE_LINK`."""
        return TABLE_LINK_CAN if self.table_link is not None else NO_TABLE_LINK


def prepare_rig_run(profile: Profile, interface: str | None = None, channel: str | None = None) -> RigRun:
    """The record, the bus and the table link of a run of the resolved ``profile``.

    Parameters
    ----------
    profile : Profile
        Resolved (the command line's options folded in).
    interface, channel : str, optional
        The command line's bus; None keeps the profile's.

    Raises
    ------
    RecordError, ProfileError
        The record cannot be loaded, or needs more than the table has.
    """
    motion = prepare_motion(profile)
    can = profile.can_settings(interface, channel)
    linked = profile.table is None or profile.table.link == "can"
    return RigRun(profile, motion, can, CanTableLink(lockstep=False) if linked else None)


def arm_question(run: RigRun, reset_drive: bool = False) -> str:
    """The question asked before arming: bus, controller, the record as the table will play it, the limits.

    Plain text (the caller escapes it for rich: "[y/N]" is not markup).
    """
    profile, motion = run.profile, run.motion
    verb = "Reset the drive's latched fault and arm" if reset_drive else "Arm"
    return (
        f"{verb} the actuator on {run.can.interface}:{run.can.channel} with {profile.control.controller}: "
        f"record {motion.name}, PGA {motion.pga_g:.3f} g, time scale {motion.time_scale:g}, {motion.duration_s:.1f} s "
        f"(max force {profile.safety.force.max_force_N / 1e3:g} kN, "
        f"hard stroke {profile.safety.stroke.hard_limit_m * 1e3:g} mm)? [y/N] "
    )


def answer_arms(answer: str) -> bool:
    """True if the operator's answer to :func:`arm_question` arms the actuator (``y`` or ``yes``)."""
    return answer.strip().lower() in ARMING_ANSWERS


def session_settings(run: RigRun, log_dir: Path, *, show_console: bool = True, reset_drive: bool = False) -> SessionSettings:
    """The session of ``run``: its record in the metadata, and the table check where record time is the table's."""
    linked = run.table_link is not None
    return SessionSettings(
        kind="run", can=run.can, duration_s=run.motion.duration_s, log_dir=log_dir, show_console=show_console,
        metadata={"record": motion_facts(run.motion), "table_link": "can" if linked else "none"},
        # the table check needs record time to be the table's: only where the harness starts the table
        table_record=run.motion if linked else None,
        table_check_off=NO_TABLE_CHECK,
        reset_drive=reset_drive,
    )


def run_on_rig(
    run: RigRun, settings: SessionSettings, *, console=None, on_host_timing: Callable[[HostTiming], None] | None = None,
) -> SessionResult:
    """Run the control session of ``run`` on its bus, with its table link (the same loop as a dry run's)."""
    return run_session(run.profile, settings, console=console, on_host_timing=on_host_timing, table_link=run.table_link)
