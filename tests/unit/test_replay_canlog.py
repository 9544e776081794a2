"""The replay's reading of can.log: every kind of frame the recorder writes comes back with its kind, data and direction."""

from __future__ import annotations

from pathlib import Path

import can
import pytest

from drivers.protocol.frame_flags import BRS, EXTENDED, FD, REMOTE, RX, flags_of
from harness.replay.canlog import CanLogError, read_can_log

FRAMES = [
    can.Message(timestamp=1.0, arbitration_id=0x30, data=bytes.fromhex("19090000f6fff7ff"), is_rx=True, is_extended_id=False),
    can.Message(timestamp=1.1, arbitration_id=0x20, data=bytes.fromhex("a1030000"), is_rx=False, is_extended_id=False),
    can.Message(timestamp=1.2, arbitration_id=0x12345, data=b"\x01", is_rx=True, is_extended_id=True),
    can.Message(timestamp=1.3, arbitration_id=0x40, is_remote_frame=True, is_rx=True, is_extended_id=False, dlc=0),
    can.Message(timestamp=1.4, arbitration_id=0x400, data=bytes(range(32)), is_fd=True, bitrate_switch=True, is_rx=True,
                is_extended_id=False),
]


def _log(tmp_path: Path, messages: list[can.Message]) -> Path:
    path = tmp_path / "can.log"
    writer = can.CanutilsLogWriter(path)
    for msg in messages:
        writer.on_message_received(msg)
    writer.stop()
    return path


def test_every_kind_of_frame_comes_back_as_the_recorder_wrote_it(tmp_path):
    frames = read_can_log(_log(tmp_path, FRAMES))
    assert len(frames) == len(FRAMES)
    for frame, msg in zip(frames, FRAMES, strict=True):
        assert frame.arbitration_id == msg.arbitration_id
        assert frame.rx == msg.is_rx
        assert flags_of(frame) == flags_of(msg)  # the reader takes the kind from these attributes
        assert frame.data == (b"" if msg.is_remote_frame else bytes(msg.data))
    assert flags_of(frames[2]) & EXTENDED and flags_of(frames[3]) & REMOTE
    assert flags_of(frames[4]) & (FD | BRS) == FD | BRS and not flags_of(frames[4]) & RX


def test_an_error_frame_is_read_as_one(tmp_path):
    error = can.Message(timestamp=2.0, arbitration_id=0x4, is_error_frame=True, data=bytes(8), is_extended_id=True)
    (frame,) = read_can_log(_log(tmp_path, [error]))
    assert frame.is_error_frame  # replay refuses such a log: the class is lost (harness/replay/recorded.py)


def test_a_line_that_is_no_frame_is_refused_naming_it(tmp_path):
    path = tmp_path / "can.log"
    path.write_text("(1.0) can0 030#00 R\nnot a frame\n")
    with pytest.raises(CanLogError, match="line 2"):
        read_can_log(path)
