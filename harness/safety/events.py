"""Safety vocabulary shared by every check: actions, stable names, bit flags, the event ring.

Every interlock and detector has a stable machine name (``"stroke_hard"``,
``"sensor_stale"``, ...). The name is the trip reason, the key of its act counter,
and the index of its bit in :attr:`SupervisedCommand.acted`: ``bit(name) == 1 << CHECK_NAMES.index(name)``.
New checks are appended, never inserted, so recorded flags keep their meaning.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum


class Action(IntEnum):
    """What a check does when it acts, in increasing severity."""

    INDICATE = 0
    """Flag and record only; the force passes."""
    CLAMP = 1
    """Limit the force (magnitude or rate) and go on."""
    FADE = 2
    """Scale the outward force down towards zero."""
    SAFE_STOP = 3
    """RUNNING/ARMED -> STOPPING: ramp the force to zero, then disable."""
    TRIP = 4
    """-> TRIPPED at once: zero force and drive disabled on this tick, latched."""


ACTION_BY_NAME: dict[str, Action] = {"indicate": Action.INDICATE, "safe_stop": Action.SAFE_STOP, "trip": Action.TRIP}

#: Stable names of all checks, in bit order. Append only.
CHECK_NAMES: tuple[str, ...] = (
    "force_clamp",
    "force_rate",
    "stroke_soft",
    "stroke_hard",
    "stroke_predictive",
    "sensor_invalid",
    "sensor_stale",
    "sensor_jump",
    "sensor_stuck",
    "sensor_disagree",
    "e2e_rejects",
    "bus_error_frames",
    "bus_error_passive",
    "bus_off",
    "bus_send_failures",
    "bus_gone",
    "foreign_command",
    "drive_fault",
    "hydraulic_pressure",
    "actuator_status_stale",
    "force_tracking",
    "loop_stall",  # bit 21; was "loop_overruns" (consecutive late ticks) before the stall budget
    "loop_timing",
    "tick_exception",
    "controller_output",
    "estop",
    "operator_stop",
    "operator_trip",
    "stop_ramp",
    "sensor_sign_flip",  # bit 29; appended: runs after sensor_stuck, before sensor_disagree (supervisor order)
    "estop_lost",  # bit 30; appended: the E-stop panel's heartbeat is older than safety.estop.max_panel_age_s
    "table_record_mismatch",  # bit 31; appended: the table does not play the record the harness was told
    "table_record_marginal",  # bit 32; appended: it follows it, but not as a healthy table does (a warning)
)

_INDEX: dict[str, int] = {name: index for index, name in enumerate(CHECK_NAMES)}


def bit(name: str) -> int:
    """The bit flag of the check called ``name``.

    Raises
    ------
    KeyError
        If ``name`` is not one of :data:`CHECK_NAMES`.
    """
    try:
        return 1 << _INDEX[name]
    except KeyError as err:
        raise KeyError(f"unknown safety check {name!r}; expected one of {', '.join(CHECK_NAMES)}") from err


def index(name: str) -> int:
    """The position of ``name`` in :data:`CHECK_NAMES` (its counter slot)."""
    return bit(name).bit_length() - 1


def names_of(flags: int) -> tuple[str, ...]:
    """Decode bit flags into check names (for reports; allocates, never call per tick)."""
    return tuple(name for i, name in enumerate(CHECK_NAMES) if flags >> i & 1)


class EventKind:
    """Kinds of event entries (plain strings, interned once)."""

    STATE = "state"
    INTERLOCK = "interlock"
    FAULT = "fault"


class Event:
    """One preallocated ring slot: ``(t, kind, name, detail)``."""

    __slots__ = ("t", "kind", "name", "detail")

    def __init__(self) -> None:
        self.t = 0.0
        self.kind = ""
        self.name = ""
        self.detail = ""


class EventRing:
    """Fixed-size ring of events, filled by the supervisor and drained by the loop.

    When the ring is full the oldest undrained event is overwritten and
    :attr:`overwritten` counts it; the latched trip reason never depends on the ring.

    Parameters
    ----------
    capacity : int
        Number of preallocated slots.
    """

    __slots__ = ("_slots", "_head", "_count", "overwritten")

    def __init__(self, capacity: int) -> None:
        if capacity < 1:
            raise ValueError(f"event ring capacity is {capacity}, expected at least 1")
        self._slots = [Event() for _ in range(capacity)]
        self._head = 0  # index of the oldest undrained event
        self._count = 0
        self.overwritten = 0

    def __len__(self) -> int:
        return self._count

    @property
    def capacity(self) -> int:
        """Number of slots."""
        return len(self._slots)

    def push(self, t: float, kind: str, name: str, detail: str) -> None:
        """Store an event in place (no allocation besides the caller's detail string)."""
        capacity = len(self._slots)
        if self._count == capacity:
            self._head = (self._head + 1) % capacity
            self._count -= 1
            self.overwritten += 1
        slot = self._slots[(self._head + self._count) % capacity]
        slot.t = t
        slot.kind = kind
        slot.name = name
        slot.detail = detail
        self._count += 1

    def drain(self, sink: Callable[[float, str, str, str], object]) -> int:
        """Pass every undrained event, oldest first, to ``sink(t, kind, name, detail)``.

        Returns
        -------
        int
            Number of events passed.
        """
        drained = 0
        capacity = len(self._slots)
        while self._count:
            slot = self._slots[self._head]
            self._head = (self._head + 1) % capacity
            self._count -= 1
            sink(slot.t, slot.kind, slot.name, slot.detail)
            drained += 1
        return drained
