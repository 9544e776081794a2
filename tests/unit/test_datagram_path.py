"""The datagram path (drivers/transports/datagram_path.py): a capability, not a backend's name.

The generic reader and writer talk to :class:`can.BusABC`; a bus that implements
:class:`~drivers.transports.datagram_path.DatagramPath` gets the path without a :class:`can.Message`,
whatever its class, and a plain python-can bus keeps ``send``/``recv``. The ``seqpacket`` bus
advertises the capability.
"""

from __future__ import annotations

import uuid

import can
import pytest

from drivers.protocol.codec import load_protocol
from drivers.protocol.datagram import encode_frame
from drivers.reader import HarnessReader
from drivers.transports.datagram_path import DatagramPath, datagram_path
from drivers.transports.seqpacket.bus import SeqPacketBus
from drivers.writer import HarnessWriter, RigWriter

PROTOCOL = load_protocol()
NOW_S = 3.25


class PlainBus(can.BusABC):
    """A python-can bus with only ``send`` and ``recv``: it records what it is sent and hands out a list."""

    def __init__(self) -> None:
        self.sent: list[can.Message] = []
        self.pending: list[can.Message] = []
        super().__init__(channel="plain")

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        self.sent.append(msg)

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        return (self.pending.pop(0) if self.pending else None), False


class FakeDatagramBus(PlainBus):
    """A bus of no backend of this project that implements :class:`DatagramPath`; its Message path fails."""

    def __init__(self, raw_receive_ok: bool = True) -> None:
        super().__init__()
        self.channel = "fake"
        self.datagrams_sent: list[bytes] = []
        self.datagrams_waiting: list[bytes] = []
        self.datagram_reads = 0
        self._raw_receive_ok = raw_receive_ok

    @property
    def raw_receive_ok(self) -> bool:
        return self._raw_receive_ok

    @property
    def direct_fd(self) -> int:
        return -1  # no socket of its own: the reader takes each datagram through recv_datagram

    def note_direct_receive(self, malformed: int) -> None:
        raise AssertionError("never called: direct_fd is -1")

    def recv_datagram(self, into: memoryview | bytearray | None = None) -> int:
        self.datagram_reads += 1
        if not self.datagrams_waiting or into is None:
            return 0
        frame = self.datagrams_waiting.pop(0)
        into[: len(frame)] = frame
        return len(frame)

    def send_datagram(self, frame: bytes | bytearray | memoryview) -> None:
        self.datagrams_sent.append(bytes(frame))

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        raise AssertionError("a bus with the datagram path is sent datagrams")


def _table_frame(x0: float) -> can.Message:
    """A TABLE_SENSORS frame as the rig sends it, through a plain bus."""
    rig_bus = PlainBus()
    RigWriter(rig_bus, PROTOCOL).table(x0, 0.0, 0.0, NOW_S)
    (msg,) = rig_bus.sent
    return msg


def test_a_bus_that_implements_the_capability_offers_the_path() -> None:
    bus = FakeDatagramBus()
    assert isinstance(bus, DatagramPath)
    assert datagram_path(bus) is bus


def test_a_plain_python_can_bus_does_not() -> None:
    bus = PlainBus()
    assert not isinstance(bus, DatagramPath)
    assert datagram_path(bus) is None
    virtual = can.Bus(interface="virtual", channel=f"plain-{uuid.uuid4().hex}")
    try:
        assert datagram_path(virtual) is None, "python-can's own backends keep recv and send"
    finally:
        virtual.shutdown()


def test_the_seqpacket_bus_advertises_the_capability() -> None:
    bus = SeqPacketBus(f"test-{uuid.uuid4().hex}")
    try:
        assert isinstance(bus, DatagramPath)
        assert datagram_path(bus) is bus
    finally:
        bus.shutdown()


def test_the_writer_sends_datagrams_on_the_fast_path_and_messages_otherwise() -> None:
    fast, plain = FakeDatagramBus(), PlainBus()
    for bus in (fast, plain):
        assert HarnessWriter(bus, PROTOCOL).command(1234.0, True, NOW_S)
    (msg,) = plain.sent
    assert fast.datagrams_sent == [encode_frame(msg)], "the same frame, byte for byte, on either path"


def test_the_reader_takes_datagrams_on_the_fast_path_and_messages_otherwise() -> None:
    frame = _table_frame(0.0125)
    fast, plain = FakeDatagramBus(), PlainBus()
    fast.datagrams_waiting.append(encode_frame(frame))
    plain.pending.append(frame)
    samples = []
    for bus in (fast, plain):
        reader = HarnessReader(bus, PROTOCOL)
        assert reader.poll(NOW_S) == 1
        samples.append((reader.table.fresh, list(reader.table.values), reader.table.last_status))
    assert samples[0] == samples[1]
    assert samples[0][0] and samples[0][1][0] == pytest.approx(0.0125)
    assert fast.datagram_reads == 2, "the frame, then nothing more waiting"


def test_the_reader_keeps_the_message_path_while_the_bus_says_raw_frames_would_differ() -> None:
    bus = FakeDatagramBus(raw_receive_ok=False)
    bus.pending.append(_table_frame(-0.002))
    reader = HarnessReader(bus, PROTOCOL)
    assert reader.poll(NOW_S) == 1
    assert bus.datagram_reads == 0
    assert reader.table.values[0] == pytest.approx(-0.002)
