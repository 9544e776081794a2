"""Safety vocabulary shared by every check: what a check does when it acts, and the event ring.

The checks' stable names and bit flags are those of the one list of checks,
:mod:`harness.safety.checks`.
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
