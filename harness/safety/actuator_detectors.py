"""Detectors on the actuator's servo controller: drive fault, pressure, status age, force tracking, compensation."""

from __future__ import annotations

from drivers.protocol.protocol_values import fault_name
from harness.hydraulics.servo_controller import steady_bleed_N
from harness.safety.comms_detectors import FlagDetector
from harness.safety.config import ActuatorConfig, ForceConfig
from harness.safety.detector_base import TIME_EPS_S, Detector, LowPass, Persistence
from harness.safety.events import ACTION_BY_NAME, Action
from harness.safety.health import TickHealth


class DriveFault(FlagDetector):
    """The actuator's servo controller reports a fault (``health.drive_fault``), named by its fault code.

    A watchdog fault the loop's own stall caused is not this check's: ``loop_stall`` is judged
    first, on the tick that ends the stall (docs/SAFETY.md, "Stall attribution").
    """

    NAME = "drive_fault"
    ACTION = Action.TRIP
    WHAT = "actuator drive reports a fault"
    DETECTS = "drive fault bit in the actuator status frame"
    RESET = "explicit reset, refused while the drive reports the fault"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the drive reports a fault."""
        return health.drive_fault

    def detail(self, health: TickHealth) -> str:
        """The phrase and the drive's fault code by name."""
        return f"{self.WHAT}: fault code {health.drive_fault_code} ({fault_name(health.drive_fault_code)})"

    def present(self, health: TickHealth) -> str:
        """Still reported?"""
        return self.detail(health) if self.bad(health) else ""


class HydraulicPressure(FlagDetector):
    """Hydraulic pressure lost (``health.pressure_ok`` False)."""

    NAME = "hydraulic_pressure"
    ACTION = Action.TRIP
    WHAT = "hydraulic pressure is not ok"
    DETECTS = "pressure-ok bit cleared in the actuator status frame"
    RESET = "explicit reset, refused while pressure is not ok"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the pressure is not ok."""
        return not health.pressure_ok


class ActuatorStatusStale(Detector):
    """Actuator status frames stopped arriving (``health.actuator_status_age_s``)."""

    NAME = "actuator_status_stale"
    ACTION = Action.TRIP
    DETECTS = "actuator status frame older than max_status_age_s, or its age not finite or negative"
    BOUND = "first tick with age > max_status_age_s"
    RESET = "explicit reset, refused while still stale"

    __slots__ = ("max_age_s",)

    def __init__(self, config: ActuatorConfig) -> None:
        super().__init__()
        self.max_age_s = config.max_status_age_s

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while the status is too old."""
        return not 0.0 <= health.actuator_status_age_s <= self.max_age_s + TIME_EPS_S  # NaN or negative: invalid, trips

    def detail(self, health: TickHealth) -> str:
        """Age and limit."""
        return (
            f"actuator status age {health.actuator_status_age_s * 1e3:.3f} ms, "
            f"expected 0 <= age <= {self.max_age_s * 1e3:.3f} ms"
        )

    def present(self, health: TickHealth) -> str:
        """Still stale?"""
        return self.detail(health) if self.update(0.0, 0.0, health) else ""


#: Largest share of ``A p_s`` the force-tracking model's orifice factor takes the load cell's force at.
_MAX_LOAD_RATIO = 2.0 / 3.0


class ForceTracking(Detector):
    """The actuator does not follow the commanded force.

    The expected force is the force commanded on the previous tick (the supervisor writes it
    to :attr:`command_N` before each update), less the velocity feedback the actuator's servo
    controller leaves at the measured sliding velocity ``v``, through a first-order lag with
    ``actuator_time_constant_s`` (none when 0): the low-frequency model of a servo-hydraulic
    actuator under a proportional force loop with velocity feed-forward (docs/SAFETY.md, "Force
    tracking of a servo-hydraulic actuator"),

        bleed = c v (1 / s - alpha),   s = sqrt(1 - sign(v) u / (A p_s))

    with ``c = velocity_feedback_Ns_per_m``, ``alpha = velocity_feedforward_gain``, ``u`` the
    load cell's force held to +-2/3 of ``A p_s = supply_force_N`` (``s = 1`` when that is null);
    with no velocity feedback, a force source. The action is ``tracking_action``; a reset is
    never refused (the error is not knowable from one sample).
    """

    NAME = "force_tracking"
    ACTION = Action.TRIP
    DETECTS = "|measured - lagged (commanded - velocity feedback) force| above tracking_tolerance_N for tracking_time_s"
    BOUND = "tracking_time_s after the error exceeds the tolerance"
    RESET = "explicit reset; filter and timer cleared"

    __slots__ = ("tolerance_N", "command_N", "_lag", "_timer", "_error_N", "_feedback_Ns_per_m", "_target_N",
                 "_feedforward_gain", "_supply_force_N")

    def __init__(self, config: ForceConfig) -> None:
        super().__init__(ACTION_BY_NAME[config.tracking_action])
        self.tolerance_N = config.tracking_tolerance_N
        self.command_N = 0.0
        self._lag = LowPass(config.actuator_time_constant_s) if config.actuator_time_constant_s > 0 else None
        self._timer = Persistence(config.tracking_time_s)
        self._error_N = 0.0
        self._feedback_Ns_per_m = config.velocity_feedback_Ns_per_m
        self._feedforward_gain = config.velocity_feedforward_gain
        self._supply_force_N = config.supply_force_N
        self._target_N = 0.0

    def expected_N(self) -> float:
        """The force the actuator should show now (N)."""
        return self._target_N if self._lag is None else self._lag.y

    def bleed_N(self, sliding_velocity_m_s: float, force_N: float) -> float:
        """The force the actuator loses at ``sliding_velocity_m_s`` while giving ``force_N`` (N).

        The load ratio ``u / (A p_s)`` is held to +-2/3 (the working force of a cylinder sized at
        2/3 supply), so a load cell reading beyond it cannot claim an unbounded bleed.
        """
        if self._supply_force_N is None:
            return (1.0 - self._feedforward_gain) * self._feedback_Ns_per_m * sliding_velocity_m_s
        held = min(max(force_N, -_MAX_LOAD_RATIO * self._supply_force_N), _MAX_LOAD_RATIO * self._supply_force_N)
        return steady_bleed_N(self._feedback_Ns_per_m, sliding_velocity_m_s, held, self._supply_force_N,
                              self._feedforward_gain)

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once the tracking error has persisted for ``tracking_time_s``."""
        self._target_N = self.command_N - self.bleed_N(health.meas.sliding_velocity_m_s, health.measured_force_N)
        if self._lag is not None:
            self._lag.update(self._target_N, dt)
        self._error_N = health.measured_force_N - self.expected_N()
        return self._timer.update(t, not abs(self._error_N) <= self.tolerance_N)

    def detail(self, health: TickHealth) -> str:
        """Measured, expected, tolerance, duration."""
        return (
            f"measured {health.measured_force_N:.6g} N vs expected {self.expected_N():.6g} N "
            f"(error {self._error_N:.6g} N), expected within {self.tolerance_N:g} N "
            f"for less than {self._timer.limit_s:g} s"
        )

    def reset(self) -> None:
        """Clear the lag (to zero force) and the timer."""
        self.command_N = 0.0
        self._target_N = 0.0
        if self._lag is not None:
            self._lag.reset(0.0, True)
        self._timer.reset()


class CompensationFault(Detector):
    """The force-tracking compensator left its stated range: a bounded parameter held at its bound, or a state not finite.

    The loop copies the compensator's own flags into ``health.compensation_pinned`` and
    ``health.compensation_diverged`` each tick, after its update and before the supervisor's
    (harness/control/compensation.py). A parameter at its bound means the actuator is not the
    one the compensator was built for by more than it was allowed to correct; the bound is held
    for ``tracking_time_s``, the time the force-tracking check gives a force error (docs/SAFETY.md,
    "Force-tracking compensation", derives both). A state that is not finite trips at once.
    """

    NAME = "compensation_fault"
    ACTION = Action.TRIP
    DETECTS = "a compensator's correction or coefficient at its bound for tracking_time_s, or its state not finite"
    BOUND = "tracking_time_s after a parameter reaches its bound; same tick for a state not finite"
    RESET = "explicit reset, refused while the compensator's state is not finite; timer cleared"

    __slots__ = ("_timer",)

    def __init__(self, config: ForceConfig) -> None:
        super().__init__()
        self._timer = Persistence(config.tracking_time_s)

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once a parameter has sat at its bound for ``tracking_time_s``, or at once for a state not finite."""
        pinned = self._timer.update(t, health.compensation_pinned)
        return health.compensation_diverged or pinned

    def detail(self, health: TickHealth) -> str:
        """Which failure, the parameter's value and the time allowed."""
        if health.compensation_diverged:
            return f"compensator state not finite (parameter {health.compensation_value!r}); expected finite"
        return (
            f"compensator parameter held at its bound ({health.compensation_value:.6g}) for "
            f"{self._timer.limit_s:g} s; expected inside its bounds or back within {self._timer.limit_s:g} s"
        )

    def present(self, health: TickHealth) -> str:
        """Still not finite? (A parameter at its bound cannot be judged from one sample.)"""
        return self.detail(health) if health.compensation_diverged else ""

    def reset(self) -> None:
        """Clear the timer."""
        self._timer.reset()


class LoadCellLimit(Detector):
    """The load cell stays beyond its bound: a servo controller's limit detector, on the force fed back.

    The supervisor bounds what the harness asks for (``max_force_N`` on the setpoint,
    ``max_flow_term_N`` on what a harness-side compensator adds); this check bounds what the load
    path carries, whatever asked for it: a blocked piston, a rig-side feed-forward acting on a
    velocity that is no longer there, a servo controller that runs away. It fires once
    ``|measured force|`` has been beyond ``load_cell_limit_N`` for ``load_cell_limit_time_s``
    (docs/SAFETY.md, "What max_force_N must bound", derives both); a load cell that is not finite
    counts as beyond (fail safe). A reset is refused while the load cell is still beyond.
    """

    NAME = "load_cell_limit"
    ACTION = Action.TRIP
    DETECTS = "|measured force| beyond load_cell_limit_N, or not finite, for load_cell_limit_time_s"
    BOUND = "load_cell_limit_time_s after the load cell passes load_cell_limit_N"
    RESET = "explicit reset, refused while |measured force| is beyond load_cell_limit_N; timer cleared"

    __slots__ = ("limit_N", "_timer", "peak_N")

    def __init__(self, config: ForceConfig) -> None:
        super().__init__()
        self.limit_N = config.load_cell_limit_N
        self._timer = Persistence(config.load_cell_limit_time_s)
        #: The largest |load-cell force| seen since the last reset (N): the figure docs/SAFETY.md reports.
        self.peak_N = 0.0

    def _beyond(self, force_N: float) -> bool:
        return not abs(force_N) <= self.limit_N

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once the load cell has been beyond the limit for ``load_cell_limit_time_s``."""
        force = abs(health.measured_force_N)
        if force > self.peak_N:
            self.peak_N = force
        return self._timer.update(t, self._beyond(health.measured_force_N))

    def detail(self, health: TickHealth) -> str:
        """The load cell, the limit, how long it has been beyond."""
        return (
            f"load cell {health.measured_force_N:.6g} N beyond +/-{self.limit_N:g} N (safety.force.load_cell_limit_N) "
            f"for {self._timer.limit_s * 1e3:g} ms; expected within: the load path carries more than any healthy "
            "command gives (a blocked piston, a servo controller's feed-forward or loop out of bounds)"
        )

    def present(self, health: TickHealth) -> str:
        """Still beyond the limit: the reset is refused."""
        return self.detail(health) if self._beyond(health.measured_force_N) else ""

    def reset(self) -> None:
        """Clear the timer and the peak."""
        self._timer.reset()
        self.peak_N = 0.0
