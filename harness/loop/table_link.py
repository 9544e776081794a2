"""The harness's link to the shaking table's controller over CAN (profile ``table.link: can``).

A real test starts and stops the table with the same frames the virtual rig obeys:
RIG_CONTROL ``command`` START_TABLE when the run enters RUNNING, STOP_TABLE at the
end of the run and on a trip (the ``stop_table`` trip action); the table controller reports
RIG_STATUS ``table_running``, and the loop counts record time from the first tick that
sees it (:class:`harness.loop.runner.ControlLoop`, ``table_running``). With
``table.link: none`` there is no such link: the operator starts and stops the table, the
record time follows the harness's clock, and a trip cannot stop the table.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from drivers.protocol.protocol_values import RigCommand

if TYPE_CHECKING:
    from drivers.link import HarnessLink
    from drivers.reader import Sample
    from drivers.writer import HarnessWriter


class CanTableLink:
    """Start, stop and watch the table controller through RIG_CONTROL and RIG_STATUS.

    Parameters
    ----------
    lockstep : bool
        The RIG_CONTROL ``lockstep`` flag to send (False for a real table).

    Attributes
    ----------
    starts, stops : int
        Start and stop commands the bus took.
    """

    def __init__(self, lockstep: bool = False) -> None:
        self.lockstep = lockstep
        self.writer: HarnessWriter | None = None
        self._status: Sample | None = None
        self._running_i = 0
        self.starts = 0
        self.stops = 0

    def attach(self, link: HarnessLink) -> None:
        """Use the open harness ``link`` (its writer for RIG_CONTROL, its reader's RIG_STATUS sample)."""
        self.writer = link.writer
        status = self._status = link.reader.sample("RIG_STATUS")
        self._running_i = status.index("table_running")

    def start(self, t: float) -> None:
        """RUNNING begins: send RIG_CONTROL start table (``t`` is the loop's time, s)."""
        if self.writer is not None and self.writer.rig_control(RigCommand.START_TABLE, self.lockstep, t):
            self.starts += 1

    def stop(self, now: float) -> bool:
        """Send RIG_CONTROL stop table; True if the bus took it (never raises on a bus failure)."""
        if self.writer is None or not self.writer.rig_control(RigCommand.STOP_TABLE, self.lockstep, now):
            return False
        self.stops += 1
        return True

    def running(self) -> bool:
        """True when the newest RIG_STATUS says the table is running."""
        status = self._status
        return status is not None and status.count > 0 and status.values[self._running_i] == 1.0
