"""Detectors on the loop's own health and on operator requests."""

from __future__ import annotations

from harness.safety.comms_detectors import FlagDetector
from harness.safety.config import RunConfig
from harness.safety.detector_base import Detector
from harness.safety.events import Action
from harness.safety.health import TickHealth


class LoopOverruns(Detector):
    """The loop cannot keep its rate.

    Detects: ``health.consecutive_overruns >= max_consecutive_overruns``.
    Bound: the tick that completes the N-th consecutive overrun. Action: TRIP.
    Reset: explicit reset, refused while the loop still reports N or more (its
    count restarts on an on-time tick).
    """

    NAME = "loop_overruns"
    ACTION = Action.TRIP
    DETECTS = "max_consecutive_overruns ticks in a row missed their deadline"
    BOUND = "the N-th consecutive overrun"
    RESET = "explicit reset, refused while the count is still >= N"

    __slots__ = ("limit",)

    def __init__(self, config: RunConfig) -> None:
        super().__init__()
        self.limit = config.max_consecutive_overruns

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while the loop reports at least N consecutive overruns."""
        return health.consecutive_overruns >= self.limit

    def detail(self, health: TickHealth) -> str:
        """Count and limit."""
        return f"{health.consecutive_overruns} consecutive overruns, expected fewer than {self.limit}"

    def present(self, health: TickHealth) -> str:
        """Still overrunning?"""
        return self.detail(health) if self.update(0.0, 0.0, health) else ""


class EStop(FlagDetector):
    """The operator's E-stop frame is asserted.

    Detects: ``health.estop``. Bound: the same tick. Action: TRIP (also from
    IDLE and DONE: the latch then blocks arming). Reset: explicit reset, refused
    while the E-stop is still asserted.
    """

    NAME = "estop"
    ACTION = Action.TRIP
    WHAT = "E-stop is asserted"
    DETECTS = "operator E-stop frame asserted"
    RESET = "explicit reset, refused while the E-stop is asserted"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the E-stop is asserted."""
        return health.estop


class OperatorStop(FlagDetector):
    """The operator asked for a controlled stop (first Ctrl-C).

    Detects: ``health.operator_stop``. Bound: the same tick. Action: SAFE_STOP
    (ARMED/RUNNING -> STOPPING; ignored in other states). Reset: the loop clears
    the flag; arming is refused while it is set.
    """

    NAME = "operator_stop"
    ACTION = Action.SAFE_STOP
    WHAT = "operator asked for a stop"
    DETECTS = "operator stop request (first Ctrl-C)"
    RESET = "the loop clears the request; arming refused while set"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the request is set."""
        return health.operator_stop


class OperatorTrip(FlagDetector):
    """The operator asked for an immediate trip (second Ctrl-C or SIGTERM).

    Detects: ``health.operator_trip``. Bound: the same tick. Action: TRIP (from
    any state). Reset: explicit reset, refused while the request is still set
    (the loop clears it once handled).
    """

    NAME = "operator_trip"
    ACTION = Action.TRIP
    WHAT = "operator asked for a trip"
    DETECTS = "operator trip request (second Ctrl-C, SIGTERM)"
    RESET = "explicit reset, refused while the request is set"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the request is set."""
        return health.operator_trip
