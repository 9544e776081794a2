"""The run lifecycle: IDLE -> ARMED -> RUNNING -> STOPPING -> DONE, or TRIPPED (latched).

Transitions (anything else raises :class:`IllegalTransition`):

============  =========  ===========================================================
from          request    to
============  =========  ===========================================================
IDLE          ARM        ARMED (only if every pre-arm check passed; else ArmRefused)
ARMED         START      RUNNING
ARMED         STOP       STOPPING
RUNNING       STOP       STOPPING
STOPPING      FINISH     DONE (the ramp reached zero; the supervisor requests it)
any           TRIP       TRIPPED (from TRIPPED: no change, the first reason stays)
TRIPPED       RESET      IDLE (only if the trip condition is gone; else ResetRefused)
DONE          RESET      IDLE
============  =========  ===========================================================

Drive enable: ARMED, RUNNING and STOPPING enable the drive; every other state
commands force 0 with the drive disabled. ARMED enables the drive with zero force
on purpose: the servo loop is closed at zero before the start, so a drive that
does not become ready is seen before any force is asked for, and the start is
bumpless (the force then rises under the rate limit).
"""

from __future__ import annotations

from enum import IntEnum

from harness.errors import SafetyError


class State(IntEnum):
    """Run states; sent in HEARTBEAT ``state``, whose value table in ``drivers/protocol/rig.dbc`` names them alike."""

    IDLE = 0
    ARMED = 1
    RUNNING = 2
    STOPPING = 3
    DONE = 4
    TRIPPED = 5


class Request(IntEnum):
    """Transition requests."""

    ARM = 0
    START = 1
    STOP = 2
    FINISH = 3
    TRIP = 4
    RESET = 5


#: States in which the drive is enabled and a force may be written.
DRIVE_STATES: frozenset[State] = frozenset({State.ARMED, State.RUNNING, State.STOPPING})

#: (state, request) -> next state, for every legal transition.
TRANSITIONS: dict[tuple[State, Request], State] = {
    (State.IDLE, Request.ARM): State.ARMED,
    (State.ARMED, Request.START): State.RUNNING,
    (State.ARMED, Request.STOP): State.STOPPING,
    (State.RUNNING, Request.STOP): State.STOPPING,
    (State.STOPPING, Request.FINISH): State.DONE,
    (State.TRIPPED, Request.RESET): State.IDLE,
    (State.DONE, Request.RESET): State.IDLE,
    **{(state, Request.TRIP): State.TRIPPED for state in State},
}


class IllegalTransition(SafetyError):
    """A request that is not legal in the current state.

    Attributes
    ----------
    state : State
        The state the request was made in.
    request : Request
        The refused request.
    """

    def __init__(self, state: State, request: Request):
        self.state = state
        self.request = request
        legal = ", ".join(r.name for (s, r) in TRANSITIONS if s is state)
        super().__init__(f"request {request.name} refused in state {state.name}; legal requests there: {legal}")


class ArmRefused(SafetyError):
    """Arming was refused; :attr:`failed` names every pre-arm check that failed."""

    def __init__(self, failed: tuple[str, ...]):
        self.failed = failed
        super().__init__("arm refused: expected every pre-arm check to pass, failed: " + "; ".join(failed))


class ResetRefused(SafetyError):
    """A reset was refused because the trip condition is still present."""

    def __init__(self, reason: str, detail: str):
        self.reason = reason
        super().__init__(f"reset refused: trip condition {reason!r} is still present ({detail})")


class Lifecycle:
    """The state machine, with the latched trip reason. Clock-free; time is passed in.

    Attributes
    ----------
    state : State
        Current state.
    trip_reason : str
        Name of the first check that tripped since the last reset ("" if none).
    trip_detail : str
        What that check saw.
    entered_s : float
        Time the current state was entered (s, the loop's clock).
    """

    __slots__ = ("state", "trip_reason", "trip_detail", "entered_s")

    def __init__(self) -> None:
        self.state = State.IDLE
        self.trip_reason = ""
        self.trip_detail = ""
        self.entered_s = 0.0

    def _go(self, t: float, request: Request) -> State:
        target = TRANSITIONS.get((self.state, request))
        if target is None:
            raise IllegalTransition(self.state, request)
        self.state = target
        self.entered_s = t
        return target

    def arm(self, t: float, failed: tuple[str, ...] = ()) -> None:
        """IDLE -> ARMED. ``failed`` lists failed pre-arm checks; any failure refuses the arm."""
        if self.state is not State.IDLE:
            raise IllegalTransition(self.state, Request.ARM)
        if failed:
            raise ArmRefused(tuple(failed))
        self._go(t, Request.ARM)

    def start(self, t: float) -> None:
        """ARMED -> RUNNING."""
        self._go(t, Request.START)

    def stop(self, t: float) -> None:
        """ARMED or RUNNING -> STOPPING (ramp the force down, then DONE)."""
        self._go(t, Request.STOP)

    def finish(self, t: float) -> None:
        """STOPPING -> DONE, once the ramp has brought the force to zero."""
        self._go(t, Request.FINISH)

    def trip(self, t: float, reason: str, detail: str = "") -> bool:
        """Any state -> TRIPPED, latching ``reason``.

        Returns
        -------
        bool
            True if this call tripped; False if already TRIPPED (the first reason is kept).
        """
        if self.state is State.TRIPPED:
            return False
        self._go(t, Request.TRIP)
        self.trip_reason = reason
        self.trip_detail = detail
        return True

    def reset(self, t: float, still_present: str = "") -> None:
        """TRIPPED or DONE -> IDLE, clearing the latch.

        Parameters
        ----------
        t : float
            Time (s).
        still_present : str
            Non-empty if the trip condition is still present (what is seen); refuses the reset.
        """
        if (self.state, Request.RESET) not in TRANSITIONS:
            raise IllegalTransition(self.state, Request.RESET)
        if self.state is State.TRIPPED and still_present:
            raise ResetRefused(self.trip_reason, still_present)
        self._go(t, Request.RESET)
        self.trip_reason = ""
        self.trip_detail = ""

    @property
    def drive_enabled(self) -> bool:
        """True in ARMED, RUNNING and STOPPING."""
        return self.state in DRIVE_STATES
