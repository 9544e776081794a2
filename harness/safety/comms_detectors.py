"""Detectors on the CAN link: E2E rejections, error frames, error states, send failures."""

from __future__ import annotations

from harness.safety.config import CommsConfig
from harness.safety.detector_base import Detector, WindowCounter
from harness.safety.events import ACTION_BY_NAME, Action
from harness.safety.health import TickHealth


class FlagDetector(Detector):
    """A detector on one boolean of :class:`TickHealth`: fires on the tick the flag is bad.

    Subclasses implement :meth:`bad` and set :attr:`WHAT` (a phrase for messages).
    """

    WHAT = ""
    BOUND = "same tick"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the flag shows the fault."""
        raise NotImplementedError

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while the flag shows the fault."""
        return self.bad(health)

    def detail(self, health: TickHealth) -> str:
        """The phrase for this fault."""
        return self.WHAT

    def present(self, health: TickHealth) -> str:
        """Still showing?"""
        return self.WHAT if self.bad(health) else ""


class RateDetector(Detector):
    """A detector on a cumulative counter: more than N increments within a sliding window."""

    COUNTER = ""
    WHAT = ""

    __slots__ = ("window",)

    def __init__(self, max_count: int, window_s: float, action: Action | None = None) -> None:
        super().__init__(action)
        self.window = WindowCounter(max_count, window_s)

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while more than ``max_count`` increments lie within the window."""
        return self.window.update(t, getattr(health, self.COUNTER))

    def detail(self, health: TickHealth) -> str:
        """Count, window and limit."""
        w = self.window
        return f"more than {w.max_count} {self.WHAT} within {w.window_s:g} s, expected at most {w.max_count}"

    def reset(self) -> None:
        """Forget the counted events."""
        self.window.reset()


class E2eRejects(RateDetector):
    """Too many frames rejected by the E2E counter/CRC check (``health.e2e_rejects``)."""

    NAME = "e2e_rejects"
    ACTION = Action.TRIP
    COUNTER = "e2e_rejects"
    WHAT = "counter/CRC rejections"
    DETECTS = "more than max_e2e_rejects counter/CRC rejections within e2e_window_s"
    BOUND = "tick the (max+1)-th rejection in the window is counted"
    RESET = "explicit reset; window cleared"

    __slots__ = ()

    def __init__(self, config: CommsConfig) -> None:
        super().__init__(config.max_e2e_rejects, config.e2e_window_s)


class BusErrorFrames(RateDetector):
    """Too many CAN error frames; the action is ``error_frame_action`` (the link still works, so by
    default the run is ended gently)."""

    NAME = "bus_error_frames"
    ACTION = Action.SAFE_STOP
    COUNTER = "error_frames"
    WHAT = "error frames"
    DETECTS = "more than max_error_frames error frames within error_frame_window_s"
    BOUND = "tick the (max+1)-th error frame in the window is counted"
    RESET = "explicit reset; window cleared"

    __slots__ = ()

    def __init__(self, config: CommsConfig) -> None:
        super().__init__(config.max_error_frames, config.error_frame_window_s, ACTION_BY_NAME[config.error_frame_action])


class BusSendFailures(RateDetector):
    """Commands that could not be sent (ENOBUFS: the tx queue is full)."""

    NAME = "bus_send_failures"
    ACTION = Action.TRIP
    COUNTER = "send_failures"
    WHAT = "failed sends"
    DETECTS = "more than max_send_failures failed sends (ENOBUFS) within send_failure_window_s"
    BOUND = "tick the (max+1)-th failure in the window is counted"
    RESET = "explicit reset; window cleared"

    __slots__ = ()

    def __init__(self, config: CommsConfig) -> None:
        super().__init__(config.max_send_failures, config.send_failure_window_s)


class BusErrorPassive(FlagDetector):
    """The CAN controller went error-passive; the action is ``error_passive_action`` (frames still get
    through, so by default the run is ended gently)."""

    NAME = "bus_error_passive"
    ACTION = Action.SAFE_STOP
    WHAT = "CAN controller is error-passive"
    DETECTS = "CAN controller error-passive"
    RESET = "explicit reset, refused while still error-passive"

    __slots__ = ()

    def __init__(self, config: CommsConfig) -> None:
        super().__init__(ACTION_BY_NAME[config.error_passive_action])

    def bad(self, health: TickHealth) -> bool:
        """True while error-passive."""
        return health.error_passive


class BusOff(FlagDetector):
    """The CAN controller is bus-off (``health.bus_off``).

    Seen from bus-off error frames (SocketCAN's error-class bits). Other backends deliver no
    error frames: there bus-off shows only as send failures, which trip ``bus_send_failures``,
    and as silence, which trips ``sensor_stale``.
    """

    NAME = "bus_off"
    ACTION = Action.TRIP
    WHAT = "CAN controller is bus-off"
    DETECTS = "CAN controller bus-off"
    RESET = "explicit reset, refused while bus-off"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while bus-off."""
        return health.bus_off


class BusGone(FlagDetector):
    """The CAN interface disappeared or cannot be read (``health.bus_gone``)."""

    NAME = "bus_gone"
    ACTION = Action.TRIP
    WHAT = "CAN interface is gone"
    DETECTS = "CAN interface down or unreadable"
    RESET = "explicit reset, refused while the bus is gone"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while the bus is gone."""
        return health.bus_gone


class ForeignCommand(FlagDetector):
    """Another node sends on the actuator command ID (``health.foreign_command``): two masters on one actuator."""

    NAME = "foreign_command"
    ACTION = Action.TRIP
    WHAT = "another node is sending on the actuator command ID"
    DETECTS = "a frame on the actuator command ID not sent by this harness"
    RESET = "explicit reset, refused while still seen"

    __slots__ = ()

    def bad(self, health: TickHealth) -> bool:
        """True while a foreign sender is seen."""
        return health.foreign_command
