"""The driver contract: one set of tests every python-can backend must pass.

:class:`BusContract` holds the test bodies; a backend subclasses it and provides
two fixtures, ``config`` (a :class:`Channel` that can be opened) and ``nonexistent``
(a Channel that cannot be opened, and a regex the BusError must match).
:class:`TestVirtualContract` runs it on python-can's ``virtual`` interface here;
tests/vcan/test_socketcan_contract.py runs the same bodies on SocketCAN ``vcan0``.

Also here: the error messages of :func:`drivers.transports.bus.open_bus` for a missing
channel or a kernel without CAN, checked against a fake ``/sys/class/net``.
"""

from __future__ import annotations

import time
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import can
import pytest

from drivers.errors import BusError
from drivers.protocol.codec import MessageCodec, load_protocol
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.reader import FrameReader, HarnessReader
from drivers.transports.bus import kernel_has_socketcan, open_bus, socketcan_preflight
from drivers.writer import FrameWriter, HarnessWriter

PROTOCOL = load_protocol()
NAMES = sorted(PROTOCOL.messages)
RECV_TIMEOUT_S = 2.0


class Channel(NamedTuple):
    """What :func:`drivers.transports.bus.open_bus` takes: ``open_bus(*channel)``."""

    interface: str
    channel: str
    bitrate_bps: int = 1_000_000


def midrange_values(codec: MessageCodec) -> list[float]:
    """A distinct, in-range value for every signal (on the DBC grid)."""
    values = []
    for k, sig in enumerate(codec.signals, start=1):
        if sig.is_float:
            values.append(0.25 * k)
        else:
            raw = sig.raw_min + (sig.raw_max - sig.raw_min) * k // (len(codec.signals) + 1)
            values.append(raw * sig.scale + sig.offset)
    return values


def recv_id(bus: can.BusABC, frame_id: int, timeout_s: float = RECV_TIMEOUT_S) -> can.Message | None:
    """Receive until a data frame with ``frame_id`` arrives or the timeout passes (a genuine bus wait)."""
    deadline = time.monotonic() + timeout_s
    while (left := deadline - time.monotonic()) > 0:
        msg = bus.recv(timeout=left)
        if msg is not None and not msg.is_error_frame and msg.arbitration_id == frame_id:
            return msg
    return None


class BusContract:
    """Contract test bodies; subclasses provide the ``config`` and ``nonexistent`` fixtures."""

    @pytest.fixture
    def pair(self, config: Channel) -> Iterator[tuple[can.BusABC, can.BusABC]]:
        sender, receiver = open_bus(*config), open_bus(*config)
        yield sender, receiver
        sender.shutdown()
        receiver.shutdown()

    def test_open_gives_a_python_can_bus(self, config: Channel) -> None:
        bus = open_bus(*config)
        try:
            assert isinstance(bus, can.BusABC)
            assert bus.protocol == can.CanProtocol.CAN_20  # classic CAN, as the DBC assumes
        finally:
            bus.shutdown()

    @pytest.mark.parametrize("name", NAMES)
    def test_every_message_round_trips(self, pair: tuple[can.BusABC, can.BusABC], name: str) -> None:
        sender, receiver = pair
        codec = PROTOCOL[name]
        values = midrange_values(codec)
        assert FrameWriter(sender, PROTOCOL, [name]).send(name, values, now=0.0)
        msg = recv_id(receiver, codec.frame_id)
        assert msg is not None, f"{name} did not arrive within {RECV_TIMEOUT_S} s"
        # (no is_rx check: socketcan reports frames from any local process as is_rx=False)
        assert msg.dlc == codec.length and not msg.is_extended_id and not msg.is_remote_frame
        decoder = Decoder(PROTOCOL)
        assert decoder.decode(msg.arbitration_id, msg.data) == RxStatus.OK
        assert decoder.values(name) == pytest.approx(values, rel=1e-6, abs=1e-9)

    def test_order_is_kept_and_no_counter_is_lost(self, pair: tuple[can.BusABC, can.BusABC]) -> None:
        sender, receiver = pair
        writer = FrameWriter(sender, PROTOCOL, ["TABLE_SENSORS", "HEARTBEAT"])
        count = 40
        for k in range(count):
            assert writer.send("TABLE_SENSORS", [k * 1e-3, 0.0, 0.0], now=0.0)
            assert writer.send("HEARTBEAT", [k % 16], now=0.0)
        decoder = Decoder(PROTOCOL)
        order: list[tuple[int, float]] = []
        deadline = time.monotonic() + RECV_TIMEOUT_S
        while len(order) < 2 * count and (left := deadline - time.monotonic()) > 0:
            msg = receiver.recv(timeout=left)
            if msg is None or msg.is_error_frame:
                continue
            assert decoder.decode(msg.arbitration_id, msg.data) == RxStatus.OK
            order.append((msg.arbitration_id, decoder.values(decoder.last.name)[0]))
        expected = []
        for k in range(count):
            expected += [(0x30, pytest.approx(k * 1e-3)), (0x50, float(k % 16))]
        assert order == expected

    def test_sender_does_not_hear_itself(self, pair: tuple[can.BusABC, can.BusABC]) -> None:
        sender, receiver = pair
        assert FrameWriter(sender, PROTOCOL, ["HEARTBEAT"]).send("HEARTBEAT", [1.0], now=0.0)
        assert recv_id(receiver, PROTOCOL["HEARTBEAT"].frame_id) is not None
        assert sender.recv(timeout=0.05) is None

    def test_command_from_another_node_is_foreign_own_is_not(self, pair: tuple[can.BusABC, can.BusABC], config: Channel) -> None:
        other, harness_bus = pair
        reader = HarnessReader(harness_bus, PROTOCOL)
        assert HarnessWriter(harness_bus, PROTOCOL).command(10.0, True, now=0.0)
        assert recv_id(other, PROTOCOL["ACTUATOR_CMD"].frame_id) is not None  # it did go out
        time.sleep(0.05)  # a genuine bus wait: an echo, if any, would have arrived by now
        reader.poll(now=0.0)
        assert not reader.foreign_command_seen
        assert HarnessWriter(other, PROTOCOL).command(10.0, True, now=0.0)
        deadline = time.monotonic() + RECV_TIMEOUT_S
        while not reader.foreign_command_seen and time.monotonic() < deadline:
            reader.poll(now=0.0)
            time.sleep(0.001)
        assert reader.counters.foreign_commands == 1

    def test_shutdown_is_clean_and_idempotent(self, config: Channel) -> None:
        bus = open_bus(*config)
        writer = FrameWriter(bus, PROTOCOL, ["HEARTBEAT"])
        reader = FrameReader(bus, PROTOCOL, ["HEARTBEAT"])
        bus.shutdown()
        bus.shutdown()
        with bus:  # leaving the context after shutdown is fine too
            pass
        assert writer.send("HEARTBEAT", [1.0], now=0.0) is False
        assert writer.health.send_failures == 1
        with pytest.raises(BusError):
            reader.poll(now=0.0)

    def test_unopenable_channel_is_a_clear_bus_error(self, nonexistent: tuple[Channel, str]) -> None:
        config, pattern = nonexistent
        with pytest.raises(BusError, match=pattern):
            open_bus(*config)


class TestVirtualContract(BusContract):
    """The contract on python-can's in-process ``virtual`` interface (always available)."""

    @pytest.fixture
    def config(self) -> Channel:
        return Channel("virtual", f"contract-{uuid.uuid4().hex}")

    @pytest.fixture
    def nonexistent(self) -> tuple[Channel, str]:
        # virtual channels are created on demand; the unopenable case is an unknown interface
        return Channel("no_such_interface", "x"), r"'no_such_interface' is not available.*virtual"


class TestSeqPacketContract(BusContract):
    """The contract on this project's ``seqpacket`` interface (Unix SOCK_SEQPACKET; the first bus opened is the hub)."""

    @pytest.fixture
    def config(self) -> Channel:
        return Channel("seqpacket", f"contract-{uuid.uuid4().hex}")

    @pytest.fixture
    def nonexistent(self, tmp_path: Path) -> tuple[Channel, str]:
        # names are created on demand; the unopenable case is a socket path in a missing directory
        missing = tmp_path / "no_such_dir" / "bus.sock"
        return Channel("seqpacket", str(missing)), r"seqpacket.*directory .*no_such_dir.* does not exist"


# --- open_bus error messages (no bus needed) -----------------------------------------------


def test_kernel_without_can_says_modprobe_and_with_vcan(tmp_path: Path) -> None:
    with pytest.raises(BusError, match=r"modprobe vcan.*scripts/with-vcan.*User-Mode Linux"):
        socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=False)


def test_missing_vcan_says_how_to_create_it(tmp_path: Path) -> None:
    with pytest.raises(BusError, match=r"'vcan7' does not exist.*ip link add dev vcan7 type vcan && ip link set up vcan7"):
        socketcan_preflight("vcan7", sys_net=tmp_path, kernel_ok=True)


def test_missing_hardware_channel_says_how_to_bring_it_up(tmp_path: Path) -> None:
    with pytest.raises(BusError, match=r"'can0' does not exist.*ip link set can0 up type can bitrate"):
        socketcan_preflight("can0", sys_net=tmp_path, kernel_ok=True)


def test_down_channel_says_set_up(tmp_path: Path) -> None:
    (tmp_path / "vcan0").mkdir()
    (tmp_path / "vcan0" / "flags").write_text("0x80\n")
    (tmp_path / "vcan0" / "operstate").write_text("down\n")
    with pytest.raises(BusError, match=r"'vcan0' is down \(operstate down\); `ip link set up vcan0`"):
        socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=True)
    (tmp_path / "vcan0" / "flags").write_text("0xc1\n")
    socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=True)  # up: no error


def test_socketcan_on_this_machine_fails_with_a_fix_when_unavailable() -> None:
    if Path("/sys/class/net/vcan_missing9").exists():
        pytest.skip("an interface named vcan_missing9 exists here")
    expected = "ip link add dev vcan_missing9" if kernel_has_socketcan() else "modprobe vcan"
    with pytest.raises(BusError, match=expected):
        open_bus(*Channel("socketcan", "vcan_missing9"))


def test_missing_driver_library_is_a_bus_error() -> None:
    # pcan needs the vendor's PCANBasic library, absent on CI machines
    try:
        bus = open_bus(*Channel("pcan", "PCAN_USBBUS1"))
    except BusError as err:
        assert "pcan" in str(err) and "PCAN_USBBUS1" in str(err)
    else:
        bus.shutdown()
        pytest.skip("a PCAN adapter and driver are present on this machine")
