"""The receive side's checks and decoding, compiled: one frame, or every frame one poll took off the bus.

:class:`~drivers.protocol.decoder.Decoder` keeps its tables and state in the two arrays of
:class:`DecoderArrays` and decodes through :func:`decode_frame` (one frame, any bus) or
:func:`receive_datagrams` (every datagram waiting on a ``seqpacket`` socket, taken off it and
decoded in one call: the tick's path; :func:`decode_datagrams` decodes datagrams already taken).
All run the same checks in the same order, so there is one definition of them:

1. an identifier of the protocol (11-bit, a message this node receives): else ``UNKNOWN_ID``;
2. a data frame in the message's format (classic or CAN FD): else ``NOT_DATA``;
3. the DBC's length: else ``WRONG_LENGTH``;
4. the profile-2 CRC in byte 0 (:mod:`drivers.protocol.e2e`): else ``BAD_CRC``;
5. the rolling counter in the low nibble of byte 1 advanced by one: else ``REPEATED_COUNTER``
   (state kept) or ``SKIPPED_COUNTER`` (state resynchronised); the first frame after a reset passes;
6. every signal inside the DBC's range (raw integers within ``[raw_min, raw_max]``, floats within
   ``[minimum, maximum]``, NaN never): else ``OUT_OF_RANGE``.

A frame that passes them all replaces the message's latest values. The status codes are
:class:`~drivers.protocol.decoder.RxStatus`'s values. Signals are unpacked as
:meth:`drivers.protocol.codec.MessageCodec.unpack` does (Intel byte order, sign, scale and offset,
32-bit floats), which calls :func:`unpack_signals` with the codec's plan; the codec's tests
check it bit for bit against cantools.

The tick's path allocates nothing: every array is made once, with the decoder. The kernels
are compiled (or loaded from numba's cache) when the first decoder is made, never in a tick.
They keep the interpreter's lock while they run (no ``nogil``): a call takes microseconds, and
letting go of the lock in the tick would let the recorder's thread take it and make the loop
wait for it back.
"""

from __future__ import annotations

import errno
import socket
from typing import Any

import numba
import numpy as np
from numba import types

from drivers.protocol.e2e import COUNTER_MODULO, CRC8_2F_INIT, CRC8_2F_XOROUT, crc_table

# RxStatus values (drivers.protocol.decoder imports this module; the enum is checked against them there)
OK, UNKNOWN_ID, WRONG_LENGTH, BAD_CRC, REPEATED_COUNTER, SKIPPED_COUNTER, OUT_OF_RANGE, NOT_DATA = range(8)
#: Status of a frame the batch kernel leaves to the caller: an error frame or one on a foreign ID (never decoded).
NOT_DECODED = -1
#: Number of status codes.
STATUS_COUNT = 8

#: Columns of a signal's row in a plan (:func:`signal_plan`).
P_START, P_LENGTH, P_SIGNED, P_FLOAT, P_SCALE, P_OFFSET, P_RAW_MIN, P_RAW_MAX, P_MIN, P_MAX = range(10)
PLAN_COLUMNS = 10
#: Highest 11-bit identifier.
MAX_STANDARD_ID = 0x7FF

# frame flags (drivers.protocol.frame_flags; repeated as literals so the kernels see constants)
_EXTENDED, _REMOTE, _ERROR, _FD = 0x01, 0x02, 0x04, 0x08
#: The ``seqpacket`` datagram's header (drivers.protocol.datagram.HEADER, ``<IBB``): ID, flags, DLC.
HEADER_BYTES = 6
#: Largest valid datagram (bytes; drivers.protocol.datagram.MAX_DATAGRAM_BYTES): the header and 64 data bytes.
MAX_DATAGRAM_BYTES = HEADER_BYTES + 64
_ID_AT, _FLAGS_AT = 0, 4

CRC_TABLE = np.array(crc_table(), dtype=np.uint8)

# libc's recv(2) and errno, called by symbol from compiled code (no Python object, no exception per call)
_recv: Any = types.ExternalFunction("recv", types.intp(types.int32, types.uintp, types.uintp, types.int32))
_errno_location: Any = types.ExternalFunction("__errno_location", types.CPointer(types.int32)())
_DONTWAIT = int(socket.MSG_DONTWAIT)
#: How :func:`receive_datagrams` ended: the batch filled up (``max_frames``), nothing waited (``EAGAIN``),
#: the other side closed (end of file); anything else is ``-errno``.
CAPPED, EMPTY, END_OF_FILE = 1, -errno.EAGAIN, 0


def signal_plan(signals: object) -> np.ndarray:
    """The plan of a message's payload signals (:class:`~drivers.protocol.codec.SignalLayout` sequence): one row each.

    Columns :data:`P_START` ... :data:`P_MAX` (bits, 0/1 flags, the DBC's scale and offset, the
    raw integer range and the physical range). Every value is exact in a float64 (raw fields are
    at most 32 bits).
    """
    rows = [
        (s.start, s.length, float(s.signed), float(s.is_float), s.scale, s.offset, s.raw_min, s.raw_max, s.minimum, s.maximum)
        for s in signals  # type: ignore[attr-defined]
    ]
    return np.array(rows, dtype=np.float64).reshape(len(rows), PLAN_COLUMNS)


@numba.njit(cache=True)
def crc_profile2(data: np.ndarray, offset: int, length: int, data_ids: np.ndarray, table: np.ndarray) -> int:
    """CRC-8/2F of payload bytes 1..length-1 then the counter's Data-ID (:func:`drivers.protocol.e2e.profile2_crc`)."""
    crc = CRC8_2F_INIT
    for index in range(1, length):
        crc = table[crc ^ data[offset + index]]
    crc = table[crc ^ data_ids[data[offset + 1] & 0x0F]]
    return crc ^ CRC8_2F_XOROUT


@numba.njit(cache=True)
def unpack_signals(data: np.ndarray, offset: int, plan: np.ndarray, count: int, out: np.ndarray, scratch: np.ndarray) -> bool:
    """Unpack ``count`` signals of the payload at ``data[offset:]`` into ``out[:count]`` (SI); False if one is out of range.

    ``scratch`` is a one-element uint32 array (a 32-bit float's bits are reinterpreted through it).
    ``out`` is filled completely even when a value is out of range.
    """
    ok = True
    floats = scratch.view(np.float32)
    for i in range(count):
        start = int(plan[i, P_START])
        length = int(plan[i, P_LENGTH])
        first, shift = start // 8, start % 8
        word = np.uint64(0)
        for b in range((shift + length + 7) // 8):
            word |= np.uint64(data[offset + first + b]) << np.uint64(8 * b)
        raw_bits = (word >> np.uint64(shift)) & ((np.uint64(1) << np.uint64(length)) - np.uint64(1))
        if plan[i, P_FLOAT] != 0.0:
            scratch[0] = np.uint32(raw_bits)
            value = float(floats[0])
            if not plan[i, P_MIN] <= value <= plan[i, P_MAX]:
                ok = False
        else:
            raw = np.int64(raw_bits)
            if plan[i, P_SIGNED] != 0.0 and raw >= np.int64(1) << np.int64(length - 1):
                raw -= np.int64(1) << np.int64(length)
            value = raw * plan[i, P_SCALE] + plan[i, P_OFFSET]
            if not plan[i, P_RAW_MIN] <= raw <= plan[i, P_RAW_MAX]:
                ok = False
        out[i] = value
    return ok


# The decoder's state, packed so that a call passes two arrays (numba's dispatcher costs about a tenth of a
# microsecond per argument on a warm cache and ten times that in a tick that starts cold).
# ``ints`` (int64): a header of offsets, then the regions below; ``floats`` (float64): the plans, the
# latest values, the decoded values of a single frame. :class:`DecoderArrays` lays them out.
I_MESSAGES, I_SIGNALS, I_SLOT_OF_ID, I_SKIP, I_LENGTHS, I_FD, I_SIGNAL_COUNTS, I_DATA_IDS = range(8)
I_COUNTER_LAST, I_ACCEPTED, I_REJECTED, I_COUNTS, I_FLOAT_BITS = range(8, 13)
INT_HEADER = 13
#: Columns of a batch's per-frame integers: datagram size (bytes), identifier, flags, status, message slot.
F_SIZE, F_ID, F_FLAGS, F_STATUS, F_SLOT = range(5)
FRAME_COLUMNS = 5


class DecoderArrays:
    """The two arrays a decoder's kernels work on, and numpy views of their regions for Python.

    Parameters
    ----------
    messages : int
        Messages received (slots 0..messages-1).
    max_signals : int
        Most payload signals of one message.
    """

    def __init__(self, messages: int, max_signals: int):
        sizes = {
            I_SLOT_OF_ID: MAX_STANDARD_ID + 1, I_SKIP: MAX_STANDARD_ID + 1, I_LENGTHS: messages, I_FD: messages,
            I_SIGNAL_COUNTS: messages, I_DATA_IDS: messages * COUNTER_MODULO, I_COUNTER_LAST: messages,
            I_ACCEPTED: messages, I_REJECTED: messages * STATUS_COUNT, I_COUNTS: STATUS_COUNT, I_FLOAT_BITS: 1,
        }
        self.ints = np.zeros(INT_HEADER + sum(sizes.values()), dtype=np.int64)
        self.ints[I_MESSAGES], self.ints[I_SIGNALS] = messages, max_signals
        at = INT_HEADER
        regions = {}
        for key, size in sizes.items():
            self.ints[key] = at
            regions[key] = self.ints[at : at + size]
            at += size
        self.slot_of_id, self.skip_id = regions[I_SLOT_OF_ID], regions[I_SKIP]
        self.lengths, self.fd, self.signal_counts = regions[I_LENGTHS], regions[I_FD], regions[I_SIGNAL_COUNTS]
        self.data_ids = regions[I_DATA_IDS].reshape(messages, COUNTER_MODULO)
        self.counter_last, self.accepted = regions[I_COUNTER_LAST], regions[I_ACCEPTED]
        self.rejected = regions[I_REJECTED].reshape(messages, STATUS_COUNT)
        self.counts = regions[I_COUNTS]
        self.slot_of_id[:] = -1
        self.counter_last[:] = -1
        plan_size, value_size = messages * max_signals * PLAN_COLUMNS, messages * max_signals
        self.floats = np.zeros(plan_size + value_size + max_signals)
        self.plans = self.floats[:plan_size].reshape(messages, max_signals, PLAN_COLUMNS)
        self.values = self.floats[plan_size : plan_size + value_size].reshape(messages, max_signals)
        #: The values of the latest frame :func:`decode_frame` unpacked.
        self.out = self.floats[plan_size + value_size :]


@numba.njit(cache=True)
def _decode(
    frame_id: int, flags: int, data: np.ndarray, offset: int, size: int, ints: np.ndarray, floats: np.ndarray,
    out: np.ndarray,
) -> tuple[int, int]:
    """Check and decode one frame whose payload is ``data[offset:offset + size]``; ``(status, slot)``.

    ``slot`` is the message's row in the tables (-1 for an unknown identifier). On ``OK`` the
    message's latest values are replaced; ``out`` holds what was unpacked (the frame's own
    values, also for ``OUT_OF_RANGE``). Counts per status, per message and in all, are kept.
    """
    messages, max_signals = ints[I_MESSAGES], ints[I_SIGNALS]
    slot = -1
    if not flags & _EXTENDED and 0 <= frame_id <= MAX_STANDARD_ID:
        slot = ints[ints[I_SLOT_OF_ID] + frame_id]
    counts = ints[I_COUNTS]
    if slot < 0:
        ints[counts + UNKNOWN_ID] += 1
        return UNKNOWN_ID, -1
    status = OK
    data_ids = ints[ints[I_DATA_IDS] + slot * COUNTER_MODULO : ints[I_DATA_IDS] + (slot + 1) * COUNTER_MODULO]
    if flags & _REMOTE or (flags & _FD != 0) != (ints[ints[I_FD] + slot] != 0):
        status = NOT_DATA
    elif size != ints[ints[I_LENGTHS] + slot]:
        status = WRONG_LENGTH
    elif data[offset] != crc_profile2(data, offset, size, data_ids, CRC_TABLE):
        status = BAD_CRC
    else:
        counter = data[offset + 1] & 0x0F
        at = ints[I_COUNTER_LAST] + slot
        last = ints[at]
        if last < 0 or counter == (last + 1) % COUNTER_MODULO:
            ints[at] = counter
        elif counter == last:
            status = REPEATED_COUNTER
        else:
            ints[at] = counter
            status = SKIPPED_COUNTER
        if status == OK:
            n = ints[ints[I_SIGNAL_COUNTS] + slot]
            plans = floats[: messages * max_signals * PLAN_COLUMNS].reshape((messages, max_signals, PLAN_COLUMNS))
            float_bits = ints[I_FLOAT_BITS]
            scratch = ints[float_bits : float_bits + 1].view(np.uint32)
            if unpack_signals(data, offset, plans[slot], n, out, scratch):
                start = messages * max_signals * PLAN_COLUMNS + slot * max_signals
                floats[start : start + n] = out[:n]
                ints[ints[I_ACCEPTED] + slot] += 1
            else:
                status = OUT_OF_RANGE
    ints[counts + status] += 1
    if status != OK:
        ints[ints[I_REJECTED] + slot * STATUS_COUNT + status] += 1
    return status, slot


@numba.njit(cache=True)
def decode_frame(frame_id: int, flags: int, data: np.ndarray, ints: np.ndarray, floats: np.ndarray) -> tuple[int, int]:
    """Check and decode one frame (payload ``data``, flags of :mod:`drivers.protocol.frame_flags`); ``(status, slot)``.

    Its unpacked values are left in the ``out`` region of ``floats`` (:attr:`DecoderArrays.out`).
    """
    messages, max_signals = ints[I_MESSAGES], ints[I_SIGNALS]
    out = floats[messages * max_signals * (PLAN_COLUMNS + 1) :]
    return _decode(frame_id, flags, data, 0, len(data), ints, floats, out)


@numba.njit(cache=True)
def decode_datagrams(
    datagrams: np.ndarray, frame_ints: np.ndarray, frame_values: np.ndarray, start: int, frames: int, ints: np.ndarray,
    floats: np.ndarray,
) -> None:
    """Decode rows ``start..frames-1`` of ``datagrams`` (``seqpacket`` wire format), in order.

    ``frame_ints[k, F_SIZE]`` holds each datagram's size; per frame the kernel writes its
    identifier, flags, status (:data:`NOT_DECODED` for an error frame or a standard identifier
    marked to skip, the foreign ones, which the caller handles) and slot, and in ``frame_values``
    its own unpacked values, so the caller can act on each frame as if it had been decoded alone.
    """
    skip = ints[I_SKIP]
    for k in range(start, frames):
        row = datagrams[k]
        frame_id = int(row[_ID_AT]) | (int(row[_ID_AT + 1]) << 8) | (int(row[_ID_AT + 2]) << 16) | (int(row[_ID_AT + 3]) << 24)
        flags = int(row[_FLAGS_AT])
        frame_ints[k, F_ID] = frame_id
        frame_ints[k, F_FLAGS] = flags
        if flags & _ERROR or (not flags & _EXTENDED and 0 <= frame_id <= MAX_STANDARD_ID and ints[skip + frame_id] != 0):
            frame_ints[k, F_STATUS] = NOT_DECODED
            frame_ints[k, F_SLOT] = -1
            continue
        status, slot = _decode(
            frame_id, flags, row, HEADER_BYTES, frame_ints[k, F_SIZE] - HEADER_BYTES, ints, floats, frame_values[k],
        )
        frame_ints[k, F_STATUS] = status
        frame_ints[k, F_SLOT] = slot


@numba.njit(cache=True)
def receive_datagrams(
    fd: int, datagrams: np.ndarray, frame_ints: np.ndarray, frame_values: np.ndarray, capacity: int,
    ints: np.ndarray, floats: np.ndarray,
) -> tuple[int, int, int]:
    """Take every waiting datagram off socket ``fd`` into the rows of ``datagrams``, then decode them all.

    A non-blocking ``recv`` per datagram until none waits or ``capacity`` rows are filled, then
    :func:`decode_datagrams` over the rows filled. Returns ``(frames, end, malformed)``: the rows
    filled; how the receiving ended (:data:`CAPPED`, :data:`EMPTY`, :data:`END_OF_FILE`, or
    ``-errno`` of a failed ``recv``, which the caller hands to the bus's own path to judge); and the
    datagrams of a size no frame has, skipped (as :meth:`~drivers.transports.seqpacket.bus.SeqPacketBus.recv_datagram`
    skips them).
    """
    frames = 0
    malformed = 0
    end = CAPPED
    width = datagrams.shape[1]
    while frames < capacity:
        got = _recv(fd, datagrams[frames].ctypes.data, width, _DONTWAIT)
        if got <= 0:
            end = END_OF_FILE if got == 0 else -int(_errno_location()[0])
            break
        if got < HEADER_BYTES or got > MAX_DATAGRAM_BYTES:
            malformed += 1
            continue
        frame_ints[frames, F_SIZE] = got
        frames += 1
    decode_datagrams(datagrams, frame_ints, frame_values, 0, frames, ints, floats)
    return frames, end, malformed
