"""What each replayed tick is given: the frames it consumed and the figures the loop gave it, as the run recorded them.

:class:`ReplayBus` stands where the CAN bus stood: the harness's reader receives from it the frames
of ``can.log`` one tick's share at a time, and what the harness's writer sends is kept for the
comparison. :class:`ReplayFeed` stands where the loop's clock stood: its :meth:`ReplayFeed.wait`
takes the place of the real-time scheduler's (the tick's ``t`` and lateness as recorded) and its
:meth:`ReplayFeed.lockstep_wait` the place of the lockstep wait (the reader polls the tick's frames
at the tick's time, as the lockstep wait did). Past the recorded ticks it raises :class:`RecordEnded`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import can
import numpy as np

from harness.loop.tick_log import BUS_GONE, CAN_FRAMES, LATENESS, OPERATOR_STOP, OPERATOR_TRIP, T
from harness.replay.canlog import LoggedFrame

if TYPE_CHECKING:
    from drivers.reader import FrameReader
    from harness.loop.runner import ControlLoop


class RecordEnded(BaseException):  # noqa: N818 - not an error: the recorded input is used up
    """The replayed loop asked for a tick past the last one the run recorded (a BaseException, so the loop
    does not take it for a fault of its own)."""


class RecordedRequests:
    """The operator's requests as the run recorded them, in place of the loop's signal handlers.

    The replay installs no handler: a Ctrl-C during a replay ends the command as any other, and a
    request the run recorded is not handed on to the command line when the replayed loop ends.
    """

    def __init__(self) -> None:
        self.stop_requested = False
        self.trip_requested = False

    def install(self) -> None:
        """No handler: the requests come from the record."""

    def restore(self) -> None:
        """Nothing was installed."""


class ReplayBus:
    """A bus that hands out the run's received frames one span of ``can.log`` at a time and keeps what is sent.

    Parameters
    ----------
    frames : sequence of LoggedFrame
        The run's ``can.log``.
    """

    channel = "replay"
    channel_info = "replay of a run's can.log"

    def __init__(self, frames: Sequence[LoggedFrame]):
        self.frames = frames
        self._next = 0
        self._end = 0
        #: The frames sent, in order: (identifier, data).
        self.sent: list[tuple[int, bytes]] = []
        #: Receiving raises (the run's reader found the bus gone in this tick).
        self.gone = False

    def serve(self, start: int, end: int) -> None:
        """Hand out the received frames of ``can.log`` lines ``start`` to ``end`` (exclusive) next."""
        self._next, self._end = start, end

    @property
    def waiting(self) -> bool:
        """A received frame of the span is still to be handed out."""
        frames = self.frames
        for index in range(self._next, self._end):
            if frames[index].rx:
                return True
        return False

    def recv(self, timeout: float | None = None) -> Any:
        """The next received frame of the span, or None (never waits)."""
        if self.gone:
            raise can.CanError("the run's reader found the bus gone in this tick")
        frames, end = self.frames, self._end
        while self._next < end:
            frame = frames[self._next]
            self._next += 1
            if frame.rx:
                return frame
        return None

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        """Keep the frame (its identifier and data) for the comparison."""
        self.sent.append((msg.arbitration_id, bytes(msg.data)))

    def shutdown(self) -> None:
        """Nothing to close."""


class ReplayFeed:
    """The loop's clock and lockstep wait in a replay: each tick as the run recorded it.

    Parameters
    ----------
    ticks : ndarray
        The tick record (:mod:`harness.loop.tick_log`), the start mark removed.
    loop_start_frame : int
        ``can.log`` lines before the loop's first tick.
    bus : ReplayBus
    reader : FrameReader
        The harness's reader on ``bus``.
    period_s : float
        The loop's period (s): a lockstep tick ``k`` happened at ``k * period_s``.
    """

    def __init__(self, ticks: np.ndarray, loop_start_frame: int, bus: ReplayBus, reader: FrameReader, period_s: float):
        self.ticks = ticks
        self.bus = bus
        self.reader = reader
        self.period_s = period_s
        self.loop: ControlLoop | None = None
        self._bounds = [loop_start_frame, *(int(end) for end in ticks[:, CAN_FRAMES])]
        #: The tick being replayed (-1 before the first).
        self.k = -1
        self.lateness_s = 0.0
        self.overruns = 0
        self._last_t = 0.0

    # ---------------------------------------------------------------- before the loop
    def before_loop(self) -> None:
        """Let the reader handle the traffic before the loop, as it did then: polled at time 0."""
        bus = self.bus
        bus.serve(0, self._bounds[0])
        while bus.waiting:
            self.reader.poll(0.0, keep_fresh=True)

    # ---------------------------------------------------------------- the scheduler's place
    def start(self) -> float:
        """The scheduler's start (nothing to wait for)."""
        return 0.0

    @property
    def elapsed_s(self) -> float:
        """The latest replayed tick's time (s), for the sends after the loop."""
        return self._last_t

    def _begin(self, k: int) -> np.ndarray:
        """Tick ``k``: serve its frames and hand the loop its operator requests; raise :class:`RecordEnded` past the record."""
        if k >= len(self.ticks):
            raise RecordEnded(k)
        self.k = k
        record = self.ticks[k]
        previous_gone = k > 0 and self.ticks[k - 1, BUS_GONE] != 0.0
        self.bus.serve(self._bounds[k], self._bounds[k + 1])
        self.bus.gone = record[BUS_GONE] != 0.0 and not previous_gone and self.loop is not None and self.loop.lockstep is None
        loop = self.loop
        if loop is not None:
            loop.signals.stop_requested = record[OPERATOR_STOP] != 0.0
            loop.signals.trip_requested = record[OPERATOR_TRIP] != 0.0
        self._last_t = float(record[T])
        return record

    def wait(self) -> float:
        """In place of the real-time scheduler's wait: the next tick's recorded time (s) and lateness."""
        record = self._begin(self.k + 1)
        self.lateness_s = float(record[LATENESS])
        return float(record[T])

    def lockstep_wait(self, k: int, timeout_s: float) -> bool:
        """In place of the lockstep wait: poll tick ``k``'s frames at its time; False where the run's rig stopped answering."""
        record = self._begin(k)
        now = k * self.period_s
        self.reader.poll(now)
        while self.bus.waiting:
            self.reader.poll(now, keep_fresh=True)
        return record[BUS_GONE] == 0.0
