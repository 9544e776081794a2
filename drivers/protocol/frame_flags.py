"""One encoding of a CAN frame's kind in a small integer, shared by the wire, the reader, the writer and the log.

python-can describes a frame's kind with seven booleans on :class:`can.Message`. The paths that
never build a Message (the ``seqpacket`` datagram, :meth:`drivers.reader.FrameReader.poll` on a
bus that hands over raw frames, the recorder's frame ring) carry them as bits of one integer:

========== ===== ==========================================
flag       bit   ``can.Message`` attribute
========== ===== ==========================================
EXTENDED   0x01  ``is_extended_id`` (29-bit identifier)
REMOTE     0x02  ``is_remote_frame``
ERROR      0x04  ``is_error_frame``
FD         0x08  ``is_fd``
BRS        0x10  ``bitrate_switch``
ESI        0x20  ``error_state_indicator``
RX         0x40  ``is_rx`` (only in the recorder's ring: the wire never carries a direction)
========== ===== ==========================================
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import can

EXTENDED = 0x01
REMOTE = 0x02
ERROR = 0x04
FD = 0x08
BRS = 0x10
ESI = 0x20
RX = 0x40
#: A reader's or writer's tap, called with every frame it received or sent, e.g. the recorder's CAN log:
#: ``tap(timestamp, frame_id, flags, data, channel)``: the time in s (wall clock), the flags with :data:`RX`
#: set for a received frame, ``data`` valid only during the call (copy what you keep).
FrameTap = Callable[[float, int, int, "bytes | bytearray | memoryview", object], object]
#: Frames the protocol's decoder never reads: a 29-bit identifier, a remote or an error frame.
NOT_PROTOCOL_DATA = EXTENDED | REMOTE | ERROR


def flags_of(msg: can.Message) -> int:
    """The flags of ``msg`` (without :data:`RX`, which the caller decides)."""
    return (
        (EXTENDED if msg.is_extended_id else 0)
        | (REMOTE if msg.is_remote_frame else 0)
        | (ERROR if msg.is_error_frame else 0)
        | (FD if msg.is_fd else 0)
        | (BRS if msg.bitrate_switch else 0)
        | (ESI if msg.error_state_indicator else 0)
    )


def message_of(
    timestamp: float, frame_id: int, flags: int, data: bytes | bytearray | memoryview, channel: Any = None
) -> can.Message:
    """A :class:`can.Message` with these fields (allocates: for logs and rare frames, not per tick)."""
    return can.Message(
        timestamp=timestamp, arbitration_id=frame_id, is_extended_id=bool(flags & EXTENDED),
        is_remote_frame=bool(flags & REMOTE), is_error_frame=bool(flags & ERROR), is_fd=bool(flags & FD),
        bitrate_switch=bool(flags & BRS), error_state_indicator=bool(flags & ESI), is_rx=bool(flags & RX),
        dlc=len(data), data=bytearray(data), channel=channel,
    )
