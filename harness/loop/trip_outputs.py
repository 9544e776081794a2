"""What a trip sends beyond the zero, disabled command: the ESTOP frame and the table stop.

The supervisor decides that the run trips and zeroes the command; the tick sends that
command first. :class:`TripOutputs` then carries the trip to the other devices the
profile's ``safety.trip_actions`` names for the class of the check that tripped
(:data:`harness.safety.config.TRIP_CLASS_OF`), in the trip tick itself:

1. ``estop``: one ESTOP frame, ``active=1``, ``source`` SUPERVISOR, ``reason`` the
   check's bit index + 1 (:data:`~harness.safety.checks.CHECK_NAMES`; 0 is "unspecified"),
   repeated every ``estop_every`` ticks (``can.estop_rate_hz``) while TRIPPED;
2. ``stop_table``: one RIG_CONTROL stop to the table controller, where the run has a table
   link (``stop_table`` given).

A safe stop that must also stop the table (``table_record_mismatch``: the table plays
another record than the test plan's) sends the same RIG_CONTROL stop once
(:meth:`TripOutputs.stop_the_table`), while the force ramps down.

Nothing here allocates per tick: the plan per check is built once, the writer reuses its
frames. A failed send is counted, never raised (the drive watchdog is the backstop).
"""

from __future__ import annotations

from collections.abc import Callable

from drivers.protocol.protocol_values import EstopSource
from harness.safety.checks import CHECK_NAMES
from harness.safety.config import TripActionsConfig
from harness.safety.lifecycle import State

#: ESTOP ``source`` of the harness's safety supervisor (the DBC's value table of ESTOP ``source``).
SUPERVISOR_SOURCE = EstopSource.SUPERVISOR
_ESTOP, _STOP_TABLE = 1, 2


def _plan(actions: TripActionsConfig) -> dict[str, tuple[int, int]]:
    """Check name -> (action bits, ESTOP reason code), for every check and the unknown reason ""."""
    plan = {}
    for k, name in enumerate(CHECK_NAMES):
        chosen = actions.for_check(name)
        bits = (_ESTOP if "estop" in chosen else 0) | (_STOP_TABLE if "stop_table" in chosen else 0)
        plan[name] = (bits, k + 1)
    return plan


class TripOutputs:
    """Sends a trip's ESTOP (repeated while TRIPPED) and table stop, as the trip actions say.

    Parameters
    ----------
    writer : drivers.writer.HarnessWriter
        Has ``estop(active, now, source, reason)``.
    actions : TripActionsConfig
        The profile's ``safety.trip_actions``.
    estop_every : int
        Ticks between two ESTOP frames while TRIPPED (loop rate / ``can.estop_rate_hz``).
    stop_table : callable, optional
        ``stop_table(now)`` sends the table controller's stop (RIG_CONTROL stop); None when the
        run has no table link (``stop_table`` is then not reachable and is skipped).

    Attributes
    ----------
    estop_frames, table_stops, failures : int
        ESTOP frames and table stops sent, and sends that failed or raised.
    """

    __slots__ = (
        "writer", "estop_every", "stop_table", "estop_frames", "table_stops", "failures", "_plan", "_tripped",
        "_estop", "_reason", "_countdown", "_table_stopped",
    )

    def __init__(
        self, writer, actions: TripActionsConfig, estop_every: int,
        stop_table: Callable[[float], object] | None = None,
    ) -> None:
        self.writer = writer
        self.estop_every = max(1, int(estop_every))
        self.stop_table = stop_table
        self.estop_frames = 0
        self.table_stops = 0
        self.failures = 0
        self._plan = _plan(actions)
        self._tripped = False
        self._estop = False
        self._reason = 0
        self._countdown = 0
        self._table_stopped = False

    @property
    def estop_asserted(self) -> bool:
        """True while the harness keeps the ESTOP asserted (TRIPPED with the ``estop`` action)."""
        return self._tripped and self._estop

    def update(self, state: State, trip_reason: str, now: float) -> None:
        """Call once per tick after the command was sent; never raises.

        Parameters
        ----------
        state : State
            The lifecycle state after this tick.
        trip_reason : str
            The latched trip reason ("" when not tripped).
        now : float
            The drivers' clock (s).
        """
        if state is not State.TRIPPED:
            self._tripped = False
            return
        if not self._tripped:
            self._on_trip(trip_reason, now)
        elif self._estop:
            self._countdown -= 1
            if self._countdown <= 0:
                self._send_estop(now)

    def _on_trip(self, reason: str, now: float) -> None:
        """The trip tick: ESTOP first (the servo's own stop), then the table."""
        self._tripped = True
        bits, self._reason = self._plan.get(reason, (0, 0))
        self._estop = bool(bits & _ESTOP)
        if self._estop:
            self._send_estop(now)
        if bits & _STOP_TABLE and self.stop_table is not None:
            try:
                self.stop_table(now)
                self.table_stops += 1
            except Exception:  # noqa: BLE001 - nothing more can be sent; the trip itself stands
                self.failures += 1

    def stop_the_table(self, now: float) -> None:
        """Send the table controller's stop, once per run, outside a trip; never raises.

        For a safe stop that must stop the table too (``table_record_mismatch``); nothing when the
        run has no table link.
        """
        if self._table_stopped or self.stop_table is None:
            return
        self._table_stopped = True
        try:
            self.stop_table(now)
            self.table_stops += 1
        except Exception:  # noqa: BLE001 - nothing more can be sent; the safe stop itself stands
            self.failures += 1

    def _send_estop(self, now: float) -> None:
        self._countdown = self.estop_every
        try:
            if self.writer.estop(True, now, SUPERVISOR_SOURCE, self._reason):
                self.estop_frames += 1
            else:
                self.failures += 1
        except Exception:  # noqa: BLE001 - a send that raised is a failed send
            self.failures += 1
