"""``harness dry-run``: the whole test against the virtual rig, over CAN, with the real loop.

By default the rig runs as a separate ``harness rig`` process, as on a real channel
(``socketcan``/``vcan0``): the loop's process then holds nothing but the loop, so no other
thread takes the interpreter lock from it. The default bus is the ``seqpacket`` interface
(drivers/transports/seqpacket/), a Unix-socket bus private to this dry run that needs no set-up.
The command starts the rig unless ``--external-rig`` says one is already running. On
python-can's in-process ``virtual`` bus (``--interface virtual``) the rig runs in a thread
of this process instead (fine in lockstep; in real time it competes with the loop). Afterwards the
dry run's peaks are printed beside the simulated passive reference, and compared with
``harness simulate --rig-effects``: the same rig models (sensors, actuator, safety)
simulated offline.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import secrets
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from drivers.link import HarnessLink
from drivers.protocol.protocol_values import RigCommand
from drivers.reader import Sample
from harness.canbus.config import CanConfig
from harness.control.factory import make_controller
from harness.errors import BusError
from harness.loop.operator import stop_if_requested
from harness.loop.table_link import CanTableLink
from harness.loop.tick import ControlTick
from harness.model.plant import Plant, TableMotion
from harness.model.warmup import warm_up
from harness.motions import GroundMotion
from harness.motions.summary import motion_facts
from harness.paths import LOG_DIR
from harness.profile import Profile
from harness.recording import load_run
from harness.recording.peaks import run_peaks
from harness.recording.runfolder import check_log_dir
from harness.recording.space import check_log_space
from harness.rig.truth import truth_metadata, truth_summary
from harness.runs.loop_rate import check_loop_rate
from harness.runs.options import StudyOptions, prepare_motion, resolve_profile
from harness.runs.run_context import write_dry_run_context
from harness.runs.session import SessionResult, SessionSettings, expected_run_size, run_session
from harness.signals.peaks import Peaks
from harness.simulation.case import CaseResult, SamplingSettings, run_case
from harness.simulation.twin import run_rig_twin

#: The python-can interface (drivers/transports/seqpacket/) of the default dry run: the rig runs in its own
#: process, on a Unix-socket bus that needs no set-up.
PRIVATE_BUS_INTERFACE = "seqpacket"
RIG_APPEAR_TIMEOUT_S = 60.0
#: The dry run's report when the rig answered its table start with RIG_STATUS ``start_refused``.
TABLE_START_REFUSED = (
    "the rig refused this run's table start (RIG_STATUS start_refused: its table was already running), so the table "
    "did not play this run's record; the peaks below are not this record's"
)
#: After this long without a RIG_STATUS frame from an external rig, say so, and how much longer the wait lasts (s).
NO_RIG_NOTICE_S = 4.0
IN_PROCESS_SWITCH_INTERVAL_S = 2e-4
#: Frames the harness sends to bring the rig into lockstep, and to show it the command counter, before the run.
#: The rig's E2E check rejects the first frame of a harness that follows another within its new-sender
#: silence (the counter jumps; the check resynchronises on it): the second is then accepted.
LOCKSTEP_SYNC_ATTEMPTS = 3
#: Longest wait (s) for the rig's answer to one of those frames; the rig answers in lockstep at once.
LOCKSTEP_SYNC_WAIT_S = 1.0


@dataclass(frozen=True)
class DryRunOptions:
    """The command line's choices for a dry run."""

    study: StudyOptions = StudyOptions()
    interface: str | None = None
    channel: str | None = None
    log_dir: str | None = None
    lockstep: bool = False
    external_rig: bool = False
    show_console: bool = True
    compare: bool = True
    reset_drive: bool = False  # --reset-drive (with external_rig): reset the drive's latched fault before arming


@dataclass
class DryRunResult:
    """The session and the simulated twins it is compared with."""

    session: SessionResult
    profile: Profile  # resolved: every option folded in
    peaks: Peaks
    passive: CaseResult | None
    twin: CaseResult | None
    motion: GroundMotion
    span_s: float | None = None  # record time covered by a run that ended early (s); None: the whole record
    truth_note: str = ""  # where the rig it served differs from the design (harness/rig/truth.py); "" when it does not
    #: Why the table did not play this run's record (the rig refused its start); "" when it did.
    table_refused: str = ""

    def largest_twin_difference(self) -> tuple[str, float]:
        """The peak that differs most from the simulated twin's, and by how much (% of the twin's).

        Only for a dry run compared with its twin (``DryRunOptions.compare``).
        """
        assert self.twin is not None, "a dry run run with compare=False has no twin"
        ours, twin = self.peaks.flatten(), self.twin.peaks.flatten()
        worst = max(twin, key=lambda k: abs(ours[k] - twin[k]) / abs(twin[k]) if twin[k] else 0.0)
        difference = abs(ours[worst] - twin[worst]) / abs(twin[worst]) * 100 if twin[worst] else 0.0
        return worst, difference


def _rig_process(profile: Profile, can, lockstep: bool) -> subprocess.Popen:
    """Start the virtual rig in its own process, serving the resolved ``profile`` on ``can``.

    The rig gets the profile this dry run resolved (``--set``, ``--variant`` and every
    option folded in) as a JSON document on its standard input: it parses no options
    of its own, so it cannot run a different profile from the loop's. On a ``seqpacket``
    channel it admits only this process at the other end (harness/runs/rig_process.py).
    """
    job = {"profile": profile.resolved_data(), "interface": can.interface, "channel": can.channel,
           "lockstep": lockstep, "parent_pid": os.getpid()}
    # Its own session: the terminal's Ctrl-C goes to the loop, which stops safely, not to the rig.
    process = subprocess.Popen([sys.executable, "-m", "harness.runs.rig_process"], stdin=subprocess.PIPE,
                               stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
    assert process.stdin is not None
    process.stdin.write(json.dumps(job).encode())
    process.stdin.close()
    return process


def _answered_after(status: Sample, seen: int, answered: Callable[[], bool]) -> bool:
    """A RIG_STATUS frame arrived after the ``seen``-th, and ``answered()`` holds."""
    return status.count > seen and answered()


class RigCoordinator:
    """The harness side's dealings with the virtual rig: wait for it, lockstep; its :attr:`table` starts and stops the table.

    Parameters
    ----------
    lockstep : bool
    period_s : float
        The loop's tick period (s): tick k happens at loop time k * period_s.
    process : subprocess.Popen, optional
        The rig process this command started (to report why it died).
    appear_timeout_s : float
    notify : callable, optional
        ``notify(line)``: told when an external rig has not answered within :data:`NO_RIG_NOTICE_S`
        (default: a line on standard error, which ``--quiet`` does not silence).
    """

    def __init__(
        self, lockstep: bool, period_s: float, process: subprocess.Popen | None = None,
        appear_timeout_s: float = RIG_APPEAR_TIMEOUT_S, notify: Callable[[str], None] | None = None,
    ):
        self.lockstep = lockstep
        self.notify = notify or _note_on_stderr
        #: The rig process's id, the one peer the harness's side of a private channel admits; () for none.
        self.peer_pids: tuple[int, ...] = () if process is None else (process.pid,)
        self.period_s = period_s
        self.process = process
        self.appear_timeout_s = appear_timeout_s
        self.link: HarnessLink | None = None  # set by on_link
        self.base_step = 0
        #: The virtual table's start and stop: the same RIG_CONTROL frames `harness run` sends a real one.
        self.table = CanTableLink(lockstep)

    def _poll_for(self, done: Callable[[], bool], timeout_s: float) -> bool:
        """Poll the bus until ``done()`` (True) or ``timeout_s`` passed (False); raises if the rig process died."""
        link = self.link
        assert link is not None, "polled from on_link, once the link is open"
        deadline = time.monotonic() + timeout_s
        while not done():
            stop_if_requested("while waiting for the virtual rig")
            process = self.process
            if process is not None and process.poll() is not None:
                detail = process.stderr.read().decode(errors="replace").strip()[-2000:] if process.stderr else ""
                raise BusError(f"the virtual rig process exited with status {process.returncode}: {detail}")
            if time.monotonic() > deadline:
                return False
            link.reader.poll(0.0, block_s=0.05)
        return True

    def _no_answer(self, what: str, timeout_s: float) -> BusError:
        assert self.link is not None
        return BusError(
            f"{what} within {timeout_s:g} s on {self.link.bus.channel_info}; start a rig with "
            "`harness rig PROFILE --interface ... --channel ...` (or drop --external-rig)"
        )

    def on_link(self, link: HarnessLink) -> None:
        """Wait for the rig's status frames; switch it to lockstep and note its step count; refuse a running table."""
        self.link = link
        self.table.attach(link)
        status = link.reader.sample("RIG_STATUS")
        if not self._wait_for_rig(status):
            raise self._no_answer("no RIG_STATUS frame from a virtual rig", self.appear_timeout_s)
        if self.lockstep:
            self.base_step = self._enter_lockstep(link)
        self._refuse_running_table(status)

    def start_refused(self) -> bool:
        """True when the newest RIG_STATUS says the rig refused this run's table start (its table was already running)."""
        if self.link is None:
            return False
        status = self.link.reader.sample("RIG_STATUS")
        return status.count > 0 and status.values[status.index("start_refused")] == 1.0

    def _wait_for_rig(self, status: Sample) -> bool:
        """Poll until the rig's first RIG_STATUS; an external rig silent for :data:`NO_RIG_NOTICE_S` is said so."""
        first = min(NO_RIG_NOTICE_S, self.appear_timeout_s)
        if self._poll_for(lambda: status.count > 0, first):
            return True
        rest = self.appear_timeout_s - first
        if rest <= 0:
            return False
        if self.process is None:  # a rig this command started may still be compiling; an external one should answer
            assert self.link is not None
            self.notify(f"no rig answers on {self.link.bus.channel_info} (no RIG_STATUS in {first:g} s); "
                        f"waiting {rest:g} s more for one (start it with `harness rig PROFILE --channel ...`)")
        return self._poll_for(lambda: status.count > 0, rest)

    def _refuse_running_table(self, status: Sample) -> None:
        """Refuse, before arming, a table that already runs: an earlier run's, another harness's, or the rig's own record.

        Its motion is not this run's record (the rig refuses a start while its table runs, RIG_STATUS
        ``start_refused``): the run would be measured against a table it does not drive.
        """
        values = status.values
        if values[status.index("table_running")] != 1.0:
            return
        raise BusError(
            f"the rig's table is running (RIG_STATUS table_running, at {values[status.index('record_time')]:.2f} s into "
            "the rig's record) while this harness is idle: the table is moving, started by an earlier run, another "
            "harness or a rig serving other record options, and it would not play this run's record. Refused before "
            "arming (this command sent no force); stop that table (restart `harness rig`) and run again"
        )

    def _enter_lockstep(self, link: HarnessLink) -> int:
        """Switch the rig to lockstep and step it once with a disabled command; return its step index then.

        Each frame is sent again until the rig shows it was accepted (RIG_STATUS ``lockstep`` set;
        ``step_index`` advanced): a harness that starts right after another one's run finds the rig's
        counter check expecting the old run's next counter, and its first frame of each kind is
        rejected. Unsynchronised, the run's first command would be the one lost, and the lockstep
        loop would wait for a step that never comes. When the command had to be sent again, the
        step index is read once more after a further wait: a first command that was only slow to be
        answered has stepped the rig too.
        """
        status = link.reader.sample("RIG_STATUS")
        lockstep, step_index = status.index("lockstep"), status.index("step_index")
        self._send_until_answered(link, lambda: link.writer.rig_control(RigCommand.NONE, True, 0.0),
                                  lambda: status.values[lockstep] == 1, "the rig did not answer the switch to lockstep")
        before = status.values[step_index]
        sent = self._send_until_answered(link, lambda: link.writer.command(0.0, False, 0.0),
                                         lambda: status.values[step_index] > before,
                                         "the rig did not step on a disabled command in lockstep")
        if sent > 1:
            self._poll_for(lambda: False, LOCKSTEP_SYNC_WAIT_S)
        return int(status.values[step_index])

    def _send_until_answered(
        self, link: HarnessLink, send: Callable[[], object], answered: Callable[[], bool], what: str,
    ) -> int:
        """``send()`` until a RIG_STATUS frame after it shows ``answered()``; return the frames sent.

        Raises
        ------
        BusError
            No answer to any of :data:`LOCKSTEP_SYNC_ATTEMPTS` frames, or the rig process died.
        """
        status = link.reader.sample("RIG_STATUS")
        for attempt in range(1, LOCKSTEP_SYNC_ATTEMPTS + 1):
            seen = status.count
            send()
            if self._poll_for(functools.partial(_answered_after, status, seen, answered), LOCKSTEP_SYNC_WAIT_S):
                return attempt
        raise self._no_answer(f"{what} (sent {LOCKSTEP_SYNC_ATTEMPTS} times)", LOCKSTEP_SYNC_WAIT_S)

    def lockstep_wait(self, tick: ControlTick) -> Callable[[int, float], bool]:
        """The loop's lockstep wait: poll until the rig reports step ``base + k``."""
        reader = tick.reader
        status = reader.sample("RIG_STATUS")
        step_index = status.index("step_index")
        period = self.period_s

        def wait(k: int, timeout_s: float) -> bool:
            now = k * period
            reader.poll(now)
            deadline = time.monotonic() + timeout_s
            while status.values[step_index] < self.base_step + k:
                if time.monotonic() > deadline:
                    return False
                reader.poll(now, keep_fresh=True, block_s=0.005)
            return True

        return wait


def _note_on_stderr(line: str) -> None:
    print(f"note: {line}", file=sys.stderr, flush=True)


def simulated_twins(
    profile: Profile, motion: GroundMotion, rate_hz: float, controller: str, lockstep: bool, span_s: float | None = None,
) -> tuple[CaseResult, CaseResult]:
    """The passive reference and the controlled rig twin of a dry run, simulated offline.

    The twin runs the rig's own sensor, actuator and safety models; a real-time dry run
    adds on average one period of delay (frames sampled up to a period old, commands
    applied up to a period late); in lockstep there is none, and sensor delays are
    rounded to whole steps as the rig does. ``span_s`` limits both to the record time a
    run that ended early covered (s), so peaks are compared over the same span. Both run on
    the rig's truth (``rig.truth``): the reduction a dry run reports is then its controller's
    on that rig, as a lab's passive and controlled tests on one table are.
    """
    duration_s = motion.duration_s if span_s is None else max(min(span_s, motion.duration_s), 1.0 / rate_hz)
    table = TableMotion.from_motion(motion)
    truth = profile.rig_truth()  # a passive test on the same rig: the rig's truth, not the design
    plant = Plant(truth.building, truth.bearing, table, rtol=profile.simulation.rtol)
    passive = run_case("passive", plant, duration_s, SamplingSettings(rate_hz))
    delay = 0.0 if lockstep else 1.0 / rate_hz
    twin = run_rig_twin(profile, motion, rate_hz, make_controller(profile, controller), asynchronous_delay_s=delay,
                        lockstep=lockstep, duration_s=duration_s)
    return passive, twin


def record_span_s(session: SessionResult, motion: GroundMotion) -> float | None:
    """Record time a run that ended early covered (s); None when it ran the whole record."""
    if session.outcome == "completed":
        return None
    start = session.loop.record_start_t_s
    if start is None:
        return 0.0
    data = load_run(session.run_path)
    span = float(data["t_s"][-1]) - start
    return span if span < motion.duration_s else None


#: Random bytes in the name of a dry run's private channel (hex-encoded: twice as many characters).
CHANNEL_TOKEN_BYTES = 8


def private_bus(can: CanConfig, external_rig: bool, suffix: str = "") -> CanConfig:
    """``can`` on a channel private to this run (and ``suffix``) when the rig is ours on the private bus.

    Two dry runs at once (or a test suite) then never meet on one ``seqpacket`` channel. The name
    carries random bytes, so nobody can bind it before this run (a plain name is a socket in this
    user's private directory, which no other user can write: drivers/transports/seqpacket/channel.py); the rig
    process is handed it, and each end admits only the other's process (:func:`_rig_process`,
    ``SessionSettings.peer_pids``).
    """
    if can.interface == PRIVATE_BUS_INTERFACE and not external_rig:
        token = secrets.token_hex(CHANNEL_TOKEN_BYTES)
        return dataclasses.replace(can, channel=f"{can.channel}-{os.getpid()}-{token}{suffix}")
    return can


@contextmanager
def serving_virtual_rig(
    profile: Profile, can: CanConfig, lockstep: bool, motion: GroundMotion, external_rig: bool = False,
) -> Iterator[RigCoordinator]:
    """The virtual rig serving ``can`` for the duration of the block; yields the session's :class:`RigCoordinator`.

    On python-can's in-process ``virtual`` interface the rig runs in a thread of this process;
    otherwise in its own process (:func:`_rig_process`); on either, none when ``external_rig`` says
    one already serves the channel (on ``virtual``, a rig the caller runs in this process). The rig
    is stopped, and its bus closed, however the block ends.

    Parameters
    ----------
    profile : Profile
        Resolved: the rig serves exactly this profile.
    can : CanConfig
    lockstep : bool
    motion : GroundMotion
        The processed record (the in-process rig's table; the rig process prepares its own).
    external_rig : bool

    Raises
    ------
    ProfileError
        For a loop rate the run could not arm at or hold, or whose period is not whole physics
        sub-steps of the rig (:func:`~harness.runs.loop_rate.check_loop_rate`), before the rig starts.
    """
    from harness.canbus.link import open_rig
    from harness.rig.parts import RigParts
    from harness.rig.virtual_rig import VirtualRig

    check_loop_rate(profile, rate_given=False, virtual_rig=not external_rig)

    rate_hz = profile.control.rate_hz
    rig = rig_link = process = None
    switch_interval = sys.getswitchinterval()
    try:
        if can.interface == "virtual" and not external_rig:
            # The rig shares this process: hand the interpreter lock over every 0.2 ms instead
            # of every 5 ms, or the loop waits up to 5 ms for it behind the rig thread.
            sys.setswitchinterval(IN_PROCESS_SWITCH_INTERVAL_S)
            rig_link = open_rig(can)
            rig = VirtualRig(RigParts.from_profile(profile), motion, rig_link, step_period_s=1.0 / rate_hz, lockstep=lockstep,
                             can_config=can)
            rig.start_thread()
        elif not external_rig:
            process = _rig_process(profile, can, lockstep)
        yield RigCoordinator(lockstep, 1.0 / rate_hz, process)
    finally:
        sys.setswitchinterval(switch_interval)
        if rig is not None:
            rig.stop()
        if rig_link is not None:
            rig_link.close()
        if process is not None:
            _stop_process(process)


def dry_run(profile: Profile, options: DryRunOptions, console=None, on_host_timing=None) -> DryRunResult:
    """Run a dry run; see the module docstring."""
    warm_up()  # compile the kernels now, never inside the loop or the rig
    stop_if_requested("after loading the compiled kernels")
    profile = resolve_profile(profile, options.study)
    check_loop_rate(profile, options.study.rate_hz is not None, virtual_rig=not options.external_rig)
    motion = prepare_motion(profile)
    rate_hz = profile.control.rate_hz
    can = private_bus(profile.can_settings(options.interface, options.channel), options.external_rig)
    # An external rig serves its own profile: only a rig this command serves is known to have this truth.
    differences = () if options.external_rig else profile.rig_truth().differences
    settings = SessionSettings(
        kind="dry-run", can=can, duration_s=motion.duration_s,
        log_dir=Path(options.log_dir) if options.log_dir else LOG_DIR, lockstep=options.lockstep,
        show_console=options.show_console,
        metadata={"record": motion_facts(motion), **truth_metadata(differences)},
        notes=((truth_summary(differences),) if differences else ()) + motion.warnings,
        table_record=motion,  # the rig's table starts with RUNNING (RIG_CONTROL): record time is the table's
        reset_drive=options.reset_drive,
    )
    check_log_dir(settings.log_dir)  # before the rig starts and the bus opens (run_session checks both again)
    check_log_space(settings.log_dir, expected_run_size(profile, settings))
    stop_if_requested("before starting the virtual rig")
    with serving_virtual_rig(profile, can, options.lockstep, motion, options.external_rig) as coordinator:
        settings.peer_pids = coordinator.peer_pids
        session = run_session(
            profile, settings, on_start=coordinator.table.start,
            make_lockstep=coordinator.lockstep_wait if options.lockstep else None,
            on_link=coordinator.on_link, on_host_timing=on_host_timing, console=console,
            stop_table=coordinator.table.stop,
        )
        table_refused = TABLE_START_REFUSED if coordinator.start_refused() else ""
    peaks = run_peaks(load_run(session.run_path))  # weight: the metadata's, the resolved profile's
    passive = twin = None
    span = record_span_s(session, motion)
    if options.compare:
        passive, twin = simulated_twins(profile, motion, rate_hz, profile.control.controller, options.lockstep, span)
    session.write_after_run(  # for `harness report`
        "target_motion.csv and the simulated references",
        lambda: write_dry_run_context(session.run_path, motion, passive, twin, span, options.lockstep))
    return DryRunResult(session, profile, peaks, passive, twin, motion, span, truth_summary(differences), table_refused)


def _stop_process(process: subprocess.Popen) -> None:
    import signal

    if process.poll() is None:
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
