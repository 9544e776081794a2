"""The control loop's run: ticks at a fixed rate (or in lockstep with a virtual rig) through the phases

    wait until every pre-arm check passes -> ARMED -> (settle) -> RUNNING for the record
    -> STOPPING (force ramps to zero) -> DONE, or TRIPPED (latched) at any point,

then a few more ticks with zero force and the drive disabled. The loop owns time: every
tick gets ``t`` and ``dt``; in real time from the absolute-deadline scheduler, in lockstep
as ``k * period`` once the rig reports step ``k``.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from harness.errors import SafetyError
from harness.loop.config import LoopConfig
from harness.loop.ending import run_ending
from harness.loop.operator import OperatorSignals
from harness.loop.status import LoopStatus
from harness.loop.tick import ControlTick
from harness.loop.tick_log import TickLog
from harness.loop.timing import PHASE, GapTrace, TimingStats
from harness.realtime.host import Scheduling, apply_realtime, restore_realtime
from harness.realtime.scheduler import FixedRateScheduler
from harness.recording.layout import Outcome
from harness.safety.lifecycle import State
from harness.safety.operator_detectors import HOST_TIMING_REMEDIES
from harness.safety.supervisor import SupervisedCommand
from harness.signals.timing_counts import TimingCounts, missed_periods

_FINAL = (State.DONE, State.TRIPPED)
#: The outcome of a run that ended in each final state (any other: ``stopped``).
#: Longest wait for the table controller's RIG_STATUS ``table_running`` after RIG_CONTROL start (s).
TABLE_START_TIMEOUT_S = 2.0
#: The safe stop's reason when the recorder cannot write (docs/SAFETY.md, "A lost record").
RECORD_LOST = "record_lost"


class ArmTimeout(SafetyError):
    """The pre-arm checks did not all pass within the arm timeout; ``failed`` lists them."""

    def __init__(self, failed: str, timeout_s: float):
        self.failed = failed
        super().__init__(f"could not arm within {timeout_s:g} s: {failed}")


@dataclass
class LoopResult:
    """How the run ended and its timing."""

    outcome: Outcome
    trip_reason: str = ""
    trip_detail: str = ""
    timing: dict = field(default_factory=dict)
    realtime_report: list[str] = field(default_factory=list)
    #: The loop thread's scheduling during the run (:meth:`~harness.realtime.host.Scheduling.as_dict`).
    scheduling: dict = field(default_factory=dict)
    operator_stopped: bool = False
    record_start_t_s: float | None = None
    #: The table against its record (:meth:`harness.safety.table_record.TableRecordCheck.summary`).
    table_record: dict = field(default_factory=dict)


class ControlLoop:
    """Runs :class:`ControlTick` through the phases of a test.

    Parameters
    ----------
    tick : ControlTick
    config : LoopConfig
    rate_hz : float
        Tick rate (the profile's loop rate unless overridden).
    duration_s : float
        Seconds of record to run (plus settle and tail).
    lockstep : callable, optional
        ``lockstep(k, timeout_s) -> bool``: poll the bus until the rig has taken step ``k`` (the
        tick then does not poll again); None for real time.
    on_start : callable, optional
        ``on_start(t)``: called once when RUNNING begins (e.g. start the virtual table).
    status : LoopStatus, optional
        Updated every tick for a console.
    clock : callable
        Monotonic clock for the real-time scheduler.
    sleep : callable
        Its sleep function (tests pass a fake clock's).
    table_running : callable, optional
        ``table_running() -> bool``: the table controller reports that the table runs (RIG_STATUS,
        ``table.link: can``). Record time then counts from the first RUNNING tick that sees it; a
        table that does not report running within :data:`TABLE_START_TIMEOUT_S` stops the run
        safely. None: record time counts from RUNNING (the harness's own clock).
    tick_log : TickLog, optional
        Notes each tick's time, step, lateness, stall, missed deadlines, operator requests, the bus's
        loss and the CAN log's length after it (:mod:`harness.loop.tick_log`), for ``harness replay``.
    """

    def __init__(
        self,
        tick: ControlTick,
        config: LoopConfig,
        rate_hz: float,
        duration_s: float,
        lockstep: Callable[[int, float], bool] | None = None,
        on_start: Callable[[float], None] | None = None,
        status: LoopStatus | None = None,
        clock: Callable[[], float] = time.perf_counter,
        sleep: Callable[[float], None] = time.sleep,
        table_running: Callable[[], bool] | None = None,
        scheduling: Scheduling | None = None,
        recorder_error: Callable[[], BaseException | None] | None = None,
        tick_log: TickLog | None = None,
    ):
        self.tick = tick
        #: Notes what each tick was given, for ``harness replay`` (None: not recorded).
        self.tick_log = tick_log
        #: ``recorder_error()``: the error that stopped the run folder's writer, or None (looked at every tick).
        self.recorder_error = recorder_error
        self._record_lost = False
        #: A SCHED_FIFO request the caller already made for this thread (None: :meth:`run` makes it, in
        #: real time only; a lockstep run keeps normal scheduling: it runs flat out and would hold a core).
        self.scheduling = scheduling
        self.table_running = table_running
        self._awaiting_table = False
        self.config = config
        self.period_s = 1.0 / rate_hz
        self.duration_s = float(duration_s)
        span_s = config.arm_timeout_s + config.settle_s + self.duration_s + config.tail_s + config.after_s + 10.0
        self.timing = TimingStats(int(span_s / self.period_s) + 1000)
        self.lockstep = lockstep
        self.on_start = on_start or (lambda t: None)
        self.status = status or LoopStatus()
        self.scheduler = FixedRateScheduler(self.period_s, config.spin_s, clock=clock, sleep=sleep)
        #: Where the time between two ticks went, on the scheduler's clock (the tick marks its parts in it).
        self.trace = tick.trace = GapTrace(clock)
        #: Gaps past the stall budget, in any phase (each recorded as a ``stall_past_budget`` event).
        self.gaps_past_budget = 0
        #: The latest gap past the budget: its length (s), and the loop time it ended (s); 0 when none.
        self.last_gap_past_budget_s = 0.0
        self.last_gap_past_budget_end_s = 0.0
        self.signals = OperatorSignals()
        #: Missed periods and stalls so far, tick by tick (:mod:`harness.signals.timing_counts` defines them;
        #: the rows' ``overrun`` column holds each tick's missed periods, so its sum is ``counts.missed_periods``).
        self.counts = TimingCounts()
        #: Stalls ridden through (within the budget): ``counts.stalls`` less :attr:`gaps_past_budget`.
        self.stalls_ridden_through = 0
        #: Longest time between the starts of two consecutive ticks so far, counted when a stall (s).
        self.longest_stall_s = 0.0
        #: The stall budget (s): ridden through up to here, tripped beyond (the supervisor's ``loop_stall``).
        self.max_stall_s = tick.supervisor.config.run.max_stall_s
        #: The lifecycle state after the latest tick: the phase a gap that follows it begins in.
        self._gap_state = State.IDLE

    def _phase(
        self, t: float, run_started: float | None, duration_s: float, armed_at: float | None
    ) -> tuple[float | None, float | None, bool]:
        """Advance the phases after a tick; returns (run_started, armed_at, finished)."""
        supervisor = self.tick.supervisor
        state = supervisor.state
        if state is State.IDLE:
            if self.signals.stop_requested or self.signals.trip_requested or self._record_lost:
                return run_started, armed_at, True
            try:
                supervisor.arm(t, self.tick.health)
                armed_at = t
            except SafetyError as err:
                if t >= self.config.arm_timeout_s:
                    raise ArmTimeout(str(err) + self._stall_note(), self.config.arm_timeout_s) from err
        elif state is State.ARMED:
            assert armed_at is not None, "ARMED only after arm() succeeded here"
            if t - armed_at >= self.config.settle_s:
                supervisor.start(t)
                run_started = t
                self._awaiting_table = self.table_running is not None
                self.on_start(t)
        elif state is State.RUNNING:
            assert run_started is not None, "RUNNING only after start() here"
            if self._awaiting_table:
                run_started = self._await_table(t, run_started)
            elif t - run_started >= duration_s + self.config.tail_s:
                supervisor.stop(t, "record finished")
        return run_started, armed_at, state in _FINAL

    def _await_table(self, t: float, started: float) -> float:
        """RUNNING, table started: record time begins when the table controller reports running.

        Returns the loop time (s) record time counts from: ``t`` once the table runs; until then
        the time RUNNING began, and a safe stop if the table has not reported running within
        :data:`TABLE_START_TIMEOUT_S`.
        """
        assert self.table_running is not None, "awaiting the table only when there is a table link"
        if self.table_running():
            self._awaiting_table = False
            return t
        if t - started >= TABLE_START_TIMEOUT_S:
            self._awaiting_table = False
            self.tick.supervisor.stop(
                t, f"the table controller did not report RIG_STATUS table_running within {TABLE_START_TIMEOUT_S:g} s "
                "of RIG_CONTROL start (table.link: can)",
            )
        return started

    def _check_recorder(self, t: float) -> None:
        """A recorder that cannot write stops the run safely (``record_lost``), once; before arming, it never arms."""
        assert self.recorder_error is not None, "called only with a recorder to watch"
        error = self.recorder_error()
        if error is None:
            return
        self._record_lost = True
        supervisor = self.tick.supervisor
        detail = (f"the recorder cannot write the run folder ({type(error).__name__}: {error}): the run is stopped "
                  "safely, its record is incomplete")
        supervisor.events.push(t, "fault", RECORD_LOST, detail)
        if supervisor.state in (State.IDLE, State.ARMED, State.RUNNING):  # later, the ramp to zero is under way
            if supervisor.state is not State.IDLE:
                supervisor.stop(t, RECORD_LOST)
            supervisor.stop_reason, supervisor.stop_detail = RECORD_LOST, detail

    def _wait(self, k: int) -> tuple[float, float]:
        """Wait for tick ``k``; return (t, lateness)."""
        if self.lockstep is None:
            t = self.scheduler.wait()
            return t, self.scheduler.lateness_s
        # once the rig stopped answering, the closing ticks do not wait for it again
        timeout_s = 0.0 if self.tick.health.bus_gone else self.config.lockstep_timeout_s
        if not self.lockstep(k, timeout_s):
            self.tick.health.bus_gone = True  # the rig stopped answering: trips as bus_gone
        return k * self.period_s, 0.0

    def _note_stall(self, t: float, stall_s: float, woke_s: float) -> int:
        """Count the tick's missed periods and its stall, record one past the budget; return the missed periods.

        A stall is a gap of two periods or more between the starts of two ticks (one or more
        missed periods; :mod:`harness.signals.timing_counts` defines both, and every display
        takes them from there). Within the budget the stall is counted, shown on the
        console and recorded as a ``timing`` event ``stall_ridden_through``. Beyond it the
        supervisor trips (``loop_stall``) where the drive may be enabled, and in every phase the
        loop records a ``timing`` event ``stall_past_budget``: the gap's start and end (loop
        time), the phase it began in and what the loop was doing through it (:class:`GapTrace`),
        so every gap the console's "longest" counts is in the record (docs/SAFETY.md, "Stall
        attribution"). In lockstep (``stall_s`` 0) the rig waits for the loop.
        """
        missed = missed_periods(stall_s, self.period_s)
        if missed < 1:
            return 0
        self.counts.add(missed)
        self.longest_stall_s = max(self.longest_stall_s, stall_s)
        if stall_s <= self.max_stall_s:
            self.stalls_ridden_through += 1
            self.tick.supervisor.events.push(
                t, "timing", "stall_ridden_through",
                f"{stall_s * 1e3:.1f} ms between two ticks ({missed} missed periods), within the "
                f"{self.max_stall_s * 1e3:.1f} ms stall budget",
            )
        else:
            self.gaps_past_budget += 1
            self.last_gap_past_budget_s = stall_s
            self.last_gap_past_budget_end_s = t
            self.tick.supervisor.events.push(
                t, "timing", "stall_past_budget",
                f"{stall_s * 1e3:.1f} ms between two ticks ({missed} missed periods), past the "
                f"{self.max_stall_s * 1e3:.1f} ms stall budget: from {woke_s - stall_s:.4f} s to {woke_s:.4f} s "
                f"(loop time), begun in {self._gap_state.name}; {self.trace.describe()}",
            )
        return missed

    def _stall_note(self) -> str:
        """For a refusal to arm: the latest gap past the budget, which a drive's watchdog fault may follow ("" if none)."""
        if not self.gaps_past_budget:
            return ""
        return (f"; the loop itself stalled {self.last_gap_past_budget_s * 1e3:.1f} ms up to t = "
                f"{self.last_gap_past_budget_end_s:.3f} s, past its {self.max_stall_s * 1e3:.1f} ms stall budget "
                "(a drive's watchdog fault after it is the stall's): " + HOST_TIMING_REMEDIES)

    def run(self) -> LoopResult:
        """Run the whole test: arm, settle, the record, the tail, the ramp-down."""
        duration_s = self.duration_s
        timing = self.timing
        scheduling = self.scheduling
        if scheduling is None and self.lockstep is not None:  # lockstep asks for nothing: recorded as normal scheduling
            scheduling = Scheduling(self.config.realtime.fifo_priority)
        report = apply_realtime(self.config.realtime, scheduling)
        tick, health, trace = self.tick, self.tick.health, self.trace
        run_started = armed_at = None
        finished_at = None
        self.signals.install()
        threads = [thread.name for thread in threading.enumerate()]  # what shares the interpreter with the loop
        try:
            self.scheduler.start()
            k = 0
            previous_t = -self.period_s
            previous_woke = None
            t = 0.0
            tick_log = self.tick_log
            if tick_log is not None:
                tick_log.start()
            try:
                while True:
                    t, lateness = self._wait(k)
                    trace.woke()
                    dt = t - previous_t  # a whole period, or more after deadlines were skipped
                    previous_t = t
                    woke = t + lateness  # when this tick really began (s, loop clock)
                    stall_s = 0.0 if previous_woke is None or self.lockstep is not None else woke - previous_woke
                    previous_woke = woke
                    missed = self._note_stall(t, stall_s, woke)
                    health.operator_stop = self.signals.stop_requested
                    health.operator_trip = self.signals.trip_requested
                    health.record_time_s = t - run_started if run_started is not None and not self._awaiting_table else math.nan
                    command = tick.run(t, dt, t, lateness, stall_s, missed, self.lockstep is None)
                    timing.add(lateness, tick.compute_s, tick.cpu_s)
                    if self.recorder_error is not None and not self._record_lost:
                        self._check_recorder(t)
                    run_started, armed_at, finished = self._phase(t, run_started, duration_s, armed_at)
                    self._update_status(t, run_started, duration_s, command, lateness)
                    self._gap_state = command.state  # the phase the next gap begins in
                    if tick_log is not None:
                        tick_log.note(t, dt, lateness, stall_s, missed, health.operator_stop, health.operator_trip,
                                      health.bus_gone)
                    trace.mark(PHASE)
                    k += 1
                    if finished and finished_at is None:
                        finished_at = t
                    if finished_at is not None and t - finished_at >= self.config.after_s:
                        break
            except ArmTimeout:
                raise  # nothing armed, nothing moved: the caller refuses the run
            except Exception as exc:  # noqa: BLE001 - a fault in the loop itself: trip, never leave mid-run silently
                tick.supervisor.report_exception(t, exc)
                tick.send_disable(t)
            except BaseException as exc:  # KeyboardInterrupt, SystemExit: latch the trip, so the final command says TRIPPED
                tick.supervisor.report_exception(t, exc)
                raise  # the finally below sends zero force with the drive disabled first
            ending = run_ending(tick.supervisor, self.signals.stop_requested)
        finally:
            tick.send_disable(self.scheduler.elapsed_s)
            self.signals.restore()
            restore_realtime(report)
        supervisor = tick.supervisor
        return LoopResult(
            outcome=ending.outcome,
            trip_reason=ending.reason,
            trip_detail=ending.detail,
            timing={**timing.summary(), "threads": threads, "missed_periods": self.counts.missed_periods,
                    "stalls": self.counts.stalls, "stalls_ridden_through": self.stalls_ridden_through,
                    "longest_stall_s": self.longest_stall_s, "stall_budget_s": self.max_stall_s,
                    "gaps_past_budget": self.gaps_past_budget,
                    "lockstep": self.lockstep is not None},
            realtime_report=report.lines,
            scheduling=report.scheduling.as_dict(),
            operator_stopped=self.signals.stop_requested,
            record_start_t_s=run_started,
            table_record=supervisor.table_record.summary(),
        )

    def _update_status(
        self, t: float, run_started: float | None, duration_s: float, command: SupervisedCommand, lateness_s: float
    ) -> None:
        """Write this tick into the shared status block (no allocation; text only when it changed).

        Parameters
        ----------
        t : float
            Loop time of the tick (s).
        run_started : float or None
            Loop time RUNNING began (s); None before.
        duration_s : float
            Seconds of record (s).
        command : SupervisedCommand
            The tick's command (state, force, trip reason).
        lateness_s : float
            The tick's wake-up lateness (s), for the console's percentiles.
        """
        status, tick, health = self.status, self.tick, self.tick.health
        status.state = command.state  # a State: stored as its code, read back as its name
        status.t_s = t
        status.run_t_s = 0.0 if run_started is None else t - run_started
        status.duration_s = duration_s
        status.stroke_m = tick.meas.sliding_displacement_m
        status.force_N = command.force_N
        status.sliding_variable = tick.controller.sliding_variable
        status.e2e_rejects = health.e2e_rejects
        status.error_frames = health.error_frames
        status.send_failures = health.send_failures
        status.stalls = self.counts.stalls
        status.gaps_past_budget = self.gaps_past_budget
        status.longest_stall_s = self.longest_stall_s
        status.missed_periods = self.counts.missed_periods
        status.last_event = tick.last_event
        status.trip_reason = command.trip_reason
        table = tick.supervisor.table_record
        status.table_verdict = table.verdict
        status.table_correlation, status.table_delay_s, status.table_amplitude_ratio, _ = table.latest_measures
        status.add_lateness(lateness_s)
