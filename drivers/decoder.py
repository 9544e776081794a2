"""The receive side of the codec: check, decode and count every frame; never raise.

:class:`Decoder` keeps, per received message, the rolling-counter state
(:class:`~drivers.e2e.CounterCheck`), a preallocated list of the latest accepted
SI values, and counts per :class:`RxStatus`. Checks, in order: known ID, data
frame in the message's format (classic or CAN FD, as the DBC says), length, CRC (with
the counter's Data-ID), counter, value ranges. The counter is checked before the ranges
so that a genuine frame with a bad value still advances the counter state (no double
count on the next frame).
"""

from __future__ import annotations

from collections.abc import Sequence
from enum import IntEnum

from drivers.codec import MessageCodec, Protocol
from drivers.e2e import CounterCheck, profile2_crc
from drivers.errors import ProtocolError


class RxStatus(IntEnum):
    """Outcome of decoding one received frame (``OK`` or the reason it was rejected)."""

    OK = 0
    UNKNOWN_ID = 1
    WRONG_LENGTH = 2
    BAD_CRC = 3
    REPEATED_COUNTER = 4
    SKIPPED_COUNTER = 5
    OUT_OF_RANGE = 6
    NOT_DATA = 7


class _RxState:
    """Receive state of one message: counter check, latest accepted values, counts."""

    __slots__ = ("codec", "counter", "values", "scratch", "accepted", "rejected")

    def __init__(self, codec: MessageCodec):
        self.codec = codec
        self.counter = CounterCheck()
        self.values = [0.0] * len(codec.signals)
        self.scratch = [0.0] * len(codec.signals)
        self.accepted = 0
        self.rejected = [0] * len(RxStatus)


class Decoder:
    """Decodes received frames into preallocated value lists, rejecting and counting bad ones.

    Parameters
    ----------
    protocol : Protocol
    names : sequence of str, optional
        The messages this node accepts; frames with other IDs are ``UNKNOWN_ID``.
        Default: every message of the protocol.

    Attributes
    ----------
    counts : list of int
        Frames per :class:`RxStatus` (``counts[RxStatus.BAD_CRC]`` ...), all messages.
    last : MessageCodec or None
        The message of the last frame that had a known ID.
    """

    def __init__(self, protocol: Protocol, names: Sequence[str] | None = None):
        chosen = list(protocol.messages) if names is None else list(names)
        self._states = {protocol[n].frame_id: _RxState(protocol[n]) for n in chosen}
        self._by_name = {s.codec.name: s for s in self._states.values()}
        self.counts = [0] * len(RxStatus)
        self.last: MessageCodec | None = None

    def values(self, name: str) -> list[float]:
        """The latest accepted values of message ``name`` (the same list object, updated in place)."""
        return self._state(name).values

    def accepted(self, name: str) -> int:
        """Frames of ``name`` accepted so far."""
        return self._state(name).accepted

    def rejected(self, name: str, status: RxStatus) -> int:
        """Frames of ``name`` rejected with ``status``."""
        return self._state(name).rejected[status]

    @property
    def rejected_total(self) -> int:
        """All rejected frames, every reason."""
        return sum(self.counts) - self.counts[RxStatus.OK]

    def reset_counters(self) -> None:
        """Forget every message's rolling-counter history (e.g. when a run starts)."""
        for state in self._states.values():
            state.counter.reset()

    def reset_counter(self, frame_id: int) -> None:
        """Forget the rolling-counter history of one message (a new sender): its next frame is accepted whatever its counter."""
        state = self._states.get(frame_id)
        if state is not None:
            state.counter.reset()

    def _state(self, name: str) -> _RxState:
        try:
            return self._by_name[name]
        except KeyError as err:
            raise ProtocolError(f"this decoder does not receive {name!r}; it receives: {', '.join(self._by_name)}") from err

    def decode(
        self, frame_id: int, data: bytes | bytearray, *, is_data_frame: bool = True, extended: bool = False, fd: bool = False,
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
        state = None if extended else self._states.get(frame_id)
        if state is None:
            self.last = None
            return self._count(None, RxStatus.UNKNOWN_ID)
        codec = state.codec
        self.last = codec
        if not is_data_frame or fd != codec.is_fd:
            return self._count(state, RxStatus.NOT_DATA)
        if len(data) != codec.length:
            return self._count(state, RxStatus.WRONG_LENGTH)
        if data[0] != profile2_crc(data, codec.length, codec.data_ids):
            return self._count(state, RxStatus.BAD_CRC)
        seq = state.counter.check(data[1] & 0x0F)
        if seq == CounterCheck.REPEATED:
            return self._count(state, RxStatus.REPEATED_COUNTER)
        if seq == CounterCheck.SKIPPED:
            return self._count(state, RxStatus.SKIPPED_COUNTER)
        if not codec.unpack(data, state.scratch):
            return self._count(state, RxStatus.OUT_OF_RANGE)
        state.values[:] = state.scratch
        state.accepted += 1
        return self._count(None, RxStatus.OK)

    def _count(self, state: _RxState | None, status: RxStatus) -> RxStatus:
        self.counts[status] += 1
        if state is not None:
            state.rejected[status] += 1
        return status
