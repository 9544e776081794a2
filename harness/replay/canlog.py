"""The run's ``can.log`` (candump ``-L`` format, :class:`can.CanutilsLogWriter`) read back frame by frame.

Each line is one frame the harness received (``R``) or sent (``T``), in the order its reader
handled them and its writer sent them. A frame read back carries the attributes the harness's
reader takes from a :class:`can.Message` (:func:`drivers.protocol.frame_flags.flags_of`), so the replay's
bus hands it to the reader as it is, without building a Message.
"""

from __future__ import annotations

from pathlib import Path

from harness.errors import HarnessError

#: The candump format's error-frame flag in the identifier field (SocketCAN's CAN_ERR_FLAG).
CAN_ERR_FLAG = 0x20000000
_CANFD_BRS, _CANFD_ESI = 0x01, 0x02


class CanLogError(HarnessError, ValueError):
    """A ``can.log`` line that is not a candump frame, or a frame replay cannot use."""


class LoggedFrame:
    """One frame of ``can.log``: its identifier, kind, data and direction (``rx``)."""

    __slots__ = (
        "timestamp", "arbitration_id", "is_extended_id", "is_remote_frame", "is_error_frame", "is_fd",
        "bitrate_switch", "error_state_indicator", "data", "channel", "rx",
    )

    def __init__(
        self, timestamp: float, frame_id: int, data: bytes, *, rx: bool, extended: bool = False, remote: bool = False,
        error: bool = False, fd: bool = False, brs: bool = False, esi: bool = False,
    ):
        self.timestamp = timestamp
        self.arbitration_id = frame_id
        self.is_extended_id = extended
        self.is_remote_frame = remote
        self.is_error_frame = error
        self.is_fd = fd
        self.bitrate_switch = brs
        self.error_state_indicator = esi
        self.data = data
        self.channel = None
        self.rx = rx


def read_can_log(path: Path) -> list[LoggedFrame]:
    """Every frame of ``path``, in order.

    Raises
    ------
    CanLogError
        A line that is not a candump frame (naming the line and what was expected).
    """
    frames: list[LoggedFrame] = []
    with open(path, encoding="ascii", errors="replace") as handle:
        for number, line in enumerate(handle, 1):
            try:
                frames.append(_frame(line))
            except (ValueError, IndexError) as err:
                raise CanLogError(
                    f"{path}, line {number}: found {line.strip()!r}, expected a candump frame '(TIME) CHANNEL ID#DATA R|T' "
                    f"({err})"
                ) from None
    return frames


def _frame(line: str) -> LoggedFrame:
    parts = line.split()
    timestamp = float(parts[0][1:-1])  # not used by the replay's reader (receive times are the poll's); kept for reading
    ident, hash_, payload = parts[2].partition("#")
    if not hash_:
        raise ValueError("no '#'")
    frame_id = int(ident, 16)
    rx = len(parts) > 3 and parts[3] == "R"
    if len(ident) == 8 and frame_id & CAN_ERR_FLAG:
        return LoggedFrame(timestamp, frame_id, bytes.fromhex(payload), rx=True, error=True)
    extended = len(ident) == 8
    if payload.startswith("R"):
        return LoggedFrame(timestamp, frame_id, b"", rx=rx, extended=extended, remote=True)
    if payload.startswith("#"):
        flags = int(payload[1], 16)
        return LoggedFrame(timestamp, frame_id, bytes.fromhex(payload[2:]), rx=rx, extended=extended, fd=True,
                           brs=bool(flags & _CANFD_BRS), esi=bool(flags & _CANFD_ESI))
    return LoggedFrame(timestamp, frame_id, bytes.fromhex(payload), rx=rx, extended=extended)
