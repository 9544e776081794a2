"""Detectors on the loop's own health and on operator requests."""

from __future__ import annotations

from drivers.protocol.protocol_values import fault_name
from harness.safety.comms_detectors import FlagDetector
from harness.safety.config import EStopConfig, RunConfig
from harness.safety.detector_base import Detector
from harness.safety.events import Action
from harness.safety.health import TickHealth

#: What to do about a loop that the host keeps from running (printed with the trip).
HOST_TIMING_REMEDIES = (
    "remedies: a lower --rate, --lockstep for a dry run, real-time priority "
    "(loop.realtime.fifo_priority: auto takes it where permitted: root, CAP_SYS_NICE or an rtprio limit), "
    "or a quieter machine"
)


class LoopStall(Detector):
    """The loop went longer than the stall budget without writing a command (``health.stall_s``).

    ``stall_s`` is the time since the previous tick's command, measured by the loop on waking:
    missed time, not a count of late ticks (one 45 ms stall at 500 Hz is 22 missed periods). A
    stalled loop cannot act, so it trips on the first tick after the stall; during the stall
    the drive-side watchdog is the backstop. It is judged after the operator's requests and
    before the sensor, CAN and actuator checks: a watchdog fault the drive latched during the
    stall, seen in the same tick, is the stall's consequence, and the detail names it; a
    sensor that moved further than a jump between the two samples around the stall is too.
    Shorter stalls are ridden through by the loop: counted, recorded as an event and shown on
    the console. A reset is never refused (the stall is over once the loop runs again).
    """

    NAME = "loop_stall"
    ACTION = Action.TRIP
    DETECTS = "the loop went longer than max_stall_s without writing a command"
    BOUND = "first tick after the stall"
    RESET = "explicit reset"

    __slots__ = ("limit_s",)

    def __init__(self, config: RunConfig) -> None:
        super().__init__()
        self.limit_s = config.max_stall_s

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True on the tick that ends a stall longer than the budget."""
        return health.stall_s > self.limit_s

    def detail(self, health: TickHealth) -> str:
        """How long, against the budget, what the drive did meanwhile, and what to do: this is host timing, not the rig."""
        drive = (f"; the drive reports fault code {health.drive_fault_code} ({fault_name(health.drive_fault_code)}) "
                 "after it, a consequence of the stall" if health.drive_fault else "")
        return (
            f"the loop went {health.stall_s * 1e3:.1f} ms without a command ({health.missed_periods} missed periods), "
            f"expected at most {self.limit_s * 1e3:.1f} ms (the stall budget){drive}: the host did not run the loop in "
            "time; " + HOST_TIMING_REMEDIES
        )

    def present(self, health: TickHealth) -> str:
        """A stall is over once the loop runs again."""
        return ""


class EStop(FlagDetector):
    """The operator's E-stop frame is asserted (``health.estop``); watched in IDLE and DONE too, where the
    latch then blocks arming."""

    NAME = "estop"
    ACTION = Action.TRIP
    WHAT = "E-stop is asserted"
    DETECTS = "operator E-stop frame asserted"
    RESET = "explicit reset, refused while the E-stop is asserted"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the E-stop is asserted."""
        return health.estop


class EStopLost(Detector):
    """The E-stop panel's heartbeat stopped: an unplugged or dead panel could not stop the run.

    An age that is not finite means no frame yet or a clock fault. Not evaluated when
    ``panel_required`` is false (a weakening the run records).
    """

    NAME = "estop_lost"
    ACTION = Action.TRIP
    DETECTS = "E-stop panel frames (source 3) older than max_panel_age_s, or their age not finite or negative"
    BOUND = "first tick with age > max_panel_age_s"
    RESET = "explicit reset, refused while the panel is still silent"

    __slots__ = ("limit_s", "required")

    def __init__(self, config: EStopConfig) -> None:
        super().__init__()
        self.limit_s = config.max_panel_age_s
        self.required = config.panel_required

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while a required panel's newest frame is too old (or has no valid age)."""
        return self.required and not 0.0 <= health.estop_panel_age_s <= self.limit_s

    def detail(self, health: TickHealth) -> str:
        """The panel's age against the bound."""
        return (
            f"E-stop panel silent: newest panel frame {health.estop_panel_age_s * 1e3:.1f} ms old, "
            f"expected 0 <= age <= {self.limit_s * 1e3:.1f} ms (is the panel plugged in?)"
        )

    def present(self, health: TickHealth) -> str:
        """Still present while the panel is silent."""
        return self.detail(health) if self.update(0.0, 0.0, health) else ""


class OperatorStop(FlagDetector):
    """The operator asked for a controlled stop (``health.operator_stop``); ignored outside ARMED and RUNNING."""

    NAME = "operator_stop"
    ACTION = Action.SAFE_STOP
    WHAT = "operator asked for a stop"
    DETECTS = "operator stop request (first Ctrl-C)"
    RESET = "none within the command (the request lasts until it ends); arming refused while set"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the request is set."""
        return health.operator_stop


class OperatorTrip(FlagDetector):
    """The operator asked for an immediate trip (``health.operator_trip``); from any state. The loop clears
    the request once handled."""

    NAME = "operator_trip"
    ACTION = Action.TRIP
    WHAT = "operator asked for a trip"
    DETECTS = "operator trip request (second Ctrl-C, SIGTERM)"
    RESET = "explicit reset, refused while the request is set"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the request is set."""
        return health.operator_trip
