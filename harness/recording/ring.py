"""Preallocated single-producer/single-consumer rings that the real-time tick writes into.

The tick (producer) copies one row into a preallocated slot and advances a write
counter; the writer thread (consumer) copies every pending slot out in one block and
advances a read counter. Nothing blocks: when the ring is full the row is dropped
and counted. Each counter is written by one side only, and a slot is published
(counter advanced) only after it has been filled, so under CPython's GIL no lock is
needed. Measured on the 2-vCPU VM (see ``logs/README.md``): ``RowRing.push`` of a
40-column float64 ndarray row takes about 0.5 us and allocates nothing (1.4 us from
a tuple); ``queue.Queue.put_nowait(row.copy())`` takes about 1.7 us, allocates
about 440 bytes per tick (garbage the collector must later walk) and takes a lock
the consumer also holds. ``FrameRing.push`` copies a frame's fields in about 1 us.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import can
import numpy as np

from drivers.protocol.frame_flags import RX, flags_of, message_of
from harness.errors import HarnessError
from harness.realtime.memory import float_view, prefaulted_zeros

MAX_DATA = 64


class RecordingError(HarnessError, ValueError):
    """A row or frame handed to the recorder does not fit (e.g. wrong number of values)."""


class RowRing:
    """A ring of ``capacity`` rows of ``n_columns`` float64 values.

    Parameters
    ----------
    n_columns : int
        Values per row.
    capacity : int
        Rows the ring holds before it drops (at 1 kHz, 4096 rows are about 4 s).
    """

    def __init__(self, n_columns: int, capacity: int):
        if n_columns < 1 or capacity < 1:
            raise ValueError(f"found n_columns={n_columns}, capacity={capacity}; expected both >= 1")
        self._buffer = np.full((capacity, n_columns), np.nan)
        self._capacity = capacity
        self._n_columns = n_columns
        self._write = 0
        self._read = 0
        self.dropped = 0

    @property
    def capacity(self) -> int:
        """Rows the ring holds."""
        return self._capacity

    @property
    def pending(self) -> int:
        """Rows written and not yet drained."""
        return self._write - self._read

    @property
    def pushed(self) -> int:
        """Rows accepted since creation."""
        return self._write

    def push(self, values: Sequence[float] | np.ndarray) -> bool:
        """Copy one row in; never blocks.

        Parameters
        ----------
        values : ndarray or sequence of float
            Exactly ``n_columns`` values, in column order.

        Returns
        -------
        bool
            False if the ring was full and the row was dropped (and counted).
        """
        if len(values) != self._n_columns:
            raise RecordingError(f"found a row of {len(values)} values, expected {self._n_columns}")
        write = self._write
        if write - self._read >= self._capacity:
            self.dropped += 1
            return False
        self._buffer[write % self._capacity] = values
        self._write = write + 1
        return True

    def drain(self, max_rows: int | None = None) -> np.ndarray:
        """Copy out the pending rows (at most ``max_rows``), oldest first, and free their slots (consumer side).

        Returns
        -------
        ndarray, shape (k, n_columns)
        """
        read = self._read
        count = self._write - read
        if max_rows is not None:
            count = min(count, max_rows)
        start = read % self._capacity
        if start + count <= self._capacity:
            block = self._buffer[start : start + count].copy()
        else:
            first = self._capacity - start
            block = np.concatenate((self._buffer[start:], self._buffer[: count - first]))
        self._read = read + count
        return block


class FrameRing:
    """A ring of CAN frames stored field by field in preallocated arrays.

    Parameters
    ----------
    capacity : int
        Frames the ring holds before it drops.
    """

    def __init__(self, capacity: int):
        if capacity < 1:
            raise ValueError(f"found capacity={capacity}, expected >= 1")
        self._capacity = capacity
        self._timestamp = prefaulted_zeros(capacity)
        self._arbitration_id = prefaulted_zeros(capacity, dtype=np.uint32)
        self._dlc = prefaulted_zeros(capacity, dtype=np.uint8)
        self._flags = prefaulted_zeros(capacity, dtype=np.uint8)
        self._channel = prefaulted_zeros(capacity, dtype=np.int16)
        self._data = bytearray(capacity * MAX_DATA)
        self._data_view = memoryview(self._data)
        # the tick writes through memoryviews of the same memory: a third of a numpy item store
        self._timestamp_mv = float_view(self._timestamp)
        self._id_mv = self._arbitration_id.data  # memoryview(array): integer items
        self._dlc_mv = self._dlc.data
        self._flags_mv = self._flags.data
        self._channel_mv = self._channel.data
        self._channels: dict[Any, int] = {None: 0}
        self._channel_names: list[Any] = [None]
        self._write = 0
        self._read = 0
        self.dropped = 0

    @property
    def pending(self) -> int:
        """Frames written and not yet drained."""
        return self._write - self._read

    @property
    def pushed(self) -> int:
        """Frames accepted since creation."""
        return self._write

    def push(self, msg: can.Message, rx: bool | None = None, timestamp: float | None = None) -> bool:
        """Copy the fields of ``msg`` in; never blocks. False if full (dropped and counted).

        Parameters
        ----------
        msg : can.Message
            The frame; not modified.
        rx : bool, optional
            Its direction as the recorder should log it (default ``msg.is_rx``).
        timestamp : float, optional
            Its time as the recorder should log it (s; default ``msg.timestamp``).
        """
        flags = flags_of(msg) | (RX if (msg.is_rx if rx is None else rx) else 0)
        data = msg.data if msg.data is not None else b""
        return self.push_fields(msg.timestamp if timestamp is None else timestamp, msg.arbitration_id, flags, data, msg.channel)

    def push_fields(
        self, timestamp: float, frame_id: int, flags: int, data: bytes | bytearray | memoryview, channel: Any = None
    ) -> bool:
        """Copy one frame in from its fields; never blocks. False if full (dropped and counted).

        A reader's and a writer's tap (:data:`drivers.protocol.frame_flags.FrameTap`) on the recorder's CAN log.

        Parameters
        ----------
        timestamp : float
            Its time as the recorder should log it (s, wall clock).
        frame_id : int
            Arbitration ID.
        flags : int
            Its kind and direction (:mod:`drivers.protocol.frame_flags`, :data:`~drivers.protocol.frame_flags.RX` for received).
        data : bytes-like
            The data field (at most 64 bytes); copied.
        channel : optional
            The channel it was seen on (logs name it).
        """
        write = self._write
        if write - self._read >= self._capacity:
            self.dropped += 1
            return False
        size = len(data)
        if size > MAX_DATA:
            raise RecordingError(f"found a CAN frame with {size} data bytes, expected at most {MAX_DATA}")
        slot = write % self._capacity
        self._timestamp_mv[slot] = timestamp
        self._id_mv[slot] = frame_id
        self._dlc_mv[slot] = size
        self._flags_mv[slot] = flags
        index = self._channels.get(channel)
        self._channel_mv[slot] = index if index is not None else self._channel_index(channel)
        if size:
            offset = slot * MAX_DATA
            self._data_view[offset : offset + size] = data
        self._write = write + 1
        return True

    def _channel_index(self, channel: Any) -> int:
        index = self._channels.get(channel)
        if index is None:
            index = len(self._channel_names)
            self._channel_names.append(channel)
            self._channels[channel] = index
        return index

    def drain(self, max_frames: int | None = None) -> list[can.Message]:
        """Rebuild the pending frames (at most ``max_frames``) as :class:`can.Message`, oldest first (consumer side)."""
        read = self._read
        count = self._write - read
        if max_frames is not None:
            count = min(count, max_frames)
        messages = [self._message(slot % self._capacity) for slot in range(read, read + count)]
        self._read = read + count
        return messages

    def _message(self, slot: int) -> can.Message:
        size = int(self._dlc[slot])
        offset = slot * MAX_DATA
        return message_of(
            float(self._timestamp[slot]), int(self._arbitration_id[slot]), int(self._flags[slot]),
            self._data[offset : offset + size], self._channel_names[int(self._channel[slot])],
        )
