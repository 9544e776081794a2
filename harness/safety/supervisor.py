"""The safety supervisor: the only producer of the command the actuator writer accepts.

The loop calls :meth:`Supervisor.update` once per tick, between the controller
and the actuator write, with the loop's time ``t`` and step ``dt`` (s), the
preallocated :class:`~harness.safety.health.TickHealth` and the controller's raw
force. It returns the same preallocated :class:`SupervisedCommand` every tick.

The checks run in the fixed order of :data:`harness.safety.checks.CHECKS` (in ARMED, RUNNING
and STOPPING; the first TRIP wins and is latched as the reason, later checks are not evaluated
on that tick): the loop's time, then every detector (operator, stalls, sensors, CAN, actuator and
the force's oscillation, the table against its record), then the controller's output and the
stroke trips, then the force shaping (clamp, stopping ramp, rate limit, stroke fade). STOPPING becomes DONE on the
first tick at or after the ramp time whose shaped force is exactly zero (at once if the stop
came from ARMED, where no force was applied).

The stroke fade comes after the rate limit: a fade may cut an outward force
towards zero faster than the rate limit (as a trip does), but the force never
grows faster than the rate limit, and never pushes outward beyond
``soft_limit_m + fade_band_m``. In IDLE and DONE only ``estop`` and
``operator_trip`` are watched (they latch TRIPPED, which blocks arming until reset);
in every state but ARMED, RUNNING and STOPPING the command is force 0, enable False.
"""

from __future__ import annotations

import math
from typing import TypeVar

from harness.errors import ProfileError
from harness.safety.actuator_detectors import ForceTracking
from harness.safety.checks import CHECK_NAMES, bit, build_detectors, index
from harness.safety.config import SafetyConfig, check_config
from harness.safety.detector_base import TIME_EPS_S, Detector
from harness.safety.events import Action, EventKind, EventRing
from harness.safety.health import TickHealth
from harness.safety.interlocks import (
    ForceClamp,
    ForceRateLimit,
    StrokeHardLimit,
    StrokePredictiveLimit,
    StrokeSoftFade,
)
from harness.safety.lifecycle import DRIVE_STATES, Lifecycle, State
from harness.safety.operator_detectors import EStop, OperatorStop, OperatorTrip
from harness.safety.oscillation_detectors import ForceOscillation
from harness.safety.prearm import pre_arm_failures
from harness.safety.supervisor_checks import ControllerOutput, LoopTiming, StopRamp, TickException
from harness.safety.table_record import TableRecordCheck

_D = TypeVar("_D", bound=Detector)

_SLOT = {name: k for k, name in enumerate(CHECK_NAMES)}
_B_CLAMP, _B_RATE, _B_SOFT = bit(ForceClamp.NAME), bit(ForceRateLimit.NAME), bit(StrokeSoftFade.NAME)
_B_RAMP = bit(StopRamp.NAME)
_I_CLAMP, _I_RATE, _I_SOFT, _I_RAMP = (
    index(ForceClamp.NAME), index(ForceRateLimit.NAME), index(StrokeSoftFade.NAME), index(StopRamp.NAME)
)


class SupervisedCommand:
    """The command for the actuator writer; one preallocated object, overwritten every tick.

    Attributes
    ----------
    t : float
        Loop time of the tick that produced it (s).
    force_N : float
        Force to command (N); 0 whenever ``enable`` is False.
    enable : bool
        Drive enable; True only in ARMED, RUNNING and STOPPING.
    state : State
        Lifecycle state after this tick.
    acted : int
        Bit flags (:func:`harness.safety.events.bit`) of every check that acted this tick.
    trip_reason : str
        Name of the latched trip reason ("" if not tripped).
    """

    __slots__ = ("t", "force_N", "enable", "state", "acted", "trip_reason")

    def __init__(self) -> None:
        self.t = 0.0
        self.force_N = 0.0
        self.enable = False
        self.state = State.IDLE
        self.acted = 0
        self.trip_reason = ""


class Supervisor:
    """Interlocks, detectors and the lifecycle; clock-free, no I/O, no per-tick allocation.

    Parameters
    ----------
    config : SafetyConfig
        Must pass :func:`~harness.safety.config.check_config`.
    period_s : float, optional
        The loop's nominal tick period (s). The force-rate limit then allows at most
        ``max_force_rate_N_per_s * period_s`` per tick, even on the tick after a stall
        whose ``dt`` is longer (docs/SAFETY.md, "Stall budget"). None: ``dt`` (offline
        simulation, where every step is one period).

    Raises
    ------
    ProfileError
        If the configuration is inconsistent (every problem listed).

    Attributes
    ----------
    command : SupervisedCommand
        The object :meth:`update` returns.
    events : EventRing
        Events since the loop last drained them.
    act_ticks : list of int
        Per check (index as in :data:`~harness.safety.events.CHECK_NAMES`), ticks it acted on.
    """

    __slots__ = (
        "config", "lifecycle", "command", "events", "act_ticks", "soft", "hard", "predictive", "clamp", "rate",
        "tracking", "oscillation", "_estop", "_operator_trip", "detectors", "_bits", "_slots", "_previous_N", "_ramp_gain",
        "_last_acted", "period_s", "table_record", "stop_reason", "stop_detail", "_ramp_detail",
    )

    def __init__(self, config: SafetyConfig, period_s: float | None = None) -> None:
        problems = check_config(config)
        if problems:
            raise ProfileError("inconsistent safety configuration: " + "; ".join(problems), key_path="safety")
        self.config = config
        self.period_s = math.inf if period_s is None else float(period_s)
        self.lifecycle = Lifecycle()
        self.command = SupervisedCommand()
        self.events = EventRing(config.run.event_capacity)
        self.act_ticks = [0] * len(CHECK_NAMES)
        self.soft = StrokeSoftFade(config.stroke)
        self.hard = StrokeHardLimit(config.stroke)
        self.predictive = StrokePredictiveLimit(config.stroke)
        self.clamp = ForceClamp(config.force)
        self.rate = ForceRateLimit(config.force)
        #: The table against its record (:meth:`TableRecordCheck.expect` before the run; off until then).
        self.table_record = TableRecordCheck(config.run.max_stall_s)
        #: The check whose safe stop ended the run, and what it saw ("" when none did: the record's end, the operator).
        self.stop_reason = ""
        self.stop_detail = ""
        #: The detectors, in the order of :data:`harness.safety.checks.CHECKS`.
        self.detectors: tuple[Detector, ...] = build_detectors(config, self.table_record)
        self.tracking = self._detector(ForceTracking)
        self.oscillation = self._detector(ForceOscillation)
        self._estop, self._operator_trip = self._detector(EStop), self._detector(OperatorTrip)
        self._bits = tuple(bit(d.NAME) for d in self.detectors)
        self._slots = tuple(index(d.NAME) for d in self.detectors)
        self._previous_N = 0.0
        self._ramp_gain = 0.0
        self._last_acted = 0
        #: The stopping ramp's event detail (fixed: built once here, not in a tick).
        self._ramp_detail = (f"force ramps to zero over {config.run.stopping_ramp_s:g} s (safety.run.stopping_ramp_s), "
                             "then the drive is disabled")

    def _detector(self, kind: type[_D]) -> _D:
        """The detector of class ``kind`` (:data:`~harness.safety.checks.CHECKS` holds each class once)."""
        for detector in self.detectors:
            if isinstance(detector, kind):
                return detector
        raise LookupError(f"the supervisor has no {kind.__name__} detector; expected one in harness.safety.checks.CHECKS")

    # ---------------------------------------------------------------- lifecycle requests

    @property
    def state(self) -> State:
        """Current lifecycle state."""
        return self.lifecycle.state

    @property
    def trip_detail(self) -> str:
        """What the latched trip reason saw ("" if not tripped)."""
        return self.lifecycle.trip_detail

    def act_counts(self) -> dict[str, int]:
        """Ticks each check acted on, by name (non-zero only; allocates: for reports, not per tick)."""
        return {name: n for name, n in zip(CHECK_NAMES, self.act_ticks, strict=True) if n}

    def _state_event(self, t: float, before: State, why: str) -> None:
        after = self.lifecycle.state
        self.events.push(t, EventKind.STATE, after.name, f"{before.name} -> {after.name}: {why}")
        self.command.state = after
        self.command.trip_reason = self.lifecycle.trip_reason

    def _clear_history(self) -> None:
        for detector in self.detectors:
            detector.reset()
        self._previous_N = 0.0
        self._last_acted = 0
        self.stop_reason = ""
        self.stop_detail = ""

    def arm(self, t: float, health: TickHealth) -> None:
        """IDLE -> ARMED if every pre-arm check passes.

        Raises
        ------
        ArmRefused
            Listing every failed check (see :data:`~harness.safety.prearm.PRE_ARM_CHECKS`).
        IllegalTransition
            If not IDLE.
        """
        before = self.lifecycle.state
        self.lifecycle.arm(t, pre_arm_failures(self.config, health) if before is State.IDLE else ())
        self._clear_history()
        self._state_event(t, before, "armed: all pre-arm checks passed")

    def start(self, t: float) -> None:
        """ARMED -> RUNNING. Raises IllegalTransition otherwise."""
        before = self.lifecycle.state
        self.lifecycle.start(t)
        self._state_event(t, before, "start")

    def stop(self, t: float, why: str = "stop requested") -> None:
        """ARMED/RUNNING -> STOPPING: ramp the force to zero over ``stopping_ramp_s``, then DONE."""
        before = self.lifecycle.state
        self.lifecycle.stop(t)
        self._ramp_gain = 1.0 if before is State.RUNNING else 0.0
        self._state_event(t, before, why)

    def trip(self, t: float, reason: str, detail: str = "") -> SupervisedCommand:
        """Latch TRIPPED with ``reason`` (a name from CHECK_NAMES); return the zero, disabled command.

        Never raises: an unknown ``reason`` is latched as given, without a counter or flag.
        """
        before = self.lifecycle.state
        if self.lifecycle.trip(t, reason, detail):
            slot = _SLOT.get(reason)
            if slot is not None:
                self.act_ticks[slot] += 1
                self.command.acted |= 1 << slot
            self.events.push(t, EventKind.FAULT, reason, detail)
            self._state_event(t, before, reason)
        return self._off(t)

    def report_exception(self, t: float, exc: BaseException) -> SupervisedCommand:
        """The loop caught ``exc`` in a tick: trip with reason ``tick_exception``."""
        return self.trip(t, TickException.NAME, f"{type(exc).__name__}: {exc}")

    def _still_present(self, health: TickHealth) -> str:
        reason = self.lifecycle.trip_reason
        meas = health.meas
        if reason == StrokeHardLimit.NAME and self.hard.check(meas.sliding_displacement_m):
            return self.hard.detail(meas.sliding_displacement_m)
        if reason == StrokePredictiveLimit.NAME and self.predictive.check(meas.sliding_displacement_m, meas.sliding_velocity_m_s):
            return self.predictive.detail(meas.sliding_displacement_m, meas.sliding_velocity_m_s)
        for detector in self.detectors:
            if detector.NAME == reason:
                return detector.present(health)
        return ""

    def reset(self, t: float, health: TickHealth) -> None:
        """TRIPPED or DONE -> IDLE, clearing the latch and all detector history.

        Raises
        ------
        ResetRefused
            If the trip condition is still visible in ``health``.
        IllegalTransition
            From any other state.
        """
        before = self.lifecycle.state
        self.lifecycle.reset(t, self._still_present(health))  # "" from DONE: no trip reason latched
        self._clear_history()
        self._state_event(t, before, "reset")
        self._off(t)

    # ---------------------------------------------------------------- the tick

    def _off(self, t: float) -> SupervisedCommand:
        command = self.command
        command.t = t
        command.force_N = 0.0
        command.enable = False
        command.state = self.lifecycle.state
        command.trip_reason = self.lifecycle.trip_reason
        self._previous_N = 0.0
        self.tracking.command_N = 0.0
        self.oscillation.command_N = 0.0
        return command

    def _count(self, slot: int, flag: int) -> bool:
        """Count an acting check; True on its rising edge (an event is due)."""
        self.act_ticks[slot] += 1
        self.command.acted |= flag
        return not self._last_acted & flag

    def _run_detectors(self, t: float, dt: float, health: TickHealth) -> bool:
        """Run every detector in order; True if one tripped."""
        bits, slots = self._bits, self._slots
        for k, detector in enumerate(self.detectors):
            if not detector.update(t, dt, health):
                continue
            action = detector.action
            if action is Action.TRIP:
                self.trip(t, detector.NAME, detector.detail(health))
                return True
            if self._count(slots[k], bits[k]):
                self.events.push(t, EventKind.FAULT, detector.NAME, detector.detail(health))
            if action is Action.SAFE_STOP and self.lifecycle.state in (State.ARMED, State.RUNNING):
                self.stop(t, detector.NAME)
                if detector.NAME != OperatorStop.NAME:  # the operator's own stop is no check's reason
                    self.stop_reason = detector.NAME
                    self.stop_detail = detector.detail(health)
        return False

    def _watch_idle(self, t: float, health: TickHealth) -> None:
        if self.lifecycle.state is State.TRIPPED:
            return
        for detector in (self._estop, self._operator_trip):
            if detector.update(t, 0.0, health):
                self.trip(t, detector.NAME, detector.detail(health))
                return

    def _shape(self, t: float, dt: float, raw_force_N: float, x_b_m: float, setpoint_N: float | None) -> float:
        """Clamp, stopping ramp, rate limit, stroke fade; flags what acted.

        Each interlock's event says its limit and the demanded value (the stopping ramp its
        length); the text is built on the rising edge only, as a detector's is.
        """
        state = self.lifecycle.state
        if setpoint_N is None:
            force = self.clamp.apply(raw_force_N)
        else:
            force = self.clamp.apply_compensated(setpoint_N, raw_force_N)
        if self.clamp.acted and self._count(_I_CLAMP, _B_CLAMP):
            self.events.push(t, EventKind.INTERLOCK, ForceClamp.NAME, self.clamp.detail(raw_force_N, setpoint_N))
        if state is State.ARMED:
            force = 0.0
        elif state is State.STOPPING:
            elapsed = t - self.lifecycle.entered_s
            force *= self._ramp_gain * max(0.0, 1.0 - elapsed / self.config.run.stopping_ramp_s)
            if self._count(_I_RAMP, _B_RAMP):
                self.events.push(t, EventKind.INTERLOCK, StopRamp.NAME, self._ramp_detail)
        demand, step_s = force, min(dt, self.period_s)
        force = self.rate.apply(demand, self._previous_N, step_s)
        if self.rate.acted and self._count(_I_RATE, _B_RATE):
            self.events.push(t, EventKind.INTERLOCK, ForceRateLimit.NAME, self.rate.detail(demand, self._previous_N, step_s))
        demand = force
        force = self.soft.apply(demand, x_b_m)
        if self.soft.acted and self._count(_I_SOFT, _B_SOFT):
            self.events.push(t, EventKind.INTERLOCK, StrokeSoftFade.NAME, self.soft.detail(demand, x_b_m))
        return force

    def update(
        self, t: float, dt: float, health: TickHealth, raw_force_N: float, setpoint_N: float | None = None,
    ) -> SupervisedCommand:
        """Supervise one tick and return the command to write.

        Parameters
        ----------
        t : float
            Loop time of this tick (s).
        dt : float
            Time since the previous tick (s), > 0.
        health : TickHealth
            This tick's health inputs (updated in place by the loop).
        raw_force_N : float
            The command to shape (N): the controller's force, or a harness-side compensator's command
            for it; NaN or inf trips ``controller_output``.
        setpoint_N : float or None, optional
            The controller's force (N) when ``raw_force_N`` is a compensator's command: ``max_force_N``
            then bounds the setpoint and ``max_flow_term_N`` what the compensator added
            (docs/SAFETY.md, "What max_force_N must bound"). None: ``raw_force_N`` is the setpoint.

        Returns
        -------
        SupervisedCommand
            The preallocated command; ``enable`` is False and ``force_N`` 0 outside ARMED/RUNNING/STOPPING.
        """
        command = self.command
        command.acted = 0
        if self.lifecycle.state not in DRIVE_STATES:
            self._watch_idle(t, health)
            return self._finish_tick(self._off(t))
        if not (math.isfinite(t) and math.isfinite(dt) and dt > 0.0):
            detail = f"t = {t!r} s, dt = {dt!r} s, expected finite t and dt > 0"
            self.trip(t if math.isfinite(t) else 0.0, LoopTiming.NAME, detail)
            return self._finish_tick(self.command)
        if self._run_detectors(t, dt, health) or not self._check_output_and_stroke(t, health, raw_force_N, setpoint_N):
            return self._finish_tick(self.command)
        force = self._shape(t, dt, raw_force_N, health.meas.sliding_displacement_m, setpoint_N)
        if self._ramp_done(t, force):
            self.lifecycle.finish(t)
            self._state_event(t, State.STOPPING, "stopping ramp complete")
            return self._finish_tick(self._off(t))
        self._previous_N = force
        self.tracking.command_N = force
        self.oscillation.command_N = force
        command.t = t
        command.force_N = force
        command.enable = True
        command.state = self.lifecycle.state
        command.trip_reason = ""
        return self._finish_tick(command)

    def _check_output_and_stroke(self, t: float, health: TickHealth, raw_force_N: float, setpoint_N: float | None) -> bool:
        """False (and tripped) if the raw force or the setpoint is not finite or the stroke trips."""
        if not math.isfinite(raw_force_N):
            self.trip(t, ControllerOutput.NAME, f"controller output not finite: {raw_force_N!r} N")
            return False
        if setpoint_N is not None and not math.isfinite(setpoint_N):
            self.trip(t, ControllerOutput.NAME, f"controller setpoint not finite: {setpoint_N!r} N")
            return False
        x_b, v_b = health.meas.sliding_displacement_m, health.meas.sliding_velocity_m_s
        if self.hard.check(x_b):
            self.trip(t, StrokeHardLimit.NAME, self.hard.detail(x_b))
            return False
        if self.predictive.check(x_b, v_b):
            self.trip(t, StrokePredictiveLimit.NAME, self.predictive.detail(x_b, v_b))
            return False
        return True

    def _ramp_done(self, t: float, force_N: float) -> bool:
        if self.lifecycle.state is not State.STOPPING or force_N != 0.0:
            return False
        return t - self.lifecycle.entered_s >= self.config.run.stopping_ramp_s - TIME_EPS_S or self._ramp_gain == 0.0

    def _finish_tick(self, command: SupervisedCommand) -> SupervisedCommand:
        self._last_acted = command.acted
        return command
