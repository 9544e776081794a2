"""The ``seqpacket`` interface (drivers/transports/seqpacket/): a CAN bus over Unix SOCK_SEQPACKET sockets.

In-process tests open several buses in one process (they are real sockets, so the
hub, relay and fail-over logic runs as across processes); the cross-process tests
start ``sys.executable`` children that import this module's ``child_*`` functions
and talk over stdin/stdout lines. The contract suite runs in test_bus_contract.py.
"""

from __future__ import annotations

import errno
import json
import os
import queue
import select
import socket
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from importlib.metadata import entry_points
from pathlib import Path

import can
import pytest

from drivers.errors import BusError
from drivers.protocol.datagram import encode_frame
from drivers.transports import seqpacket
from drivers.transports.bus import is_queue_full
from drivers.transports.seqpacket.bus import (
    ACCEPT_CHECK_INTERVAL_S,
    BYTES_PER_QUEUED_FRAME,
    SOCKET_BUFFER_BYTES,
    WANTED_BACKLOG_FRAMES,
    SeqPacketBus,
)
from drivers.transports.seqpacket.channel import ABSTRACT_PREFIX, parse_channel, private_directory

REPO = Path(__file__).resolve().parents[2]
HERE = Path(__file__).resolve().parent
WAIT_S = 5.0  # upper bound of any wait for something that should happen at once
CHILD_TIMEOUT_S = 30.0
STOP_ID = 0x7FF


# --- frames and helpers shared with the child processes --------------------------------------


def make_frames(count: int, seed: int) -> list[can.Message]:
    """``count`` distinct frames cycling through every kind the wire format carries."""
    fd_lengths = (12, 16, 20, 24, 32, 48, 64)
    frames = []
    for k in range(count):
        kind = k % 6
        fill = bytes((seed * 31 + k * 7 + j) & 0xFF for j in range(64))
        if kind == 0:  # classic, standard ID, 0..8 bytes
            msg = can.Message(arbitration_id=(seed * 64 + k) & 0x7FF, is_extended_id=False, data=fill[: k % 9])
        elif kind == 1:  # classic, extended ID, 8 bytes
            msg = can.Message(arbitration_id=((k << 13) ^ seed ^ 0x1ABCDE) & 0x1FFFFFFF, is_extended_id=True, data=fill[:8])
        elif kind == 2:  # remote frame: a DLC, no data
            msg = can.Message(arbitration_id=(k + seed) & 0x7FF, is_extended_id=False, is_remote_frame=True, dlc=k % 9)
        elif kind == 3:  # error frame: bus-off + controller error-passive
            msg = can.Message(
                arbitration_id=0x044, is_extended_id=False, is_error_frame=True, data=bytes([0, 0x10, k & 0xFF, 0, 0, 0, 0, 0])
            )
        elif kind == 4:  # FD, extended, bit-rate switch and ESI
            msg = can.Message(
                arbitration_id=(k * 977 + seed) & 0x1FFFFFFF, is_extended_id=True, is_fd=True,
                bitrate_switch=True, error_state_indicator=True, data=fill[: fd_lengths[k % len(fd_lengths)]],
            )
        else:  # FD, standard, no bit-rate switch
            msg = can.Message(arbitration_id=(k * 3 + seed) & 0x7FF, is_extended_id=False, is_fd=True, data=fill[:5])
        frames.append(msg)
    return frames


def fields(msg: can.Message) -> list:
    """Everything the bus must carry unchanged, JSON-friendly."""
    return [
        msg.arbitration_id, msg.is_extended_id, msg.is_remote_frame, msg.is_error_frame, msg.is_fd,
        msg.bitrate_switch, msg.error_state_indicator, msg.dlc, bytes(msg.data).hex(),
    ]


def say(obj: dict) -> None:
    print(json.dumps(obj), flush=True)


def child_exchange(channel: str, count: str, send_seed: str) -> None:
    """Child: open the bus, send ``count`` frames after "go", report what arrived, shut down on "done"."""
    bus = can.Bus(interface="seqpacket", channel=channel)
    say({"ready": True, "hub": bus.is_hub})
    assert sys.stdin.readline().strip() == "go"
    sent_ok = 0
    for msg in make_frames(int(count), int(send_seed)):
        bus.send(msg)
        sent_ok += 1
    received = []
    deadline = time.monotonic() + WAIT_S
    while len(received) < int(count) and (left := deadline - time.monotonic()) > 0:
        msg = bus.recv(timeout=left)
        if msg is not None:
            received.append(fields(msg) + [msg.is_rx, msg.channel, abs(time.time() - msg.timestamp) < 60])
    say({"sent": sent_ok, "received": received, "hub": bus.is_hub})
    sys.stdin.readline()  # "done": stay on the bus until the parent is finished
    bus.shutdown()


def child_relay(channel: str) -> None:
    """Child: be on the bus (the hub when first) and keep receiving, so the hub relays, until STOP_ID."""
    bus = can.Bus(interface="seqpacket", channel=channel)
    say({"ready": True, "hub": bus.is_hub})
    seen = 0
    deadline = time.monotonic() + CHILD_TIMEOUT_S
    while time.monotonic() < deadline:
        msg = bus.recv(timeout=0.5)
        if msg is None:
            continue
        if msg.arbitration_id == STOP_ID:
            break
        seen += 1
    say({"seen": seen, "hub": bus.is_hub, "relay_drops": bus.relay_drops})
    bus.shutdown()


class Child:
    """A child Python process running one of the ``child_*`` functions; JSON lines on stdout."""

    def __init__(self, function: str, *args: object):
        code = (
            f"import sys; sys.path[:0] = [{str(REPO)!r}, {str(HERE)!r}]; "
            f"import test_seqpacket as t; t.{function}(*sys.argv[1:])"
        )
        self.proc = subprocess.Popen(
            [sys.executable, "-c", code, *map(str, args)],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
        )
        self._lines: queue.Queue[str] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self._lines.put(line)

    def expect(self, timeout: float = CHILD_TIMEOUT_S) -> dict:
        try:
            return json.loads(self._lines.get(timeout=timeout))
        except queue.Empty:
            self.proc.kill()
            _, err = self.proc.communicate()
            raise AssertionError(f"child said nothing within {timeout} s; stderr:\n{err}") from None

    def tell(self, line: str) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()

    def finish(self) -> None:
        """Wait for a clean exit (code 0)."""
        try:
            _, err = self.proc.communicate(timeout=CHILD_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            _, err = self.proc.communicate()
        assert self.proc.returncode == 0, f"child exited with {self.proc.returncode}; stderr:\n{err}"

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.communicate()


def receive(bus: can.BusABC, count: int, timeout_s: float = WAIT_S) -> list[can.Message]:
    """Up to ``count`` frames, waiting at most ``timeout_s`` in all (a genuine bus wait)."""
    got: list[can.Message] = []
    deadline = time.monotonic() + timeout_s
    while len(got) < count and (left := deadline - time.monotonic()) > 0:
        msg = bus.recv(timeout=left)
        if msg is not None:
            got.append(msg)
    return got


@pytest.fixture
def channel() -> str:
    return f"test-{uuid.uuid4().hex}"


@pytest.fixture
def children() -> Iterator[list[Child]]:
    started: list[Child] = []
    yield started
    for child in started:
        child.kill()


def open_(buses: list[SeqPacketBus], channel: str, **kwargs: object) -> SeqPacketBus:
    bus = can.Bus(interface="seqpacket", channel=channel, **kwargs)
    assert isinstance(bus, SeqPacketBus)
    buses.append(bus)
    return bus


# --- channel names ------------------------------------------------------------------------


def test_at_names_are_abstract_addresses() -> None:
    addr = parse_channel("@harness")
    assert addr.address == "\0shaketable-can/harness" and addr.path is None and addr.name == "@harness"


def test_plain_names_are_sockets_in_the_private_directory() -> None:
    addr = parse_channel("harness")
    assert addr.private and addr.path == addr.address == os.path.join(private_directory(), "harness")


def test_abstract_channel_leaves_no_file(
    buses: list[SeqPacketBus], channel: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    channel = "@" + channel
    hub = open_(buses, channel)
    assert hub.is_hub and list(tmp_path.iterdir()) == []
    with open("/proc/net/unix") as table:
        assert f"@{ABSTRACT_PREFIX[1:]}{channel[1:]}" in table.read()


@pytest.mark.parametrize(
    ("channel", "pattern"),
    [
        ("", r"'' is not a usable name; expected a name of letters"),
        ("@", r"'@' is not a usable name"),
        ("two words", r"'two words' is not a usable name"),
        ("@" + "x" * 93, r"93 characters; at most 92"),
        ("x" * 93, r"over the 107 bytes a Unix socket path holds"),
        ("/no/such/directory/bus.sock", r"directory '/no/such/directory' does not exist"),
        ("/tmp/", r"names a directory"),
        ("/tmp/" + "x" * 110, r"at most 107"),
        (7, r"7 is a int; expected a name"),
    ],
)
def test_unusable_channels_are_bus_errors(channel: object, pattern: str) -> None:
    with pytest.raises(BusError, match=pattern):
        SeqPacketBus(channel)  # type: ignore[arg-type]


# --- one process, several nodes -------------------------------------------------------------


def test_first_node_is_hub_others_connect(buses: list[SeqPacketBus], channel: str) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    assert hub.is_hub and not node.is_hub
    assert node.peer_count == 1
    assert hub.protocol == can.CanProtocol.CAN_20 and hub.state == can.BusState.ACTIVE
    assert SeqPacketBus._detect_available_configs() == []


@pytest.mark.parametrize("direction", ["hub to node", "node to hub"])
def test_every_field_round_trips(buses: list[SeqPacketBus], channel: str, direction: str) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    sender, receiver = (hub, node) if direction == "hub to node" else (node, hub)
    frames = make_frames(60, seed=3)
    before = time.time()
    for msg in frames:
        sender.send(msg)
    got = receive(receiver, len(frames))
    after = time.time()
    assert [fields(m) for m in got] == [fields(m) for m in frames]
    assert all(m.is_rx and m.channel == channel and before <= m.timestamp <= after for m in got)
    assert receiver.recv(timeout=0) is None and sender.recv(timeout=0) is None


def test_oversize_frame_is_a_value_error(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel)
    with pytest.raises(ValueError, match="65 data bytes; at most 64"):
        hub.send(can.Message(arbitration_id=1, is_fd=True, data=bytes(65)))
    with pytest.raises(ValueError, match="does not fit"):
        hub.send(can.Message(arbitration_id=1 << 32, data=b"\x01"))


def test_three_nodes_through_the_hub_relay(buses: list[SeqPacketBus], channel: str) -> None:
    hub, b, c = open_(buses, channel), open_(buses, channel), open_(buses, channel)
    frame = {name: can.Message(arbitration_id=k, is_extended_id=False, data=[k]) for k, name in enumerate("abc", start=1)}
    b.send(frame["b"])
    assert fields(receive(hub, 1)[0]) == fields(frame["b"])  # the hub's recv relays it ...
    assert fields(receive(c, 1)[0]) == fields(frame["b"])  # ... to the other peer
    c.send(frame["c"])
    assert fields(receive(hub, 1)[0]) == fields(frame["c"])
    assert fields(receive(b, 1)[0]) == fields(frame["c"])
    hub.send(frame["a"])
    assert fields(receive(b, 1)[0]) == fields(frame["a"]) and fields(receive(c, 1)[0]) == fields(frame["a"])
    for bus in (hub, b, c):  # nobody heard its own frame, nothing is left over
        assert bus.recv(timeout=0) is None
    assert hub.peer_count == 2 and hub.relay_drops == 0


def test_receive_own_messages_echoes_locally(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel, receive_own_messages=True)
    node = open_(buses, channel)
    msg = can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\x01\x02")
    hub.send(msg)
    own = hub.recv(timeout=0)
    assert own is not None and fields(own) == fields(msg) and not own.is_rx
    other = receive(node, 1)
    assert len(other) == 1 and other[0].is_rx
    assert hub.recv(timeout=0) is None and node.recv(timeout=0) is None


def test_filters_apply_and_timeout_zero_drains_past_rejected_frames(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel, can_filters=[{"can_id": 0x50, "can_mask": 0x7FF, "extended": False}])
    node = open_(buses, channel)
    for frame_id in (0x10, 0x20, 0x50, 0x30):
        node.send(can.Message(arbitration_id=frame_id, is_extended_id=False, data=b"\x00"))
    # the four frames wait in the node's connection; the hub's first recv accepts it and reads them.
    # python-can's BusABC.recv gives up after one rejected frame when timeout=0; this bus skips them
    msg = hub.recv(timeout=0)
    assert msg is not None and msg.arbitration_id == 0x50
    assert hub.recv(timeout=0) is None  # 0x30 rejected, queue empty


def test_malformed_datagram_is_counted_and_dropped(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel)
    raw = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    try:
        raw.connect(parse_channel(channel).address)
        raw.send(b"\x01\x02")  # shorter than the header
        raw.send(encode_frame(can.Message(arbitration_id=0x42, is_extended_id=False, data=b"\x07")))
        got = receive(hub, 1)
        assert [fields(m) for m in got] == [[0x42, False, False, False, False, False, False, 1, "07"]]
        assert hub.malformed_frames == 1
    finally:
        raw.close()


# --- receive timing --------------------------------------------------------------------------


class _NoPoll:
    """Stands in for an epoll object: fails the test if polled."""

    def poll(self, *args: object) -> list:
        raise AssertionError("recv(timeout=0) polled")

    def fileno(self) -> int:
        return -1

    def close(self) -> None:
        pass


@pytest.mark.parametrize("role", ["node", "hub"])
def test_recv_timeout_zero_is_a_plain_nonblocking_recv(
    buses: list[SeqPacketBus], channel: str, role: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    hub.send(can.Message(arbitration_id=1, data=b""))  # the hub accepts the node here
    bus = node if role == "node" else hub
    real_ep, real_listen_ep = bus._ep, bus._listen_ep
    monkeypatch.setattr(bus, "_ep", _NoPoll())
    monkeypatch.setattr(bus, "_listen_ep", _NoPoll())
    bus._next_accept_check = float("inf")  # the hub's periodic accept check is not due
    if role == "node":
        assert select.select([real_ep], [], [], WAIT_S)[0]  # the frame has arrived
        assert bus.recv(timeout=0) is not None
    t0 = time.perf_counter()
    assert bus.recv(timeout=0) is None
    elapsed = time.perf_counter() - t0
    monkeypatch.setattr(bus, "_ep", real_ep)
    monkeypatch.setattr(bus, "_listen_ep", real_listen_ep)
    assert elapsed < 0.1  # generous: only catches an accidental wait


def test_hub_checks_for_new_peers_in_recv_at_most_every_interval(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel)
    node = open_(buses, channel)
    node.send(can.Message(arbitration_id=0x11, data=b"\x01"))
    hub._next_accept_check = time.monotonic() + 3600.0
    assert hub.recv(timeout=0) is None and hub.peer_count == 0  # not accepted yet: check not due
    hub._next_accept_check = 0.0
    msg = hub.recv(timeout=0)  # due: accepts the node and reads its waiting frame
    assert msg is not None and msg.arbitration_id == 0x11 and hub.peer_count == 1
    assert hub._next_accept_check - time.monotonic() <= ACCEPT_CHECK_INTERVAL_S


@pytest.mark.parametrize("role", ["node", "hub"])
def test_recv_with_timeout_waits_that_long_when_nothing_arrives(buses: list[SeqPacketBus], channel: str, role: str) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    bus = node if role == "node" else hub
    t0 = time.monotonic()
    assert bus.recv(timeout=0.05) is None
    elapsed = time.monotonic() - t0
    assert 0.05 <= elapsed < 1.0  # the lower bound is exact (epoll rounds up); the upper one is loose


def test_blocking_recv_wakes_for_a_frame(buses: list[SeqPacketBus], channel: str) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    timer = threading.Timer(0.02, lambda: node.send(can.Message(arbitration_id=0x77, data=b"\x05")))
    timer.start()
    try:
        msg = hub.recv(timeout=WAIT_S)
    finally:
        timer.join()
    assert msg is not None and msg.arbitration_id == 0x77


def test_fileno_is_one_descriptor_readable_when_a_frame_waits(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel)
    fd = hub.fileno()
    node = open_(buses, channel)
    assert select.select([fd], [], [], WAIT_S)[0] == [fd]  # a connection waits to be accepted
    assert hub.recv(timeout=0) is None and hub.peer_count == 1  # accepted; the descriptor stays the same
    node.send(can.Message(arbitration_id=0x33, data=b""))
    assert select.select([fd], [], [], WAIT_S)[0] == [fd]
    assert receive(hub, 1)[0].arbitration_id == 0x33
    assert hub.fileno() == fd
    assert select.select([fd], [], [], 0)[0] == []
    hub.shutdown()
    assert hub.fileno() == -1


# --- full buffers ------------------------------------------------------------------------------


@pytest.mark.parametrize("direction", ["hub to node", "node to hub"])
def test_full_peer_buffer_is_enobufs(buses: list[SeqPacketBus], channel: str, direction: str) -> None:
    hub, node = open_(buses, channel), open_(buses, channel)
    hub.send(can.Message(arbitration_id=0, data=b""))  # accept the node
    assert receive(node, 1)
    sender, stalled = (hub, node) if direction == "hub to node" else (node, hub)
    msg = can.Message(arbitration_id=0x30, is_extended_id=False, data=bytes(8))
    sent = 0
    with pytest.raises(can.CanOperationError) as excinfo:
        while sent < 100_000:
            sender.send(msg)
            sent += 1
    err = excinfo.value
    assert "Transmit buffer full" in str(err) and err.error_code == errno.ENOBUFS and is_queue_full(err)
    granted = sender.socket_buffer_bytes
    assert sent >= granted // (2 * BYTES_PER_QUEUED_FRAME)  # the buffer holds what the kernel granted
    if granted >= 2 * SOCKET_BUFFER_BYTES:  # where net.core.wmem_max allows the buffer asked for
        assert sent >= WANTED_BACKLOG_FRAMES, f"only {sent} frames fit; a stalled reader should fall 0.5 s behind"
    assert len(receive(stalled, sent, timeout_s=WAIT_S)) == sent  # nothing lost before the error
    sender.send(msg)  # room again once the reader caught up
    assert len(receive(stalled, 1)) == 1


def test_hub_counts_relay_drops_for_a_stalled_peer_and_still_serves_the_others(buses: list[SeqPacketBus], channel: str) -> None:
    hub, b, c = open_(buses, channel), open_(buses, channel), open_(buses, channel)
    hub.send(can.Message(arbitration_id=0, data=b""))  # accept both
    assert receive(b, 1) and receive(c, 1)
    msg = can.Message(arbitration_id=0x30, is_extended_id=False, data=bytes(8))
    sent = 0
    while hub.relay_drops == 0 and sent < 100_000:  # c never reads; the hub keeps up with b
        b.send(msg)
        sent += 1
        assert hub.recv(timeout=WAIT_S) is not None
    assert hub.relay_drops == 1 and sent > 1
    with pytest.raises(can.CanOperationError, match=r"Transmit buffer full: 1 of 2 peers"):
        hub.send(can.Message(arbitration_id=0x31, is_extended_id=False, data=b""))
    assert [m.arbitration_id for m in receive(b, 1)] == [0x31]  # b got the hub's frame regardless
    assert len(receive(c, sent)) == sent - 1  # everything relayed before c's buffer filled
    assert c.recv(timeout=0) is None


# --- hub goes away ---------------------------------------------------------------------------


def test_hub_shutdown_in_process_a_peer_takes_over(buses: list[SeqPacketBus], channel: str) -> None:
    hub, b, c = open_(buses, channel), open_(buses, channel), open_(buses, channel)
    hub.send(can.Message(arbitration_id=1, data=b""))
    assert receive(b, 1) and receive(c, 1)
    hub.shutdown()
    b.send(can.Message(arbitration_id=2, data=b""))  # b sees the hub gone, rejoins: nobody listens, b becomes hub
    assert b.is_hub
    assert c.recv(timeout=0.2) is None  # c sees end-of-file, then connects to b (frame 2 predates it)
    assert not c.is_hub and c.peer_count == 1
    b.send(can.Message(arbitration_id=3, data=b""))
    assert [m.arbitration_id for m in receive(c, 1)] == [3]
    c.send(can.Message(arbitration_id=4, data=b""))
    assert [m.arbitration_id for m in receive(b, 1)] == [4]


def test_path_channel_replaces_stale_socket_and_unlinks_on_shutdown(buses: list[SeqPacketBus], tmp_path: Path) -> None:
    path = tmp_path / "bus.sock"
    stale = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    stale.bind(str(path))  # a socket file nobody listens on, as a crashed hub leaves it
    stale.close()
    assert path.is_socket()
    hub = open_(buses, str(path))
    node = open_(buses, str(path))
    assert hub.is_hub and not node.is_hub and path.is_socket()
    node.send(can.Message(arbitration_id=0x21, data=b"\x09"))
    assert [m.arbitration_id for m in receive(hub, 1)] == [0x21]
    hub.shutdown()
    assert not path.exists()
    node.shutdown()
    assert not path.exists()


def test_path_channel_refuses_to_replace_a_regular_file(tmp_path: Path) -> None:
    path = tmp_path / "notes.txt"
    path.write_text("keep me")
    with pytest.raises(BusError, match="exists and is not a socket"):
        SeqPacketBus(str(path))
    assert path.read_text() == "keep me"


def test_shutdown_is_idempotent_and_later_calls_raise(buses: list[SeqPacketBus], channel: str) -> None:
    hub = open_(buses, channel)
    hub.shutdown()
    hub.shutdown()
    with pytest.raises(can.CanOperationError, match="shut down"):
        hub.send(can.Message(arbitration_id=1, data=b""))
    with pytest.raises(can.CanOperationError, match="shut down"):
        hub.recv(timeout=0)


# --- across processes ------------------------------------------------------------------------


@pytest.mark.parametrize("child_is_hub", [True, False], ids=["child-hub", "parent-hub"])
def test_two_processes_exchange_frames_both_ways(
    buses: list[SeqPacketBus], children: list[Child], channel: str, child_is_hub: bool
) -> None:
    count = 300
    if not child_is_hub:
        bus = open_(buses, channel)
    child = Child("child_exchange", channel, count, 7)
    children.append(child)
    assert child.expect() == {"ready": True, "hub": child_is_hub}
    if child_is_hub:
        bus = open_(buses, channel)
    assert bus.is_hub is not child_is_hub
    child.tell("go")
    mine = make_frames(count, seed=8)
    for msg in mine:
        bus.send(msg)
    got = receive(bus, count)
    report = child.expect()
    child.tell("done")
    child.finish()
    assert [fields(m) for m in got] == [fields(m) for m in make_frames(count, seed=7)]  # none lost, in order
    assert all(m.is_rx and m.channel == channel for m in got)
    assert report["sent"] == count
    assert [r[:9] for r in report["received"]] == [fields(m) for m in mine]
    assert all(r[9:] == [True, channel, True] for r in report["received"])
    assert bus.recv(timeout=0) is None


def test_three_processes_through_a_hub_process(buses: list[SeqPacketBus], children: list[Child], channel: str) -> None:
    child = Child("child_relay", channel)
    children.append(child)
    assert child.expect() == {"ready": True, "hub": True}
    b, c = open_(buses, channel), open_(buses, channel)
    assert not b.is_hub and not c.is_hub
    frames_b, frames_c = make_frames(100, seed=1), make_frames(100, seed=2)
    for msg in frames_b:
        b.send(msg)
    got_c = receive(c, len(frames_b))
    for msg in frames_c:
        c.send(msg)
    got_b = receive(b, len(frames_c))
    assert [fields(m) for m in got_c] == [fields(m) for m in frames_b]
    assert [fields(m) for m in got_b] == [fields(m) for m in frames_c]
    b.send(can.Message(arbitration_id=STOP_ID, is_extended_id=False, data=b""))
    assert child.expect() == {"seen": 200, "hub": True, "relay_drops": 0}
    child.finish()
    assert [m.arbitration_id for m in receive(c, 1)] == [STOP_ID]


def test_hub_process_goes_away_and_comes_back(buses: list[SeqPacketBus], children: list[Child], channel: str) -> None:
    first = Child("child_exchange", channel, 3, 11)
    children.append(first)
    assert first.expect()["hub"] is True
    bus = open_(buses, channel)
    first.tell("go")
    assert [fields(m) for m in receive(bus, 3)] == [fields(m) for m in make_frames(3, 11)]
    for msg in make_frames(3, 12):
        bus.send(msg)
    assert len(first.expect()["received"]) == 3
    first.tell("done")
    first.finish()  # the hub process has exited

    for msg in make_frames(20, 13):  # nobody else on the bus: dropped silently
        bus.send(msg)
    assert bus.recv(timeout=0) is None
    assert bus.is_hub  # it found the hub gone, and nobody listening, so it took over

    second = Child("child_exchange", channel, 50, 14)
    children.append(second)
    assert second.expect() == {"ready": True, "hub": False}  # the returning process joins as a peer
    second.tell("go")
    got = receive(bus, 50)
    mine = make_frames(50, 15)
    for msg in mine:
        bus.send(msg)
    report = second.expect()
    second.tell("done")
    second.finish()
    assert [fields(m) for m in got] == [fields(m) for m in make_frames(50, 14)]
    assert [r[:9] for r in report["received"]] == [fields(m) for m in mine]  # the dropped 20 never arrive


def test_idle_peer_rejoins_a_restarted_hub_without_losing_the_next_frame(
    buses: list[SeqPacketBus], children: list[Child], channel: str
) -> None:
    first = Child("child_relay", channel)
    children.append(first)
    assert first.expect()["hub"] is True
    bus = open_(buses, channel)
    bus.send(can.Message(arbitration_id=STOP_ID, is_extended_id=False, data=b""))
    assert first.expect()["seen"] == 0
    first.finish()  # hub gone while this node made no call
    second = Child("child_relay", channel)
    children.append(second)
    assert second.expect()["hub"] is True  # the old address was free: the new process is the hub
    bus.send(can.Message(arbitration_id=0x123, is_extended_id=False, data=b"\x01"))  # finds its socket dead, rejoins, sends
    assert not bus.is_hub and bus.peer_count == 1
    bus.send(can.Message(arbitration_id=STOP_ID, is_extended_id=False, data=b""))
    assert second.expect()["seen"] == 1
    second.finish()


# --- registration ------------------------------------------------------------------------------


@pytest.fixture
def without_the_entry_point(monkeypatch: pytest.MonkeyPatch) -> None:
    """python-can's interface tables as an import without the installed entry point leaves them."""
    import can.interfaces
    import can.util

    backends = dict(can.interfaces.BACKENDS)
    backends.pop("seqpacket", None)
    valid = frozenset(backends)
    monkeypatch.setattr(can.interfaces, "BACKENDS", backends)
    monkeypatch.setattr("can.interface.BACKENDS", backends)
    for module in (can.interfaces, can.util, can):
        monkeypatch.setattr(module, "VALID_INTERFACES", valid)


@pytest.mark.usefixtures("without_the_entry_point")
def test_register_makes_the_interface_known_without_the_entry_point(channel: str) -> None:
    with pytest.raises(can.CanInterfaceNotImplementedError):
        can.Bus(interface="seqpacket", channel=channel)
    seqpacket.register()
    assert "seqpacket" in can.util.VALID_INTERFACES and "seqpacket" in can.VALID_INTERFACES
    bus = can.Bus(interface="seqpacket", channel=channel)
    assert isinstance(bus, SeqPacketBus)
    bus.shutdown()


@pytest.mark.usefixtures("without_the_entry_point")
def test_importing_the_drivers_registers_nothing(channel: str) -> None:
    import importlib

    import drivers

    importlib.reload(drivers)
    importlib.reload(seqpacket)
    assert "seqpacket" not in can.interfaces.BACKENDS and "seqpacket" not in can.VALID_INTERFACES
    with pytest.raises(can.CanInterfaceNotImplementedError):
        can.Bus(interface="seqpacket", channel=channel)


@pytest.mark.usefixtures("without_the_entry_point")
def test_open_bus_registers_the_interface_where_the_entry_point_is_missing(channel: str) -> None:
    from drivers.transports.bus import open_bus

    bus = open_bus("seqpacket", channel)
    try:
        assert isinstance(bus, SeqPacketBus) and bus.channel == channel
    finally:
        bus.shutdown()


def test_entry_point_is_installed_and_names_the_bus() -> None:
    found = {ep.name: ep for ep in entry_points(group="can.interface")}
    assert "seqpacket" in found and found["seqpacket"].value == "drivers.transports.seqpacket:SeqPacketBus", (
        "reinstall the package (pip install -e .) so python-can finds the seqpacket entry point"
    )
    assert found["seqpacket"].load() is SeqPacketBus
    assert can.interfaces.BACKENDS["seqpacket"] == ("drivers.transports.seqpacket", "SeqPacketBus")


def test_open_bus_opens_seqpacket(channel: str) -> None:
    from drivers.transports.bus import open_bus

    bus = open_bus("seqpacket", channel)
    try:
        assert isinstance(bus, SeqPacketBus) and bus.channel == channel
    finally:
        bus.shutdown()
