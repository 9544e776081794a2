"""The virtual rig: table, plant, sensors, actuator and drive served on the CAN bus.

Two ways to run (see :mod:`harness.rig` for the lockstep contract):

- real time: :meth:`VirtualRig.service` (called by the runner at the sensor rate
  with the wall clock) handles every waiting frame, advances the plant from its
  last time to ``now`` in physics sub-steps and publishes whatever is due;
- lockstep: each ACTUATOR_CMD frame is applied and advances the rig exactly one
  step period, after which the rig publishes TABLE_SENSORS, BASE_SENSORS,
  (STORY_DRIFTS, FLOOR_ACCELS every k-th step), ACTUATOR_STATUS and, last,
  RIG_STATUS with ``step_index`` = steps taken.

On the CAN FD protocol (``can.fd``) the four sensor messages go out as one SENSOR_SET frame,
every step in lockstep and at the sensor rate in real time.

Time: the rig's own time is an integer count of sub-steps; ``now`` (wall clock,
passed in) is used only for the drive watchdog, frame timestamps and, in real
time, to know how far to advance.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

import can
import numpy as np

from drivers import rig_reader
from drivers.protocol.codec import load_protocol
from drivers.protocol.protocol_values import DriveState, FaultCode, RigCommand
from drivers.rig_reader import RigReader
from drivers.writer import RigWriter
from harness.canbus.config import CanConfig
from harness.errors import ModelError
from harness.rig.actuator import make_actuator
from harness.rig.drive import Drive, ResetVerdict
from harness.rig.faults import (
    DRIVE_FAULT,
    ESTOP,
    MAX_EXTRA_DELAY_S,
    PRESSURE_LOST,
    SEIZE,
    FaultSet,
    schedule_from,
)
from harness.rig.history import History, record_columns
from harness.rig.journal import RigJournal
from harness.rig.parts import RigParts, RigState
from harness.rig.publish import RigPublisher
from harness.rig.runner import serve
from harness.rig.schedule import PublishSchedule
from harness.rig.sensors import SIGNALS, SensorModel
from harness.rig.table import TablePlant
from harness.safety.lifecycle import State

if TYPE_CHECKING:
    from drivers.link import RigLink
    from harness.motions import GroundMotion

#: HEARTBEAT state of a harness whose run has ended normally: the table it started is held
#: (``_stop_table_after_the_run``). Not TRIPPED: after a trip the profile's trip actions decide whether
#: the table stops (``stop_table``); a table controller does not stop on its own because the harness tripped.
RUN_ENDED_STATES = frozenset({int(State.DONE)})


class VirtualRig:
    """The 4-DOF rig on a CAN bus.

    Parameters
    ----------
    parts : RigParts
        The rig's true building, bearing and settings (:meth:`RigParts.from_profile` of a profile).
    motion : GroundMotion
        The processed record the table plays.
    bus_or_link : can.BusABC or RigLink
        An open bus (the rig builds its writer), or a link from
        :func:`drivers.link.open_rig` (its writer is used). Either way the rig receives
        through its own :class:`~drivers.rig_reader.RigReader` on the bus, timed by ``clock``.
    step_period_s : float
        The harness's control period (s); a whole multiple of the physics sub-step.
    lockstep : bool, optional
        Start in lockstep and stay there (RIG_CONTROL lockstep=0 does not leave it);
        default ``rig.lockstep`` of the profile.
    seed : int, optional
        Noise seed; default ``rig.seed``.
    clock : callable
        Wall clock (s) for the runner thread.
    can_config : CanConfig, optional
        Message rates (real time); defaults of :class:`~harness.canbus.config.CanConfig`.
    """

    def __init__(
        self,
        parts: RigParts,
        motion: GroundMotion,
        bus_or_link: can.BusABC | RigLink,
        *,
        step_period_s: float,
        lockstep: bool | None = None,
        seed: int | None = None,
        clock: Callable[[], float] = time.monotonic,
        can_config: CanConfig | None = None,
    ):
        if parts.building.n_stories != 3:
            raise ModelError(f"the rig protocol carries 3 stories; the building has {parts.building.n_stories}")
        self.config = cfg = parts.rig
        self.h = cfg.physics_substep_s
        self.n_sub = int(round(step_period_s / self.h))
        if self.n_sub < 1 or abs(self.n_sub * self.h - step_period_s) > 1e-9 * step_period_s:
            raise ModelError(f"step period {step_period_s} s is not a whole multiple of the physics sub-step {self.h} s")
        self.step_period_s = float(step_period_s)
        self.clock = clock
        can_settings = can_config or CanConfig()
        if isinstance(bus_or_link, can.BusABC):
            self.bus, protocol = bus_or_link, load_protocol(can_settings.dbc_path or None, fd=can_settings.fd)
            writer = RigWriter(self.bus, protocol)
        else:
            self.bus, protocol, writer = bus_or_link.bus, bus_or_link.protocol, bus_or_link.writer
        seeds = np.random.SeedSequence(cfg.seed if seed is None else seed).spawn(2)
        self._force_rng = np.random.default_rng(seeds[1])
        self.table = TablePlant(parts.building, parts.bearing, motion, parts.rtol, cfg)
        self.sensors = SensorModel(cfg.sensors, self.h, 3.0 + MAX_EXTRA_DELAY_S, np.random.default_rng(seeds[0]))
        self.actuator = make_actuator(cfg, self.h, self.table, seed)
        self.drive = Drive(cfg.drive.watchdog_timeout_s)
        self.faults = FaultSet(schedule_from(cfg.faults))
        self.publisher = RigPublisher(writer, self.faults, self.sensors)
        self.reader = RigReader(self.bus, protocol, clock)
        self.history = History(int(math.ceil(cfg.history_s / self.h)), self.table.y.size)
        self.schedule = PublishSchedule(can_settings, self.h, self.step_period_s)
        #: The emulated E-stop panel is plugged in and sends its heartbeat (tests unplug it).
        self.panel_connected = True
        #: The emulated panel's button is pressed (its frames then carry active=1).
        self.panel_pressed = False
        self._panel_period_s = 1.0 / can_settings.estop_panel_rate_hz
        self._panel_every_steps = max(1, int(round(self._panel_period_s / self.step_period_s)))
        self.pinned_lockstep = bool(cfg.lockstep if lockstep is None else lockstep)
        self.lockstep = self.pinned_lockstep
        self._truth = np.zeros(len(SIGNALS))
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop_event = threading.Event()
        self.error: BaseException | None = None
        #: Each state change, one line each, for a terminal that prints from its own thread (``harness rig``).
        self.journal = RigJournal()
        #: The latest DRIVE_RESET's verdict (None before the first).
        self.last_reset: ResetVerdict | None = None
        self._last_estop_frame_time = -math.inf
        self._measured_force_N = 0.0
        self._reset_rig()

    # ----------------------------------------------------------------- state
    def _reset_rig(self) -> None:
        self.table.reset()
        self.actuator.reset()
        self.drive.reset()
        self.history.clear()
        self.faults.reset_schedule()
        self.n = 0
        self.step_index = 0
        self.armed = False
        #: The last RIG_CONTROL start table was refused (the table already ran): RIG_STATUS ``start_refused``.
        self.start_refused = False
        self.force_N = 0.0
        self._t0: float | None = None
        #: When the real-time service last ran (s, wall clock); None before the first.
        self._last_service_s: float | None = None
        #: The latest time the drive's watchdog may judge now (s): the previous service while this one reads
        #: the frames that waited through the rig's own stall (:meth:`_watched_until`), else infinite.
        self._watched_to_s = math.inf
        #: Real-time services that came two sensor periods or more after the one before (the rig's own stalls).
        self.own_stalls = 0
        self._announce = self.lockstep
        self._last_drive_state = DriveState.OFF
        self._last_status_time = -math.inf
        self._last_panel_time = -math.inf
        self._panel_next_step = 0
        self._heard_harness = False
        self.journal.forget()
        self.table.truth(self._truth, 0.0)
        self.sensors.reset(self._truth)
        self._update_faults()
        self.schedule.reset(0)

    @property
    def rig_time_s(self) -> float:
        """Rig time (s): sub-steps taken times the sub-step."""
        return self.n * self.h

    @property
    def state(self) -> RigState:
        """A snapshot (see :class:`RigState`)."""
        return RigState(
            self.drive.state, self.drive.fault_code, self.pressure_ok, self.actuator.force_N, self.drive.command_N,
            self.rig_time_s, self.table.record_time_s, self.step_index, self.table.running, self.lockstep,
            self.faults.active_ids(), self.reader.frames,
        )

    @property
    def pressure_ok(self) -> bool:
        """Hydraulic pressure present (no pressure-lost fault)."""
        return not self.faults.is_on(PRESSURE_LOST)

    def _update_faults(self) -> None:
        self.faults.update(self.table.record_time_s if self.table.started else None)
        self.sensors.set_delays(self.faults.extra_delay_s, self.n_sub if self.lockstep else None)
        if self.table.can_seize:  # a force source on a motion-source table has no coupled plant to seize
            self.table.set_seized(self.faults.is_on(SEIZE))

    def _injected_drive_code(self) -> int:
        """The fault code of an injected drive fault present now (0: none)."""
        faults = self.faults
        if not faults.is_on(DRIVE_FAULT):
            return 0
        return int(min(max(faults.param[DRIVE_FAULT, 0], 0.0), 255.0)) or FaultCode.INJECTED

    def _update_drive(self, now: float) -> None:
        if self.faults.is_on(ESTOP):
            self.drive.on_estop()
        drive = self.config.drive
        self.drive.timeout_s = drive.lockstep_watchdog_timeout_s if self.lockstep else drive.watchdog_timeout_s
        self.drive.update(min(now, self._watched_to_s), self.pressure_ok, self._injected_drive_code())

    def _estop_asserted(self, now: float) -> bool:
        """An E-stop is asserted now: the rig's E-stop fault, the panel pressed, or an active ESTOP frame lately.

        "Lately": within the drive's watchdog timeout (an active stop is repeated at ``can.estop_rate_hz``).
        """
        return self.faults.is_on(ESTOP) or self.panel_pressed or now - self._last_estop_frame_time <= self.drive.timeout_s

    def _on_drive_reset(self, now: float) -> None:
        """A DRIVE_RESET frame: the drive judges it; the verdict is journalled and, in lockstep, announced at once."""
        self._update_faults()
        self._update_drive(now)
        acknowledged = int(self.reader.drive_reset[0])
        verdict = self.drive.request_reset(
            acknowledged, now, pressure_ok=self.pressure_ok, injected_code=self._injected_drive_code(),
            estop_asserted=self._estop_asserted(now),
        )
        self.last_reset = verdict
        self.journal.note(verdict.describe(acknowledged, self.drive.fault_code))
        if self.lockstep:  # the harness waits for the verdict before it arms: no step comes to carry it
            self._publish_status(now)
            self._last_drive_state = self.drive.state

    def _watch(self) -> None:
        """Journal what changed (drive, harness, table); a few comparisons unless something did."""
        drive, table = self.drive, self.table
        self.journal.watch(drive.state, drive.fault_code, drive.harness_state if self._heard_harness else None,
                           table.running, table.record_time_s)

    # --------------------------------------------------------------- physics
    def _substep(self) -> None:
        enabled = self.drive.enabled
        force = self.actuator.substep(self.drive.command_N, enabled)
        plant_input = self.actuator.plant_input(force)
        table = self.table
        t = self.n * self.h
        self.history.append(t, table.record_time_s if table.running else None, plant_input, table.y)
        table.advance(t, self.h, plant_input)
        self.n += 1
        self.force_N = force
        table.truth(self._truth, plant_input)
        self.sensors.push(self._truth)

    def _step(self, now: float) -> None:
        if self.armed:
            self.armed = False
            self.table.start()
            self.faults.reset_schedule()
        for _ in range(self.n_sub):
            self._substep()
        self.step_index += 1
        self._update_faults()
        self._update_drive(now)
        self._publish_lockstep(now)

    # ------------------------------------------------------------ publishing
    def _publish_lockstep(self, now: float) -> None:
        self._announce = False
        self._last_status_time = now
        pub = self.publisher
        pub.sensor_messages(now, True, self.step_index % self.schedule.story_every_steps == 0)
        self._publish_status(now)
        if self.faults.is_on(ESTOP):
            pub.estop(now)
        if self.step_index >= self._panel_next_step:  # on the step grid: ages are judged on the loop's time
            self._panel_next_step = self.step_index + self._panel_every_steps
            self._publish_panel(now)
        self._publish_rig_status(now)
        self._last_drive_state = self.drive.state

    def _publish_panel(self, now: float) -> None:
        """The emulated E-stop panel's frame (heartbeat, or a press), if it is plugged in."""
        if self.panel_connected:
            self._last_panel_time = now
            self.publisher.panel(now, self.panel_pressed)

    def _publish_status(self, now: float) -> None:
        noise = self.config.actuator.force_noise_N
        measured = self.actuator.force_N + (noise * float(self._force_rng.standard_normal()) if noise > 0 else 0.0)
        self._measured_force_N = measured
        self.publisher.status(measured, self.drive.state, self.pressure_ok, self.drive.fault_code, now)

    def _repeat_status(self, now: float) -> None:
        """ACTUATOR_STATUS again with the last measured force: the idle beacon draws no noise (lockstep stays
        deterministic however often the wall clock fires it)."""
        self.publisher.status(self._measured_force_N, self.drive.state, self.pressure_ok, self.drive.fault_code, now)

    def _publish_rig_status(self, now: float) -> None:
        table = self.table
        self.publisher.rig_status(
            table.running, self.lockstep, self.faults.any_active, min(table.record_time_s, 1677.0), self.step_index, now,
            self.start_refused,
        )

    def _publish_due(self, now: float) -> None:
        due = self.schedule.due(self.n)
        pub = self.publisher
        pub.sensor_messages(now, due.sensors, due.stories)
        if due.status:
            self._publish_status(now)
            if self.faults.is_on(ESTOP):
                pub.estop(now)
        if due.rig_status:
            self._publish_rig_status(now)

    # ---------------------------------------------------------------- frames
    def _on_control(self, now: float) -> None:
        command, lockstep, fault_id, fault_param = self.reader.control
        self.faults.inject(int(fault_id), float(fault_param))
        if bool(lockstep) != self.lockstep and not (self.pinned_lockstep and not lockstep):
            self.lockstep = bool(lockstep)
            self.step_index = 0
            self._t0 = None
            self._last_service_s = None  # real time starts watching afresh
        command = int(command)
        if command == RigCommand.RESET:
            self._reset_rig()
            self.journal.note("rig reset (RIG_CONTROL): plant at rest, every latch cleared, drive OFF")
        elif command == RigCommand.START_TABLE and (self.table.running or self.armed):
            # Answered, not ignored: RIG_STATUS start_refused until a stop, a reset or an accepted start.
            if not self.start_refused:
                self.journal.note(f"start table refused (RIG_CONTROL): the table already "
                                  f"{'runs' if self.table.running else 'is armed to start'}; stop it first")
            self.start_refused = True
        elif command == RigCommand.START_TABLE:
            self.start_refused = False
            if self.lockstep:
                self.armed = True
            else:
                self.table.start()
                self.faults.reset_schedule()
        elif command == RigCommand.STOP_TABLE:
            self.armed = False
            self.start_refused = False
            self.table.stop()
        self._update_faults()
        self._update_drive(now)
        if self.lockstep:  # entering lockstep, or a command in it: the harness sees the effect
            self._publish_lockstep(now)

    def _handle(self, kind: int, now: float) -> None:
        if kind == rig_reader.COMMAND:
            # Record the command before the watchdog judges: a frame that arrived is proof
            # the harness is alive, even when this rig was the one that stalled.
            enable, force = self.reader.command
            self.drive.on_command(bool(enable), force, now)
            self._update_drive(now)
            if self.lockstep:
                self._step(now)
        elif kind == rig_reader.HEARTBEAT:
            self._heard_harness = True
            self.drive.on_heartbeat(now, int(self.reader.heartbeat[0]))
            self._stop_table_after_the_run()
            self._update_drive(now)
        elif kind == rig_reader.CONTROL:
            self._on_control(now)
        elif kind == rig_reader.ESTOP:
            self._last_estop_frame_time = now
            self.drive.on_estop()
        elif kind == rig_reader.DRIVE_RESET:
            self._on_drive_reset(now)

    def _stop_table_after_the_run(self) -> None:
        """The harness's heartbeat says its run ended (DONE): hold the table it started.

        A table left running after its run would play on while the next harness waits idle, and
        that harness's start would find it running (RIG_STATUS ``start_refused``).
        """
        if (self.table.running or self.armed) and self.drive.harness_state in RUN_ENDED_STATES:
            self.armed = False
            self.table.stop()
            self.journal.note("table stopped: the harness's run ended")

    def _after_frames(self, now: float) -> None:
        self._update_faults()
        self._update_drive(now)
        if self._announce and self.lockstep:
            self._announce = False
            self._publish_lockstep(now)
        if self.lockstep and self.drive.state != self._last_drive_state:
            self._publish_status(now)  # a watchdog trip between steps is announced at once
            self._last_drive_state = self.drive.state
        if self.lockstep and now - self._last_status_time >= self.schedule.rig_status_period_s:
            self._last_status_time = now  # idle beacon: a harness that joins late still finds the rig and its drive
            self._repeat_status(now)
            self._publish_rig_status(now)
        if now - self._last_panel_time >= self._panel_period_s:  # the panel's own clock (idle lockstep too)
            self._publish_panel(now)

    def service(self, now: float, wait_s: float = 0.0) -> int:
        """In real time, advance to ``now`` and publish what is due; then handle the waiting frames.

        Real time advances first, so a frame received now acts from now on (never
        on the interval before it arrived). In lockstep the frames drive the steps.

        Parameters
        ----------
        now : float
            Wall-clock time (s), from the same clock as every other ``now``.
        wait_s : float
            Wait up to this long for the first frame (the lockstep thread's poll
            timeout); the frames are then handled at ``clock()``.

        Returns
        -------
        int
            Frames handled.
        """
        with self._lock:
            judged = self.drive.state
            if not self.lockstep:
                self._watched_to_s = self._watched_until(now)
                self._update_drive(now)
                judged = self.drive.state
                self._advance_to(now)
            handled = 0
            kind = self.reader.receive(wait_s)
            while kind != rig_reader.NOTHING:
                handled += 1
                self._handle(kind, now if wait_s == 0.0 else self.clock())
                self._watch()
                kind = self.reader.receive(0.0)
            if wait_s:
                now = self.clock()
            judged_late, self._watched_to_s = self._watched_to_s < now, math.inf
            self._after_frames(now)
            if judged_late and self.drive.state != judged:
                self._publish_status(now)  # judged late (after the rig's own stall): announced at once
            self._watch()
            return handled

    def _watched_until(self, now: float) -> float:
        """The latest time (s) the drive's watchdog may judge before this service reads its frames.

        The drive it emulates never stalls; this process can (a busy host, an emulator's stopped
        virtual CPU). After a gap of two sensor periods or more between services (a stall, as the
        loop counts one: :mod:`harness.signals.timing_counts`), the heartbeats and commands that
        arrived meanwhile still wait unread: judged at ``now`` before them (or as each is read, a
        command before the heartbeat behind it), the watchdog would latch HEARTBEAT_WATCHDOG on a
        harness that kept sending. Until every waiting frame is read it then judges only up to the
        previous service (the last moment it watched), and at ``now`` once they are
        (:meth:`_after_frames`), so a harness that really went silent still trips it in this
        service; the sub-steps of the stall run with the drive as last judged.
        """
        last, self._last_service_s = self._last_service_s, now
        if last is None or now - last < 2.0 * self.schedule.sensor_period_s:
            return now
        self.own_stalls += 1
        return last

    def _advance_to(self, now: float) -> None:
        """Sub-steps up to ``now``, then what is due, once (after a stall: no burst of old values)."""
        if self._t0 is None:
            self._t0 = now - self.n * self.h
        target = int((now - self._t0) / self.h + 1e-9)
        if target - self.n > self.schedule.max_catch_up:
            self.schedule.late_services += 1
        while self.n < target:
            self._substep()
        if self.schedule.any_due(self.n):
            self._update_faults()
            self._publish_due(now)

    def step_lockstep(self, force_N: float, enable: bool, now: float) -> None:
        """Apply one command and advance one step, as an ACTUATOR_CMD frame would (in-process)."""
        with self._lock:
            self._update_drive(now)
            self.drive.on_command(enable, force_N, now)
            self._step(now)
            self._watch()

    def announce(self, now: float) -> None:
        """Publish the lockstep set for the current step (what entering lockstep sends)."""
        with self._lock:
            self._publish_lockstep(now)

    def record_columns(self) -> dict[str, np.ndarray]:
        """Canonical run columns of the record run from the exact history (see :func:`.history.record_columns`)."""
        return record_columns(self.history, self.table.record, self.step_period_s)

    # --------------------------------------------------------------- thread
    def start_thread(
        self, poll_timeout_s: float = 0.002, sleep: Callable[[float], None] = time.sleep, fifo_priority: int | str = 0,
    ) -> None:
        """Serve the bus in a daemon thread (real time or lockstep, as commanded); ``fifo_priority`` as
        :func:`harness.rig.runner.serve` takes it.

        If the loop fails (e.g. the bus goes away) the thread ends and keeps the
        exception in :attr:`error`; :attr:`serving` turns False.
        """
        if self._thread is not None:
            return
        self._stop_event.clear()
        self._thread = threading.Thread(
            target=serve, args=(self, self._stop_event, poll_timeout_s, sleep, fifo_priority), name="virtual-rig", daemon=True
        )
        self._thread.start()

    @property
    def serving(self) -> bool:
        """True while the service thread runs."""
        return self._thread is not None and self._thread.is_alive()

    def stop(self, timeout_s: float = 2.0) -> None:
        """Stop the thread, disable the drive and announce it (one ACTUATOR_STATUS with drive OFF)."""
        self._stop_event.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
            self._thread = None
        with self._lock:
            self.drive.reset()
            self.actuator.reset()
            self._publish_status(self.clock())

