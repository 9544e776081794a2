"""The rig's journal: each state change of the drive, the harness and the table, one line each.

The rig's service thread calls :meth:`RigJournal.watch` after every frame it handles and
after every service; it compares a few numbers with the last ones it saw and, only on a
change, queues one short line. The terminal (``harness rig``) takes the lines off the queue
from its own thread (:meth:`RigJournal.drain`) and prints them, so printing never runs in,
or waits on, the rig's physics thread. The queue is bounded: a terminal that never drains
(a rig process whose output goes nowhere) keeps only the latest :data:`JOURNAL_LINES`.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from enum import IntEnum

from drivers.protocol.protocol_values import DriveState, FaultCode, fault_name
from harness.safety.lifecycle import State

#: Lines kept when nobody drains the journal.
JOURNAL_LINES = 256

#: What a harness lifecycle state means for the run, on the rig's terminal.
_RUN_NOTES: dict[int, str] = {
    State.RUNNING: "run started",
    State.DONE: "run ended: completed",
    State.TRIPPED: "run ended: tripped",
}
#: Why a drive fault latched, where the rig can tell the operator what to do.
_FAULT_NOTES: dict[int, str] = {
    FaultCode.HEARTBEAT_WATCHDOG: "the harness's heartbeats stopped (a run ended, or the harness died); "
                                  "the next run needs --reset-drive",
    FaultCode.COMMAND_WATCHDOG: "the harness's commands stopped while enabled; the next run needs --reset-drive",
    FaultCode.ESTOP: "an E-stop; release it, then the next run needs --reset-drive",
    FaultCode.PRESSURE_LOST: "hydraulic pressure lost; restore it, then the next run needs --reset-drive",
}


def _state_name(enum: type[IntEnum], value: int) -> str:
    try:
        return enum(int(value)).name
    except ValueError:
        return str(int(value))


class RigJournal:
    """A bounded queue of ``(wall time, line)`` and the state it last reported.

    Parameters
    ----------
    clock : callable
        Wall clock stamped on each line (s since the epoch).
    """

    def __init__(self, clock: Callable[[], float] = time.time):
        self.clock = clock
        self._lines: deque[tuple[float, str]] = deque(maxlen=JOURNAL_LINES)
        self.forget()

    def forget(self) -> None:
        """Forget the reported state (after the rig's reset): the next :meth:`watch` reports from OFF and idle."""
        self._drive = (int(DriveState.OFF), int(FaultCode.NONE))
        self._harness: int | None = None
        self._table_running = False

    def note(self, line: str) -> None:
        """Queue ``line`` (an event the watch cannot see: a reset, a table command)."""
        self._lines.append((self.clock(), line))

    def watch(self, drive_state: int, fault_code: int, harness_state: int | None, table_running: bool,
              record_time_s: float) -> None:
        """Queue a line for each of the drive, the harness and the table that changed since the last call.

        Parameters
        ----------
        drive_state, fault_code : int
            The drive's state and fault code (ACTUATOR_STATUS).
        harness_state : int or None
            The harness's lifecycle state from its latest heartbeat (None before the first).
        table_running : bool
        record_time_s : float
            Time into the record (s).
        """
        drive = (int(drive_state), int(fault_code))
        if drive != self._drive:
            self._drive = drive
            line = f"drive {_state_name(DriveState, drive_state)}"
            if drive_state in (DriveState.FAULT, DriveState.ESTOP):
                line += f", fault {fault_name(fault_code)}"
                note = _FAULT_NOTES.get(int(fault_code))
                line += f"; {note}" if note else "; the drive's own fault: the rig needs a reset or a restart"
            self.note(line)
        if harness_state is not None and harness_state != self._harness:
            self._harness = int(harness_state)
            line = f"harness {_state_name(State, harness_state)}"
            run_note = _RUN_NOTES.get(int(harness_state))
            self.note(f"{line}: {run_note}" if run_note else line)
        if table_running != self._table_running:
            self._table_running = bool(table_running)
            self.note("table started: record from 0 s" if table_running
                      else f"table stopped at record time {record_time_s:.2f} s")

    def drain(self) -> list[tuple[float, str]]:
        """Take every queued ``(wall time, line)`` off the queue, oldest first (from any thread)."""
        lines = []
        while True:
            try:
                lines.append(self._lines.popleft())
            except IndexError:
                return lines
