"""One tick of the control loop: read -> estimate -> control -> compensate -> supervise -> write -> record.

The estimate -> control -> compensate -> supervise part is :func:`harness.loop.step.control_step`, the one
step the rig twin and the ideal simulator also run.

Everything the tick touches is allocated before the run: the measurement record, the
health record, the row, the drivers' frames and samples. Controllers, the estimator
and the supervisor get the loop's ``t`` and ``dt``; nothing here reads a clock except
through the ``now`` it is given. An exception from the estimator or the controller
trips the run (zero force, drive disabled) and never escapes with the drive enabled.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

import numpy as np

from harness.control.compensation import Compensator, NoCompensation
from harness.control.controllers import Controller
from harness.control.estimator import FrictionEstimator
from harness.errors import EXPECTED_ERRORS
from harness.loop.step import StepValues, control_step
from harness.loop.timing import READ, RECORD, SUPERVISE, WRITE, GapTrace
from harness.loop.trip_outputs import TripOutputs
from harness.realtime.memory import float_view
from harness.safety.checks import bit
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import SupervisedCommand, Supervisor
from harness.signals import columns as layout

if TYPE_CHECKING:
    from drivers.link import HarnessLink
    from harness.loop.status import LoopStatus

# Positions in the row (harness.signals.columns.CONTROL_ROW) of what the tick records, looked up by
# name once, at import. Module constants: a store through one costs what a literal index costs
# (a global load), less than through an instance attribute.
_AT = layout.CONTROL_ROW_INDEX
_T = _AT[layout.TIME]
_STATE = _AT[layout.STATE]
_TABLE_DISPLACEMENT = _AT[layout.TABLE_DISPLACEMENT]
_TABLE_VELOCITY = _AT[layout.TABLE_VELOCITY]
_TABLE_ACCELERATION = _AT[layout.TABLE_ACCELERATION]
_BASE_DISPLACEMENT = _AT[layout.BASE_DISPLACEMENT]
_BASE_VELOCITY = _AT[layout.BASE_VELOCITY]
_BASE_ACCELERATION = _AT[layout.BASE_ACCELERATION]
_SLIDING_DISPLACEMENT = _AT[layout.SLIDING_DISPLACEMENT]
_SLIDING_VELOCITY = _AT[layout.SLIDING_VELOCITY]
_ESTIMATED_NU = _AT[layout.ESTIMATED_NU]
_FRICTION_ESTIMATE = _AT[layout.FRICTION_ESTIMATE]
_SLIDING_VARIABLE = _AT[layout.SLIDING_VARIABLE]
_EQUIVALENT_FORCE = _AT[layout.EQUIVALENT_FORCE]
_FORCE_RAW = _AT[layout.FORCE_RAW]
_FORCE_COMMAND = _AT[layout.FORCE_COMMAND]
_DRIVE_ENABLED = _AT[layout.DRIVE_ENABLED]
_FORCE_MEASURED = _AT[layout.FORCE_MEASURED]
_DRIVE_STATE = _AT[layout.DRIVE_STATE]
_INTERLOCK_FLAGS = _AT[layout.INTERLOCK_FLAGS]
_LATENESS = _AT[layout.LATENESS]
_COMPUTE = _AT[layout.COMPUTE]
_OVERRUN = _AT[layout.OVERRUN]
_E2E_REJECTS = _AT[layout.E2E_REJECTS]
_ERROR_FRAMES = _AT[layout.ERROR_FRAMES]
_SEND_FAILURES = _AT[layout.SEND_FAILURES]
#: The checks whose safe stop stops the table too: it plays another record than the one the harness was told.
_STOPS_THE_TABLE = bit("table_record_mismatch")


class TickRecorder(Protocol):
    """Where the tick records its row and the supervisor's events (a :class:`~harness.recording.runfolder.RunFolder`)."""

    def record_row(self, values: np.ndarray) -> object:
        """Queue one row; never blocks."""
        ...

    def record_event(self, t: float, kind: str, name: str, detail: str) -> object:
        """Queue one event; never blocks."""
        ...


class ControlTick:
    """The work of one tick, wired once to the link, controller, estimator, supervisor and recorder.

    Parameters
    ----------
    link : drivers.link.HarnessLink
        Reader (polls the bus itself) and writer of the harness side.
    controller : Controller
        ``update(t, dt, meas, friction_N, state) -> force`` with visible internals.
    estimator : FrictionEstimator
    supervisor : Supervisor
    recorder : TickRecorder, optional
        Has ``record_row(row)`` and ``record_event(t, kind, name, detail)`` (a RunFolder).
    heartbeat_every : int
        Send the heartbeat every this many ticks.
    estop_every : int
        While TRIPPED with the ``estop`` trip action, repeat the ESTOP frame every this many ticks
        (loop rate / ``can.estop_rate_hz``).
    stop_table : callable, optional
        ``stop_table(now)``: the table controller's stop (RIG_CONTROL stop), for the ``stop_table``
        trip action and the safe stop of ``table_record_mismatch``; None when the run has no table link.
    compensator : Compensator, optional
        Turns the controller's force into the command the supervisor shapes and supervises
        (``control.compensation``, harness/control/compensation.py); default none (the force as is).
        Its health flags reach the supervisor's ``compensation_fault`` check through the tick's health.
    """

    def __init__(
        self,
        link: HarnessLink,
        controller: Controller,
        estimator: FrictionEstimator,
        supervisor: Supervisor,
        recorder: TickRecorder | None = None,
        heartbeat_every: int = 5,
        estop_every: int = 5,
        stop_table: Callable[[float], object] | None = None,
        compensator: Compensator | None = None,
    ):
        self.reader = link.reader
        self.writer = link.writer
        self.bus_health = link.reader.health
        self.controller = controller
        self.compensator: Compensator = NoCompensation() if compensator is None else compensator
        self.estimator = estimator
        self.supervisor = supervisor
        self.recorder = recorder
        self.health = TickHealth()
        self.meas = self.health.meas
        self.row = np.zeros(len(layout.CONTROL_ROW))
        self._row_mv = float_view(self.row)  # the tick writes through it: a third of a numpy item store
        self.heartbeat_every = max(1, int(heartbeat_every))
        self.ticks = 0
        #: Times the zero, disabled command could not be sent (the drive watchdog is then the backstop).
        self.disable_failures = 0
        self.last_event = ""
        #: The latest tick's compute time (s, wall clock) and the CPU time of the thread that ran it (s): from
        #: the start of :meth:`run` until its command is sent and its events are handed on. The row's
        #: ``compute_s`` column and the loop's timing statistics both take this one measurement.
        self.compute_s = 0.0
        self.cpu_s = 0.0
        #: When each part of the latest tick ended (the loop gives it its own clock): where a long gap went.
        self.trace = GapTrace()
        self.command: SupervisedCommand = supervisor.command
        #: The friction and controller force of the latest tick's :func:`~harness.loop.step.control_step`, overwritten.
        self.step = StepValues()
        reader = self.reader
        self._table, self._base, self._status = reader.table, reader.base, reader.status
        self._drifts, self._accels = reader.sample("STORY_DRIFTS"), reader.sample("FLOOR_ACCELS")
        self._xdd0 = self._table.index("xddot_0")
        self._yddb = self._base.index("yddot_b")
        self._story_slots = self._story_row_slots()
        #: The live console's status block, if any (:meth:`attach_status`): stories, fault code and event lines.
        self.status: LoopStatus | None = None
        self._status_stories = tuple(
            (j - 1, self._drifts.values, self._drifts.index(f"drift_{j}"), self._accels.values, self._accels.index(f"accel_{j}"))
            for j in range(1, layout.PROTOCOL_STORIES + 1)
        )
        self._sink: Callable[[float, str, str, str], None] = self._record_event if recorder is not None else self._keep_event
        #: The trip's ESTOP frame and table stop (safety.trip_actions), sent after the disable command.
        self.trip_outputs = TripOutputs(link.writer, supervisor.config.trip_actions, estop_every, stop_table)

    # ------------------------------------------------------------------ read
    def read(self, now: float, stall_s: float = 0.0, missed_periods: int = 0, poll: bool = True) -> None:
        """Poll the bus (unless the caller already did this tick) and update the records in place."""
        health = self.health
        if poll:
            try:
                self.reader.poll(now)
            except EXPECTED_ERRORS:
                health.bus_gone = True
        self.reader.fill(self.meas)
        table, base, status = self._table, self._base, self._status
        health.table_fresh = table.fresh
        health.base_fresh = base.fresh
        health.table_age_s = table.age(now)
        health.base_age_s = base.age(now)
        health.e2e_ok = self.reader.e2e_ok()
        health.e2e_rejects = self.reader.e2e_rejects
        bus = self.bus_health
        health.error_frames = bus.error_frames
        health.error_passive = bus.error_passive
        health.bus_off = bus.bus_off
        health.send_failures = bus.send_failures
        health.foreign_command = self.reader.foreign_command_seen
        health.drive_ready = self.reader.drive_ready
        health.drive_fault = self.reader.drive_fault
        health.drive_fault_code = self.reader.fault_code
        health.pressure_ok = self.reader.pressure_ok
        health.actuator_status_age_s = status.age(now)
        health.actuator_status_fresh = status.fresh
        # the load cell: the supervisor's tracking check, and the actuator-aware designs' force state
        self.meas.actuator_force_N = health.measured_force_N = self.reader.measured_force_n
        health.estop = self.reader.estop_requested
        health.estop_panel_age_s = self.reader.panel_age(now)
        health.stall_s = stall_s
        health.missed_periods = missed_periods

    # ------------------------------------------------------------------ the tick
    def run(
        self, t: float, dt: float, now: float, lateness_s: float = 0.0, stall_s: float = 0.0, missed_periods: int = 0,
        poll: bool = True,
    ) -> SupervisedCommand:
        """Run one tick at loop time ``t`` (s) with step ``dt`` (s); ``now`` is the drivers' clock (s).

        ``stall_s`` is the time since the previous tick's command (s; 0 in lockstep) and
        ``missed_periods`` the deadlines skipped before this tick. The bus is polled first,
        so sample ages are judged on what arrived while the loop was away.
        ``poll=False`` when the caller has already polled the bus this tick (lockstep).
        """
        started, cpu_started = time.perf_counter(), time.thread_time()
        supervisor, trace = self.supervisor, self.trace
        friction = raw = math.nan
        try:
            self.read(now, stall_s, missed_periods, poll)
        except Exception as exc:  # noqa: BLE001 - any failure in the tick trips; it never kills the process
            command = supervisor.report_exception(t, exc)
        else:
            trace.mark(READ)
            step = self.step  # estimate -> control (marks CONTROL) -> compensate -> supervise; an exception trips
            command = control_step(t, dt, self.health, self.estimator, self.controller, self.compensator, supervisor, step,
                                   trace=trace)
            friction, raw = step.friction_N, step.raw_N
        trace.mark(SUPERVISE)
        self.write(t, command, now)
        trace.mark(WRITE)
        self.ticks += 1
        try:
            try:
                supervisor.events.drain(self._sink)
            finally:  # the tick's work is done: its command is out and its events are handed on
                self.compute_s = time.perf_counter() - started
                self.cpu_s = time.thread_time() - cpu_started
            self._fill_row(t, command, friction, raw, lateness_s, self.compute_s, missed_periods)
            if self.recorder is not None:
                self.recorder.record_row(self.row)
            if self.status is not None:
                self.publish(self.status)
        except Exception as exc:  # noqa: BLE001 - a fault in our own recording code: trip now, zero sent at once
            command = supervisor.report_exception(t, exc)
            self.send_disable(now)
        trace.mark(RECORD)
        return command

    def write(self, t: float, command: SupervisedCommand, now: float) -> None:
        """Send the supervised command (the only path to the actuator) and the heartbeat; never raises.

        A value the DBC cannot carry, or any other failure to encode or send, trips the run
        (``tick_exception``) and zero force with the drive disabled is sent instead.
        """
        try:
            self.writer.command(command.force_N, command.enable, now)
            if self.ticks % self.heartbeat_every == 0:
                self.writer.heartbeat(int(command.state), now)
        except Exception as exc:  # noqa: BLE001 - never send it, trip instead
            self.supervisor.report_exception(t, exc)
            self.send_disable(now)
            return
        self.trip_outputs.update(command.state, command.trip_reason, now)  # after the disable command, same tick
        if command.acted & _STOPS_THE_TABLE:
            self.trip_outputs.stop_the_table(now)  # once: the table plays the wrong record while the force ramps down

    def send_disable(self, now: float) -> None:
        """Command zero force with the drive disabled, whatever the state (on a trip and on the way out); never raises."""
        try:
            self.writer.command(0.0, False, now)
            self.writer.heartbeat(int(self.supervisor.state), now)
        except Exception:  # noqa: BLE001 - nothing more can be sent; the drive watchdog is the backstop
            self.disable_failures += 1
        supervisor = self.supervisor
        self.trip_outputs.update(supervisor.state, supervisor.command.trip_reason, now)

    # ------------------------------------------------------------------ record
    def _story_row_slots(self) -> tuple[tuple[int, list[float], int], ...]:
        """``(row position, decoded values, position in them)`` of every story column of the row.

        The reader updates the story messages' value lists in place, so holding them is safe;
        the tick copies each story value through this table, with no lookup by name.
        """
        drifts, accels = self._drifts, self._accels
        stories = range(1, layout.PROTOCOL_STORIES + 1)
        return (
            *((_AT[layout.drift(j)], drifts.values, drifts.index(f"drift_{j}")) for j in stories),
            *((_AT[layout.floor_acceleration(j)], accels.values, accels.index(f"accel_{j}")) for j in stories),
        )

    def _fill_row(
        self, t: float, command: SupervisedCommand, friction: float, raw: float, lateness: float, compute: float, overrun: int
    ) -> None:
        """Write this tick's values into the row: one store per column, through the named positions."""
        row, meas, health, controller = self._row_mv, self.meas, self.health, self.controller
        row[_T] = t
        row[_STATE] = int(command.state)
        row[_TABLE_DISPLACEMENT] = meas.table_displacement_m
        row[_TABLE_VELOCITY] = meas.table_velocity_m_s
        row[_TABLE_ACCELERATION] = self._table.values[self._xdd0]
        row[_BASE_DISPLACEMENT] = meas.base_displacement_m
        row[_BASE_VELOCITY] = meas.base_velocity_m_s
        row[_BASE_ACCELERATION] = self._base.values[self._yddb]
        row[_SLIDING_DISPLACEMENT] = meas.sliding_displacement_m
        row[_SLIDING_VELOCITY] = meas.sliding_velocity_m_s
        for slot, values, i in self._story_slots:
            row[slot] = values[i]
        row[_ESTIMATED_NU] = self.estimator.nu
        row[_FRICTION_ESTIMATE] = friction
        row[_SLIDING_VARIABLE] = controller.sliding_variable
        row[_EQUIVALENT_FORCE] = controller.equivalent_force_N
        row[_FORCE_RAW] = raw
        row[_FORCE_COMMAND] = command.force_N
        row[_DRIVE_ENABLED] = 1.0 if command.enable else 0.0
        row[_FORCE_MEASURED] = health.measured_force_N
        row[_DRIVE_STATE] = self.reader.drive_state
        row[_INTERLOCK_FLAGS] = command.acted
        row[_LATENESS] = lateness
        row[_COMPUTE] = compute
        row[_OVERRUN] = overrun  # deadlines missed before this tick
        row[_E2E_REJECTS] = health.e2e_rejects
        row[_ERROR_FRAMES] = health.error_frames
        row[_SEND_FAILURES] = health.send_failures

    def attach_status(self, status: LoopStatus) -> None:
        """Publish into the live console's status block from now on: story drifts and floor accelerations,
        the servo's fault code (every tick, no allocation) and a line per event."""
        status.n_stories = layout.PROTOCOL_STORIES
        self.status = status

    def publish(self, status: LoopStatus) -> None:
        """Copy the latest story drifts (m), floor accelerations (m/s^2) and fault code into ``status`` (cell stores)."""
        for index, drifts, drift_at, accels, accel_at in self._status_stories:
            status.set_story(index, drifts[drift_at], accels[accel_at])
        status.fault_code = self.reader.fault_code

    def _record_event(self, t: float, kind: str, name: str, detail: str) -> None:
        self.last_event = f"{t:8.3f} s  {kind} {name}: {detail}"
        if self.status is not None:
            self.status.add_event(self.last_event)
        recorder = self.recorder
        assert recorder is not None, "the event sink when the tick was given a recorder"  # per event, not per tick
        recorder.record_event(t, kind, name, detail)

    def _keep_event(self, t: float, kind: str, name: str, detail: str) -> None:
        self.last_event = f"{t:8.3f} s  {kind} {name}: {detail}"
        if self.status is not None:
            self.status.add_event(self.last_event)

    @property
    def state(self) -> State:
        """The supervisor's lifecycle state."""
        return self.supervisor.state
