"""The control loop's run: ticks at a fixed rate (or in lockstep with a virtual rig) through the phases

    wait until every pre-arm check passes -> ARMED -> (settle) -> RUNNING for the record
    -> STOPPING (force ramps to zero) -> DONE, or TRIPPED (latched) at any point,

then a few more ticks with zero force and the drive disabled. The loop owns time: every
tick gets ``t`` and ``dt``; in real time from the absolute-deadline scheduler, in lockstep
as ``k * period`` once the rig reports step ``k``.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from harness.errors import SafetyError
from harness.loop.config import LoopConfig
from harness.loop.operator import OperatorSignals
from harness.loop.realtime import apply_realtime, restore_realtime
from harness.loop.scheduler import FixedRateScheduler
from harness.loop.tick import ControlTick
from harness.loop.timing import TimingStats
from harness.safety.lifecycle import State

_FINAL = (State.DONE, State.TRIPPED)


class ArmTimeout(SafetyError):
    """The pre-arm checks did not all pass within the arm timeout; ``failed`` lists them."""

    def __init__(self, failed: str, timeout_s: float):
        self.failed = failed
        super().__init__(f"could not arm within {timeout_s:g} s: {failed}")


@dataclass
class LoopStatus:
    """What the live console shows; the loop overwrites the fields in place every tick."""

    phase: str = "starting"
    state: str = "IDLE"
    t_s: float = 0.0
    run_t_s: float = 0.0
    duration_s: float = 0.0
    stroke_m: float = 0.0
    force_N: float = 0.0
    sliding_variable: float = 0.0
    overruns: int = 0
    e2e_rejects: int = 0
    error_frames: int = 0
    send_failures: int = 0
    last_event: str = ""
    trip_reason: str = ""


@dataclass
class LoopResult:
    """How the run ended and its timing."""

    outcome: str
    trip_reason: str = ""
    timing: dict = field(default_factory=dict)
    realtime_report: list[str] = field(default_factory=list)
    operator_stopped: bool = False
    record_start_t_s: float | None = None


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
    ):
        self.tick = tick
        self.config = config
        self.period_s = 1.0 / rate_hz
        self.duration_s = float(duration_s)
        span_s = config.arm_timeout_s + config.settle_s + self.duration_s + config.tail_s + config.after_s + 10.0
        self.timing = TimingStats(int(span_s / self.period_s) + 1000)
        self.lockstep = lockstep
        self.on_start = on_start or (lambda t: None)
        self.status = status or LoopStatus()
        self.scheduler = FixedRateScheduler(self.period_s, config.spin_s, clock=clock)
        self.signals = OperatorSignals()

    def _phase(self, t: float, run_started: float | None, duration_s: float, armed_at: float | None):
        """Advance the phases after a tick; returns (run_started, armed_at, finished)."""
        supervisor = self.tick.supervisor
        state = supervisor.state
        if state is State.IDLE:
            if self.signals.stop_requested or self.signals.trip_requested:
                return run_started, armed_at, True
            try:
                supervisor.arm(t, self.tick.health)
                armed_at = t
            except SafetyError as err:
                if t >= self.config.arm_timeout_s:
                    raise ArmTimeout(str(err), self.config.arm_timeout_s) from err
        elif state is State.ARMED and t - armed_at >= self.config.settle_s:
            supervisor.start(t)
            run_started = t
            self.on_start(t)
        elif state is State.RUNNING and t - run_started >= duration_s + self.config.tail_s:
            supervisor.stop(t, "record finished")
        return run_started, armed_at, state in _FINAL

    def _wait(self, k: int) -> tuple[float, float]:
        """Wait for tick ``k``; return (t, lateness)."""
        if self.lockstep is None:
            t = self.scheduler.wait()
            return t, self.scheduler.lateness_s
        if not self.lockstep(k, self.config.lockstep_timeout_s):
            self.tick.health.bus_gone = True  # the rig stopped answering: trips as bus_gone
        return k * self.period_s, 0.0

    def run(self) -> LoopResult:
        """Run the whole test: arm, settle, the record, the tail, the ramp-down."""
        duration_s = self.duration_s
        timing = self.timing
        report = apply_realtime(self.config.realtime)
        tick, health = self.tick, self.tick.health
        run_started = armed_at = None
        finished_at = None
        outcome = "error"
        self.signals.install()
        try:
            self.scheduler.start()
            k = 0
            previous_t = -self.period_s
            while True:
                t, lateness = self._wait(k)
                dt = t - previous_t  # a whole period, or more after deadlines were skipped
                previous_t = t
                health.operator_stop = self.signals.stop_requested
                health.operator_trip = self.signals.trip_requested
                started, cpu_started = time.perf_counter(), time.thread_time()
                command = tick.run(t, dt, t, lateness, self.scheduler.consecutive_overruns, self.lockstep is None)
                timing.add(lateness, time.perf_counter() - started, time.thread_time() - cpu_started)
                run_started, armed_at, finished = self._phase(t, run_started, duration_s, armed_at)
                self._update_status(t, run_started, duration_s, command)
                k += 1
                if finished and finished_at is None:
                    finished_at = t
                if finished_at is not None and t - finished_at >= self.config.after_s:
                    break
            state = tick.supervisor.state
            outcome = {State.DONE: "completed", State.TRIPPED: "tripped"}.get(state, "stopped")
            if outcome == "completed" and self.signals.stop_requested:
                outcome = "stopped"
        finally:
            tick.send_disable(self.scheduler.elapsed_s)
            self.signals.restore()
            restore_realtime(report)
            timing.overruns = self.scheduler.overruns
        return LoopResult(
            outcome=outcome,
            trip_reason=tick.supervisor.command.trip_reason,
            timing=timing.summary(),
            realtime_report=report.lines,
            operator_stopped=self.signals.stop_requested,
            record_start_t_s=run_started,
        )

    def _update_status(self, t: float, run_started: float | None, duration_s: float, command) -> None:
        status, tick = self.status, self.tick
        status.state = command.state.name
        status.t_s = t
        status.run_t_s = 0.0 if run_started is None else t - run_started
        status.duration_s = duration_s
        status.stroke_m = tick.meas.sliding_displacement_m
        status.force_N = command.force_N
        status.sliding_variable = tick.controller.sliding_variable
        status.overruns = self.scheduler.overruns
        status.e2e_rejects = tick.health.e2e_rejects
        status.error_frames = tick.health.error_frames
        status.send_failures = tick.health.send_failures
        status.last_event = tick.last_event
        status.trip_reason = command.trip_reason
