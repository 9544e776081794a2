"""The receive side of the codec: check, decode and count every frame; never raise.

:class:`Decoder` keeps, per received message, the rolling-counter state, a preallocated
list of the latest accepted SI values, and counts per :class:`RxStatus`, in the arrays the
compiled checks of :mod:`drivers.protocol.frame_kernel` work on. Checks, in order: known ID, data
frame in the message's format (classic or CAN FD, as the DBC says), length, CRC (with
the counter's Data-ID), counter, value ranges. The counter is checked before the ranges
so that a genuine frame with a bad value still advances the counter state (no double
count on the next frame). :meth:`Decoder.decode` judges one frame (any bus);
:meth:`Decoder.decode_datagrams` judges a poll's ``seqpacket`` datagrams in one call.
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import IntEnum

import numpy as np

from drivers.errors import ProtocolError
from drivers.protocol import frame_kernel as kernel
from drivers.protocol.codec import MessageCodec, Protocol
from drivers.protocol.datagram import HEADER, MAX_DATAGRAM_BYTES
from drivers.protocol.frame_flags import EXTENDED, FD, REMOTE

assert (HEADER.size, MAX_DATAGRAM_BYTES) == (kernel.HEADER_BYTES, kernel.MAX_DATAGRAM_BYTES), \
    "the kernel reads the seqpacket datagram as drivers.protocol.datagram writes it"


class RxStatus(IntEnum):
    """Outcome of decoding one received frame (``OK`` or the reason it was rejected)."""

    OK = kernel.OK
    UNKNOWN_ID = kernel.UNKNOWN_ID
    WRONG_LENGTH = kernel.WRONG_LENGTH
    BAD_CRC = kernel.BAD_CRC
    REPEATED_COUNTER = kernel.REPEATED_COUNTER
    SKIPPED_COUNTER = kernel.SKIPPED_COUNTER
    OUT_OF_RANGE = kernel.OUT_OF_RANGE
    NOT_DATA = kernel.NOT_DATA


#: Status by code, for the kernels' integer statuses (a list index, not an enum call, in the tick).
STATUS_OF = tuple(RxStatus(code) for code in range(kernel.STATUS_COUNT))


class DatagramBatch:
    """Preallocated arrays for one poll's ``seqpacket`` datagrams and what :meth:`Decoder.decode_datagrams` made of them.

    Parameters
    ----------
    capacity : int
        Most frames one batch holds (the reader's ``max_frames``).
    max_signals : int
        Most signals a received message carries (the decoder's).

    Attributes
    ----------
    rows : list of memoryview
        Writable views of the datagram rows, one per frame (``recv_into`` targets).
    frame_ints, flat_ints : memoryview
        Per frame (``frame_ints[k, column]``, columns :data:`~drivers.protocol.frame_kernel.F_SIZE` ...; ``flat_ints``
        the same memory in one dimension): datagram
        size (bytes, the caller writes it), identifier, flags (:mod:`drivers.protocol.frame_flags`), status code
        (:data:`drivers.protocol.frame_kernel.NOT_DECODED` for an error frame or a foreign identifier), message slot.
    value_rows : list of memoryview
        Per frame, the values it carried.
    """

    def __init__(self, capacity: int, max_signals: int):
        self.datagrams = np.zeros((capacity, MAX_DATAGRAM_BYTES + 1), dtype=np.uint8)  # one byte more: an oversize one shows
        self.rows = [row.data for row in self.datagrams]
        self.ints = np.zeros((capacity, kernel.FRAME_COLUMNS), dtype=np.int64)
        self.frame_ints = self.ints.data
        #: The same, flat: frame ``k``'s column ``c`` at ``k * FRAME_COLUMNS + c`` (no index tuple to build).
        self.flat_ints = self.ints.reshape(-1).data
        self.frame_values = np.zeros((capacity, max_signals))
        self.value_rows = [row.data for row in self.frame_values]


class Decoder:
    """Decodes received frames into preallocated value lists, rejecting and counting bad ones.

    The checks and the decoding are :mod:`drivers.protocol.frame_kernel`'s, on this decoder's arrays.

    Parameters
    ----------
    protocol : Protocol
    names : sequence of str, optional
        The messages this node accepts; frames with other IDs are ``UNKNOWN_ID``.
        Default: every message of the protocol.
    skip : sequence of str, optional
        Messages :meth:`decode_datagrams` leaves to the caller (foreign identifiers, not decoded).

    Attributes
    ----------
    counts : memoryview of int
        Frames per :class:`RxStatus` (``counts[RxStatus.BAD_CRC]`` ...), all messages.
    last : MessageCodec or None
        The message of the last frame that had a known ID.
    """

    def __init__(self, protocol: Protocol, names: Sequence[str] | None = None, skip: Sequence[str] = ()):
        chosen = list(protocol.messages) if names is None else list(names)
        self._codecs = tuple(protocol[n] for n in chosen)
        self._slot = {codec.name: k for k, codec in enumerate(self._codecs)}
        count = len(self._codecs)
        self.max_signals = max([len(codec.signals) for codec in self._codecs] + [1])
        self._arrays = arrays = kernel.DecoderArrays(count, self.max_signals)
        for k, codec in enumerate(self._codecs):
            arrays.slot_of_id[codec.frame_id] = k
            arrays.lengths[k], arrays.fd[k], arrays.signal_counts[k] = codec.length, codec.is_fd, len(codec.signals)
            arrays.data_ids[k] = codec.data_ids
            arrays.plans[k, : len(codec.signals)] = codec.plan
        for name in skip:
            arrays.skip_id[protocol[name].frame_id] = 1
        self._ints, self._floats = arrays.ints, arrays.floats
        self.counts = arrays.counts.data
        #: Per message, the list :meth:`values` hands out (a copy of its row, refreshed on every accepted frame).
        self._lists = tuple([0.0] * len(codec.signals) for codec in self._codecs)
        self._out_rows = tuple(arrays.out[: len(codec.signals)].data for codec in self._codecs)
        self.last: MessageCodec | None = None
        # compile the kernels (or load them from numba's cache) now, at configure time, never in a tick
        self.decode(-1, b"")
        self.decode_datagrams(self.batch(1), 0, 0)
        self.receive_datagrams(-1, self.batch(1), 1)  # a bad descriptor: recv fails at once, nothing is read
        arrays.counts[:] = 0

    def values(self, name: str) -> list[float]:
        """The latest accepted values of message ``name`` (the same list object, updated in place)."""
        return self._lists[self._state(name)]

    def accepted(self, name: str) -> int:
        """Frames of ``name`` accepted so far."""
        return int(self._arrays.accepted[self._state(name)])

    def rejected(self, name: str, status: RxStatus) -> int:
        """Frames of ``name`` rejected with ``status``."""
        return int(self._arrays.rejected[self._state(name), status])

    @property
    def rejected_total(self) -> int:
        """All rejected frames, every reason."""
        counts = self._arrays.counts
        return int(counts.sum() - counts[RxStatus.OK])

    def reset_counters(self) -> None:
        """Forget every message's rolling-counter history (e.g. when a run starts)."""
        self._arrays.counter_last[:] = -1

    def reset_counter(self, frame_id: int) -> None:
        """Forget the rolling-counter history of one message (a new sender): its next frame is accepted whatever its counter."""
        arrays = self._arrays
        if 0 <= frame_id <= kernel.MAX_STANDARD_ID and arrays.slot_of_id[frame_id] >= 0:
            arrays.counter_last[arrays.slot_of_id[frame_id]] = -1

    def _state(self, name: str) -> int:
        try:
            return self._slot[name]
        except KeyError as err:
            raise ProtocolError(f"this decoder does not receive {name!r}; it receives: {', '.join(self._slot)}") from err

    def decode(
        self, frame_id: int, data: bytes | bytearray | memoryview, *, is_data_frame: bool = True, extended: bool = False,
        fd: bool = False,
    ) -> RxStatus:
        """Check and decode one frame; never raises.

        On ``OK`` the message's :meth:`values` list is updated in place; on a
        rejection it keeps its previous contents.

        Parameters
        ----------
        frame_id : int
            Arbitration ID.
        data : bytes-like
            Payload.
        is_data_frame : bool
            False for remote or error frames (rejected as ``NOT_DATA``).
        extended : bool
            A 29-bit identifier: never one of the protocol's (``UNKNOWN_ID``).
        fd : bool
            The frame is a CAN FD frame; one whose format is not the message's (an FD frame on a
            classic ID, a classic frame on an FD ID) is rejected as ``NOT_DATA``.
        """
        flags = (0 if is_data_frame else REMOTE) | (EXTENDED if extended else 0) | (FD if fd else 0)
        payload = np.frombuffer(data, dtype=np.uint8)
        status, slot = kernel.decode_frame(frame_id, flags, payload, self._ints, self._floats)
        self.last = self._codecs[slot] if slot >= 0 else None
        if status == kernel.OK:
            self._lists[slot][:] = self._out_rows[slot]
        return STATUS_OF[status]

    def batch(self, capacity: int) -> DatagramBatch:
        """Arrays for :meth:`decode_datagrams` of up to ``capacity`` frames (made once, by the reader)."""
        return DatagramBatch(capacity, self.max_signals)

    def decode_datagrams(self, batch: DatagramBatch, start: int, frames: int) -> None:
        """Check and decode datagrams ``start..frames-1`` of ``batch`` in one compiled call, in order.

        Each frame is judged as :meth:`decode` would judge it alone, and its status, slot and own
        values are left in ``batch``; the messages' :meth:`values` lists are not touched:
        :meth:`take` hands an accepted frame's values over, frame by frame, as the caller goes.
        """
        kernel.decode_datagrams(batch.datagrams, batch.ints, batch.frame_values, start, frames, self._ints, self._floats)
        self._note_last(batch, frames)

    def receive_datagrams(self, fd: int, batch: DatagramBatch, capacity: int) -> tuple[int, int, int]:
        """Take the datagrams waiting on socket ``fd`` into ``batch`` and decode them, in one compiled call.

        Returns ``(frames, end, malformed)`` as :func:`drivers.protocol.frame_kernel.receive_datagrams`;
        the frames are left in ``batch`` as :meth:`decode_datagrams` leaves them.
        """
        frames, end, malformed = kernel.receive_datagrams(
            fd, batch.datagrams, batch.ints, batch.frame_values, capacity, self._ints, self._floats,
        )
        self._note_last(batch, frames)
        return frames, end, malformed

    def _note_last(self, batch: DatagramBatch, frames: int) -> None:
        """:attr:`last` after a batch: the message of its last decoded frame (None for an unknown identifier)."""
        ints = batch.frame_ints
        for k in range(frames - 1, -1, -1):
            if ints[k, kernel.F_STATUS] != kernel.NOT_DECODED:
                slot = ints[k, kernel.F_SLOT]
                self.last = self._codecs[slot] if slot >= 0 else None
                return

    def take(self, batch: DatagramBatch, frame: int) -> None:
        """Make the values of accepted ``frame`` of ``batch`` its message's latest (:meth:`values`)."""
        target = self._lists[batch.frame_ints[frame, kernel.F_SLOT]]
        target[:] = batch.value_rows[frame][: len(target)]
