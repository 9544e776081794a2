"""One control session on a bus: what ``harness dry-run`` and ``harness run`` share.

Opens the harness side of the CAN link (the bus load and protocol version are checked
before anything is opened), builds the controller, the friction estimator and the
safety supervisor from the profile, creates the run folder and taps the raw CAN traffic
into it, runs the loop under the live console, and closes everything whatever happens:
the last frame the harness sends is always zero force with the drive disabled.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

from drivers.link import HarnessLink
from drivers.reader import CONTROL_MEASUREMENTS
from harness import exit_codes
from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness
from harness.console.live import LiveConsole, run_title
from harness.control.compensation import NoCompensation
from harness.control.controllers import Controller
from harness.control.factory import build_controller_for_rig, make_compensator, make_friction_estimator
from harness.errors import ProfileError, StoppedByOperator
from harness.loop.operator import stop_if_requested
from harness.loop.preflight import HostTiming, HostTimingRefused, measure_host_timing
from harness.loop.runner import ArmTimeout, ControlLoop, LoopResult
from harness.loop.status import LoopStatus
from harness.loop.table_link import CanTableLink
from harness.loop.tick import ControlTick
from harness.loop.tick_log import TICK_COLUMNS, TickLog
from harness.model.warmup import warm_up
from harness.profile import Profile
from harness.realtime.host import Scheduling, request_fifo, restore_scheduling
from harness.recording import RunFolder
from harness.recording.layout import Outcome, RunKind
from harness.recording.replayable import REPLAY_VERSION
from harness.recording.runfolder import check_log_dir
from harness.recording.space import RunSize, check_log_space, run_size
from harness.runs.loop_rate import check_loop_rate
from harness.safety.config import TRIP_CLASSES
from harness.safety.supervisor import Supervisor
from harness.safety.table_record import NO_RECORD
from harness.safety.weakening import summary
from harness.signals.columns import CONTROL_ROW, PROTOCOL_STORIES

if TYPE_CHECKING:
    from harness.motions import GroundMotion

OUTCOME_EXIT = {"completed": exit_codes.OK, "tripped": exit_codes.TRIPPED, "stopped": exit_codes.STOPPED}


@dataclass
class SessionSettings:
    """How one session runs, besides the resolved profile (which gives the rate and the controller).

    Attributes
    ----------
    can : CanConfig
        The profile's can section with the command line's interface and channel.
    duration_s : float
        Record time the run covers (s).
    """

    kind: RunKind
    can: CanConfig
    duration_s: float
    log_dir: Path
    lockstep: bool = False
    show_console: bool = True
    metadata: dict = field(default_factory=dict)
    #: Yellow lines of the live console for the whole run (e.g. where the rig's truth differs from the design).
    notes: tuple[str, ...] = ()
    #: The record the table was told to play, compared online with the table's motion (harness/safety/table_record.py);
    #: only where the table starts with the run (RIG_CONTROL), so that record time is the table's. None: no check.
    table_record: GroundMotion | None = None
    #: Why there is no table check, when ``table_record`` is None (for the outcome and metadata.json).
    table_check_off: str = NO_RECORD
    #: ``--reset-drive``: reset the drive's latched fault before arming (:mod:`harness.runs.drive_reset`).
    reset_drive: bool = False
    #: On a ``seqpacket`` channel, the only processes admitted at the other end (the rig process a dry run
    #: started); empty: any process of this user (or of ``can.peer_group``).
    peer_pids: tuple[int, ...] = ()


@dataclass
class SessionResult:
    """What a session produced."""

    outcome: Outcome
    trip_reason: str
    run_path: Path
    loop: LoopResult
    bus: dict = field(default_factory=dict)
    #: What the recorder lost and why ("" when the run folder holds the whole record).
    record_problem: str = ""

    @property
    def record_complete(self) -> bool:
        """True if every row, frame and event reached the run folder."""
        return not self.record_problem

    @property
    def exit_code(self) -> int:
        """The command's exit status for this outcome.

        A run that lost any of its record exits 3 like a trip, whether it completed, was stopped
        by its own safe stop (``record_lost``) or by the operator: the table moved, the rig is
        safe, and the test must be repeated to get its data (docs/SAFETY.md, "A lost record").
        """
        if not self.record_complete and self.outcome in OUTCOME_EXIT:
            return exit_codes.TRIPPED
        return OUTCOME_EXIT.get(self.outcome, exit_codes.INTERNAL_ERROR)

    def write_after_run(self, what: str, write: Callable[[], object]) -> bool:
        """Every write into the run folder after the loop goes through here: a disk error is a lost record.

        Parameters
        ----------
        what : str
            What ``write`` writes, for the outcome line (e.g. ``"target_motion.csv and the references"``).
        write : callable
            Writes it; an ``OSError`` (disk full, file-size limit, a folder gone) is caught.

        Returns
        -------
        bool
            True if written; False if not: the record is then incomplete (exit status 3, said on the
            outcome line), never a traceback.
        """
        try:
            write()
        except OSError as err:
            lost = f"{what} not written ({type(err).__name__}: {err})"
            self.record_problem = f"{self.record_problem}; {lost}" if self.record_problem else lost
            return False
        return True


def expected_run_size(profile: Profile, settings: SessionSettings) -> RunSize:
    """The most a session's run folder holds (:mod:`harness.recording.space`), from its rates and its length."""
    from harness.canbus.link import prepare

    protocol, _ = prepare(settings.can)  # the DBC, read without touching the bus
    rates = settings.can.rates_hz()
    if settings.lockstep:  # the rig answers every step with RIG_STATUS
        rates["RIG_STATUS"] = max(rates.get("RIG_STATUS", 0.0), profile.control.rate_hz)
    frames_per_s = sum(rates.values())
    data_bytes = sum(rate * protocol.messages[name].length for name, rate in rates.items() if name in protocol.messages)
    loop = profile.loop
    span_s = loop.arm_timeout_s + loop.settle_s + settings.duration_s + loop.tail_s + loop.after_s
    record = settings.table_record
    return run_size(
        len(CONTROL_ROW), profile.control.rate_hz, span_s, frames_per_s, data_bytes / frames_per_s if frames_per_s else 0.0,
        settings.can.channel, record_values=4 * len(record.t_s) if record is not None else 0,
    )


def bus_statistics(link) -> dict:
    """Frames received, rejected by kind, sent, and the bus's error counters (for metadata and benchmarks)."""
    from drivers.protocol.decoder import RxStatus

    reader, health = link.reader, link.reader.health
    counts = reader.decoder.counts
    return {
        "frames_received": reader.counters.frames,
        "rejected": {status.name.lower(): counts[status] for status in RxStatus if status is not RxStatus.OK and counts[status]},
        "frames_lost": counts[RxStatus.SKIPPED_COUNTER],
        "polls_capped": reader.counters.polls_capped,
        "foreign_commands": reader.counters.foreign_commands,
        "error_frames": health.error_frames,
        "send_failures": health.send_failures,
        **refused_peers(link.bus),
    }


def refused_peers(bus) -> dict:
    """``{"refused_peers": [why, ...], "refused_peer_count": n}`` of a bus that checks its peers (seqpacket), else {}."""
    count = getattr(bus, "refused_count", 0)
    return {"refused_peers": list(bus.refused_peers), "refused_peer_count": count} if count else {}


def _metadata(profile: Profile, settings: SessionSettings) -> dict:
    stroke, force = profile.safety.stroke, profile.safety.force
    return {
        "controller": profile.control.controller,
        "rate_hz": profile.control.rate_hz,
        "lockstep": settings.lockstep,
        "can": {
            "interface": settings.can.interface, "channel": settings.can.channel, "bitrate_bps": settings.can.bitrate_bps,
            "fd": settings.can.fd, "data_bitrate_bps": settings.can.data_bitrate_bps if settings.can.fd else None,
        },
        "total_weight_N": profile.structure.total_weight_N,
        "stroke_soft_limit_m": stroke.soft_limit_m,
        "stroke_hard_limit_m": stroke.hard_limit_m,
        "force_limit_N": force.max_force_N,
        "estop_panel_required": profile.safety.estop.panel_required,
        "trip_actions": {group: list(getattr(profile.safety.trip_actions, group)) for group in TRIP_CLASSES},
        "safety_weakened": [item.as_dict() for item in profile.safety_weakened],
        "overlay": profile.overlay_record(),
        **settings.metadata,
    }



def _replay_facts(settings: SessionSettings, profile_controller: bool) -> dict:
    """What ``harness replay`` needs besides the profile, the CAN log and the tick record.

    ``profile_controller`` is False for an identification's excitation, which replay does not rebuild.
    """
    return {
        "version": REPLAY_VERSION,  # the one harness replay reads (harness/recording/replayable.py)
        "duration_s": settings.duration_s,
        "table_check": settings.table_record is not None,
        "table_check_off": "" if settings.table_record is not None else settings.table_check_off,
        "profile_controller": profile_controller,
    }


NO_PANEL_WARNING = (
    "safety.estop.panel_required is false: this run does not require a live E-stop panel; an unplugged panel "
    "cannot be told from one that is not pressed"
)


def _note_no_panel(folder, console) -> None:
    """Record and show the weakening of running without a required E-stop panel."""
    folder.record_event(None, "safety", "estop_panel_not_required", NO_PANEL_WARNING)
    if console is not None:
        console.print(f"[bold yellow]warning:[/] {NO_PANEL_WARNING}")


def _reset_drive(link, folder, console) -> None:
    """``--reset-drive``: reset the drive's latched fault, recorded in events and metadata; refuses the run if it cannot."""
    from harness.runs.drive_reset import DriveResetRefused, reset_drive

    try:
        done = reset_drive(link)
    except DriveResetRefused as err:
        folder.metadata["drive_reset"] = {"sent": False, "refused": str(err)}
        folder.record_event(None, "safety", "drive_reset_refused", str(err))
        folder.finish("refused", trip_reason=str(err))
        raise
    folder.metadata["drive_reset"] = done.as_dict()
    folder.record_event(None, "safety", "drive_reset" if done.sent else "drive_reset_not_needed", done.summary())
    if console is not None:
        console.print(done.summary(), highlight=False)


def _check_host_timing(
    profile: Profile, settings: SessionSettings, link, folder, report, judge_idle: bool = False,
) -> HostTiming:
    """The pre-flight timing check (harness.loop.preflight); refuses the run, nothing moved, if it fails.

    ``judge_idle``: the loop has no real-time priority, so the machine's idle CPU is judged too.
    """
    samples = [link.reader.sample(name) for name in CONTROL_MEASUREMENTS]
    timing = measure_host_timing(
        profile.control.rate_hz, profile.safety.run.max_stall_s, profile.loop.spin_s,
        poll=lambda: link.reader.poll(0.0),  # drain what the rig sends; ages are judged from the loop's first tick
        frame_counts=lambda: tuple(sample.count for sample in samples),  # and watch the rig's frames arrive
        max_sensor_age_s=profile.safety.sensors.max_sensor_age_s, judge_idle=judge_idle,
    )
    folder.record_event(None, "timing", "host_timing", timing.summary())
    if report is not None:
        report(timing)
    try:
        timing.check()
    except HostTimingRefused as err:
        folder.finish("refused", trip_reason=str(err))
        raise
    return timing


def run_session(
    profile: Profile,
    settings: SessionSettings,
    *,
    on_start: Callable[[float], None] | None = None,
    make_lockstep: Callable[[ControlTick], Callable[[int, float], bool]] | None = None,
    on_link: Callable[[HarnessLink], None] | None = None,
    on_host_timing: Callable[[HostTiming], None] | None = None,
    console=None,
    stop_table: Callable[[float], object] | None = None,
    table_link: CanTableLink | None = None,
    controller: Controller | None = None,
) -> SessionResult:
    """Run one session and return its outcome; the run folder is finished in every case.

    Parameters
    ----------
    profile : Profile
    settings : SessionSettings
    on_start : callable, optional
        Called with the loop time when RUNNING begins.
    make_lockstep : callable, optional
        Given the tick, returns the lockstep wait function (``settings.lockstep`` must be True).
    on_link : callable, optional
        Called with the open harness link before the loop starts (e.g. to switch a virtual rig to lockstep).
    on_host_timing : callable, optional
        Called with the pre-flight timing check's result (real time only), before arming.
    console : rich Console, optional
    stop_table : callable, optional
        ``stop_table(now)``: send the table controller's stop (the ``stop_table`` trip action);
        None when the run has no table link.
    table_link : CanTableLink, optional
        The table controller on the bus (``table.link: can`` for ``harness run``): started at
        RUNNING, stopped at the end and on a trip (``stop_table`` trip action), record time
        counted from its RIG_STATUS ``table_running``. Overrides ``on_start`` and ``stop_table``.
    controller : Controller, optional
        What computes the raw force instead of the profile's ``control.controller`` design (an
        identification's excitation); the supervisor shapes and supervises it all the same.

    Raises
    ------
    HostTimingRefused
        In real time, when the host cannot hold the stall budget (nothing was moved).
    ProfileError
        For a loop rate the run could not arm at or hold (:func:`~harness.runs.loop_rate.check_loop_rate`),
        whoever called: the command line checks it first, naming ``--rate``; this is the check a
        direct caller cannot skip.
    """
    check_loop_rate(profile, rate_given=False, virtual_rig=False)
    if profile.structure.n_stories != PROTOCOL_STORIES:
        raise ProfileError(f"the CAN protocol carries {PROTOCOL_STORIES} stories; this profile has {profile.structure.n_stories}",
                           profile.source_path, "structure")
    warm_up()  # the estimator's kernel must not compile inside the first tick
    # The profile's design runs through the profile's compensation; a given controller (an
    # identification's excitation) is commanded as it is.
    profile_controller = controller is None  # an identification's excitation is not the profile's: replay cannot rebuild it
    compensator = make_compensator(profile, controller=profile.control.controller) if controller is None else NoCompensation()
    if controller is None:
        controller = build_controller_for_rig(profile, profile.control.controller)
    estimator = make_friction_estimator(profile)
    supervisor = Supervisor(profile.safety, period_s=1.0 / profile.control.rate_hz)
    record = settings.table_record
    if record is not None:
        supervisor.table_record.expect(record.velocity_m_s, record.dt_s, settings.duration_s, 1.0 / profile.control.rate_hz)
    else:
        supervisor.table_record.ignore(settings.table_check_off)
    if table_link is not None:
        on_start, stop_table = table_link.start, table_link.stop
    check_log_dir(settings.log_dir)  # before the bus opens: an unwritable log directory is bad input, nothing started
    check_log_space(settings.log_dir, expected_run_size(profile, settings))  # and one too full to hold the record
    stop_if_requested("before opening the bus")
    scheduling: Scheduling | None = None
    link = open_harness(settings.can, settings.peer_pids)
    folder = None
    try:
        folder = RunFolder.create(
            settings.log_dir, profile.name, settings.kind, profile.resolved_data(), CONTROL_ROW,
            metadata={**_metadata(profile, settings), "replay": _replay_facts(settings, profile_controller)},
            tick_columns=TICK_COLUMNS,
        ).start()
        recording = folder
        stop_if_requested("after creating the run folder")
        heartbeat_every = max(1, round(profile.control.rate_hz / settings.can.heartbeat_rate_hz))
        estop_every = max(1, round(profile.control.rate_hz / settings.can.estop_rate_hz))
        tick = ControlTick(link, controller, estimator, supervisor, folder, heartbeat_every, estop_every, stop_table,
                           compensator)
        if not profile.safety.estop.panel_required:
            _note_no_panel(folder, console)
        link.reader.tap, link.writer.tap = folder.frame_taps()
        if table_link is not None:
            table_link.attach(link)
        if on_link is not None:
            on_link(link)
            stop_if_requested("after the rig answered")
        if settings.reset_drive:
            _reset_drive(link, folder, console)
            stop_if_requested("after the drive's reset")
        if not settings.lockstep:  # before the pre-flight check, so that it measures the scheduling the run gets
            scheduling = request_fifo(profile.loop.realtime.fifo_priority)
        host_timing = None if settings.lockstep else _check_host_timing(
            profile, settings, link, folder, on_host_timing, judge_idle=scheduling is not None and not scheduling.granted)
        lockstep = make_lockstep(tick) if settings.lockstep and make_lockstep else None
        status = LoopStatus()
        tick.attach_status(status)  # stories, fault code and event lines for the live console
        loop = ControlLoop(tick, profile.loop, profile.control.rate_hz, settings.duration_s, lockstep, on_start, status,
                           table_running=table_link.running if table_link is not None else None, scheduling=scheduling,
                           recorder_error=lambda: recording.writer_error,
                           tick_log=TickLog(folder.record_tick, lambda: recording.frames_recorded))
        controller_name = settings.metadata.get("controller", profile.control.controller)  # an excitation names itself
        title = run_title(profile.name, settings.kind, settings.metadata, controller_name, profile.control.rate_hz,
                          bool(lockstep))
        alerts = (summary(profile.safety_weakened),) if profile.safety_weakened else ()
        with LiveConsole(status, profile.safety.stroke.soft_limit_m, profile.safety.stroke.hard_limit_m,
                         profile.safety.force.max_force_N, title, console, settings.show_console, alerts,
                         settings.notes):
            try:
                result = loop.run()
            except ArmTimeout as err:
                from harness.runs.drive_reset import latched_fault_note

                note = latched_fault_note(link)  # say why the drive is not ready, and what resets it
                refused = ArmTimeout(f"{err.failed}; {note}", profile.loop.arm_timeout_s) if note else err
                folder.record_event(None, "fault", "arm_refused", str(refused))
                folder.finish("error", trip_reason=f"arm refused: {refused.failed}")
                if refused is err:
                    raise
                raise refused from err
        if table_link is not None and result.outcome != "tripped":
            table_link.stop(loop.scheduler.elapsed_s)  # the end of the run (a trip's stop is its trip action)
        bus = bus_statistics(link)
        folder.finish(result.outcome, trip_reason=result.trip_reason or None,
                      summary={"timing": result.timing, "realtime": result.realtime_report,
                               "scheduling": result.scheduling, "bus": bus,
                               "record_start_t_s": result.record_start_t_s, "table_record": result.table_record,
                               "host_timing": host_timing.as_dict() if host_timing else None})
        return SessionResult(result.outcome, result.trip_reason, folder.path, result, bus, folder.record_problem())
    except StoppedByOperator as stop:  # at a safe point before the loop: nothing moved
        if folder is not None:
            folder.record_event(None, "lifecycle", "operator_stop", str(stop))
            folder.finish("stopped", trip_reason=f"operator stop before arming, {stop.where}")
            stop.run_path = str(folder.path)
        raise
    except BaseException:
        if folder is not None:
            folder.finish("error")  # idempotent: keeps an outcome already written
        raise
    finally:
        if scheduling is not None:
            restore_scheduling(scheduling)  # what follows (the reference simulation, the report) at normal priority
        link.writer.tap = None
        link.reader.tap = None
        link.close()
