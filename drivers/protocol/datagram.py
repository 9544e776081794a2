"""One CAN frame in one datagram: the layout of the datagram path and of the ``seqpacket`` interface's wire.

:data:`HEADER` (``<IBB``: arbitration ID, flags of :mod:`drivers.protocol.frame_flags`, DLC) followed by
the data (at most 64 bytes), one datagram per frame. The receiver stamps ``timestamp = time.time()`` on arrival
(the same wall clock as the sender's, so the two compare).

Three parts read or write it, so it lives with the protocol's other frame encoding (the flags): the
compiled receive of :mod:`drivers.protocol.frame_kernel` (its ``HEADER_BYTES`` and ``MAX_DATAGRAM_BYTES``,
which :mod:`drivers.protocol.decoder` checks against these), a bus that offers the datagram path
(:class:`~drivers.transports.datagram_path.DatagramPath`: the reader and writer hand it frames in this
layout), and the ``seqpacket`` interface (:mod:`drivers.transports.seqpacket`), whose wire it is.
"""

from __future__ import annotations

import struct
import time

from can import Message

from drivers.protocol.frame_flags import BRS, ERROR, ESI, EXTENDED, FD, REMOTE, flags_of

#: Frame header: arbitration ID, flags (:mod:`drivers.protocol.frame_flags`, never ``RX``), DLC; the data follows.
HEADER = struct.Struct("<IBB")
#: Largest data field (bytes; CAN FD).
MAX_DATA_BYTES = 64
#: Largest valid datagram (bytes).
MAX_DATAGRAM_BYTES = HEADER.size + MAX_DATA_BYTES


def encode_frame(msg: Message) -> bytes:
    """One frame's datagram: :data:`HEADER` then the data.

    Raises
    ------
    ValueError
        More than 64 data bytes, or an ID or DLC that does not fit the header.
    """
    flags = flags_of(msg)
    if not flags & FD:
        flags &= ~(BRS | ESI)  # only an FD frame has them
    data = msg.data
    if len(data) > MAX_DATA_BYTES:
        raise ValueError(f"frame 0x{msg.arbitration_id:x} has {len(data)} data bytes; at most {MAX_DATA_BYTES}")
    try:
        return HEADER.pack(msg.arbitration_id, flags, msg.dlc) + data
    except struct.error as err:
        raise ValueError(f"frame ID {msg.arbitration_id!r} or DLC {msg.dlc!r} does not fit a CAN frame: {err}") from err


#: Every attribute python-can's Message.__init__ sets. When they are exactly its slots, a received
#: frame skips the keyword call (a third of its cost, once per frame per tick): the object is
#: made bare and every field set below; otherwise ``Message()`` makes it and the same lines set it.
_MESSAGE_FIELDS = frozenset({
    "timestamp", "arbitration_id", "is_extended_id", "is_remote_frame", "is_error_frame", "channel", "is_fd",
    "is_rx", "bitrate_switch", "error_state_indicator", "data", "dlc",
})
_BARE_MESSAGE_OK = set(getattr(Message, "__slots__", ())) - {"__weakref__"} == _MESSAGE_FIELDS


def _new_message() -> Message:
    return Message.__new__(Message) if _BARE_MESSAGE_OK else Message()


def decode_frame(buf: bytearray, size: int, channel: str) -> Message | None:
    """The Message in ``buf[:size]``, stamped ``time.time()``; None when malformed."""
    if size < HEADER.size or size > MAX_DATAGRAM_BYTES:
        return None
    arbitration_id, flags, dlc = HEADER.unpack_from(buf)
    msg = _new_message()
    msg.timestamp = time.time()
    msg.arbitration_id = arbitration_id
    msg.is_extended_id = bool(flags & EXTENDED)
    msg.is_remote_frame = bool(flags & REMOTE)
    msg.is_error_frame = bool(flags & ERROR)
    msg.is_fd = bool(flags & FD)
    msg.bitrate_switch = bool(flags & BRS)
    msg.error_state_indicator = bool(flags & ESI)
    msg.dlc = dlc
    msg.data = bytearray() if flags & REMOTE else buf[HEADER.size:size]
    msg.channel = channel
    msg.is_rx = True
    return msg
