"""The loop's tick record: what each tick was given, kept exact so that ``harness replay`` can run it again.

A tick's command depends on the frames it consumed and on what the loop handed it: its time
``t`` and step ``dt``, its lateness and the stall before it (the supervisor's ``loop_stall``),
the deadlines missed, the operator's requests and whether the bus was gone. The frames are in
the run's ``can.log`` already, in the order the reader handled them; what it lacks is which
tick consumed which. So after every tick the loop notes, beside those figures, how many frames
the CAN log holds by then (:attr:`harness.recording.RunFolder.frames_recorded`): the frames of
tick ``k`` are the lines between the previous tick's mark and its own, and the lines before the
first mark are the traffic before the loop (the rig's first frames, the lockstep switch).

The record is a row of float64 values written through a preallocated array into the
recorder's bounded ring (nothing allocates in the tick; a full ring counts a drop, which makes
the record incomplete), and the recorder thread writes it in binary (``ticks.bin``): a
decimal text would round ``t`` and the lateness, and replay compares bit for bit.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from harness.realtime.memory import float_view

#: The values of one tick record, in order (``metadata.json`` ``tick_columns`` repeats them).
TICK_COLUMNS: tuple[str, ...] = (
    "t_s", "dt_s", "lateness_s", "stall_s", "missed_periods", "operator_stop", "operator_trip", "bus_gone", "can_frames",
)
T, DT, LATENESS, STALL, MISSED, OPERATOR_STOP, OPERATOR_TRIP, BUS_GONE, CAN_FRAMES = range(len(TICK_COLUMNS))


class TickLog:
    """Notes each tick's inputs into a recorder's tick ring.

    Parameters
    ----------
    record : callable
        ``record(values)``: queue one record (``RunFolder.record_tick``); never blocks.
    frames_recorded : callable
        ``frames_recorded() -> int``: frames the CAN log holds so far (``RunFolder.frames_recorded``).
    """

    def __init__(self, record: Callable[[np.ndarray], object], frames_recorded: Callable[[], int]):
        self._record = record
        self._frames_recorded = frames_recorded
        self.values = np.zeros(len(TICK_COLUMNS))
        self._mv = float_view(self.values)

    def start(self) -> None:
        """Mark where the loop begins in the CAN log: a record with ``t_s`` NaN (before the first tick)."""
        values = self._mv
        for i in range(len(TICK_COLUMNS)):
            values[i] = math.nan
        values[CAN_FRAMES] = self._frames_recorded()
        self._record(self.values)

    def note(
        self, t: float, dt: float, lateness_s: float, stall_s: float, missed: int, operator_stop: bool,
        operator_trip: bool, bus_gone: bool,
    ) -> None:
        """Record one tick: its time and step (s), its lateness and the stall before it (s), the deadlines missed,
        the operator's requests and the bus's loss as the tick saw them, and the CAN log's length after it."""
        values = self._mv
        values[T] = t
        values[DT] = dt
        values[LATENESS] = lateness_s
        values[STALL] = stall_s
        values[MISSED] = missed
        values[OPERATOR_STOP] = 1.0 if operator_stop else 0.0
        values[OPERATOR_TRIP] = 1.0 if operator_trip else 0.0
        values[BUS_GONE] = 1.0 if bus_gone else 0.0
        values[CAN_FRAMES] = self._frames_recorded()
        self._record(self.values)
