"""Who may reach a ``seqpacket`` channel: another user is refused, whether it joins or squats (docs/SAFETY.md, "Threat model").

The intruder is a forked child of this test that gives up root for uid 65534 (``nobody``)
before it touches the channel, as a local user's 30-line script would. It only uses
sockets, so it needs nothing of this checkout. Where this process is not root (it cannot
become another user), those tests skip and say so.
"""

from __future__ import annotations

import errno
import json
import os
import shutil
import socket
import tempfile
import time
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path

import can
import pytest

from drivers.errors import BusError
from drivers.protocol.datagram import encode_frame
from drivers.transports.seqpacket import channel as channel_module
from drivers.transports.seqpacket.bus import SeqPacketBus
from drivers.transports.seqpacket.channel import parse_channel

STRANGER_UID = 65534  # nobody
ESTOP_ID = 0x010
ESTOP = can.Message(arbitration_id=ESTOP_ID, is_extended_id=False, data=bytes([0xFF, 0x00, 0x01]))

needs_root = pytest.mark.skipif(
    os.geteuid() != 0, reason="the intruder must run as another user (uid 65534): only root can switch to it here",
)


class Stranger:
    """A forked child running ``act(report)`` as uid 65534; ``report(dict)`` sends a line to this test."""

    def __init__(self, act: Callable[[Callable[[dict], None], int], None]):
        self._read, write = os.pipe()
        self._go_read, self._go = os.pipe()
        self.pid = os.fork()
        if self.pid == 0:  # the child: never returns into pytest
            status = 0
            try:
                os.close(self._read)
                os.close(self._go)
                os.setgroups([])
                os.setgid(STRANGER_UID)
                os.setuid(STRANGER_UID)
                out = os.fdopen(write, "w", buffering=1)
                act(lambda line: out.write(json.dumps(line) + "\n"), self._go_read)
            except BaseException as err:  # report anything, then leave
                try:
                    os.write(write, (json.dumps({"error": repr(err)}) + "\n").encode())
                except OSError:
                    pass
                status = 1
            finally:
                os._exit(status)
        os.close(write)
        os.close(self._go_read)
        self._lines = os.fdopen(self._read)

    def next(self, timeout_s: float = 10.0) -> dict:
        """The child's next report."""
        import select

        ready, _, _ = select.select([self._lines], [], [], timeout_s)
        assert ready, "the intruder said nothing"
        line = self._lines.readline()
        assert line, "the intruder exited without a word"
        return json.loads(line)

    def go(self) -> None:
        """Tell the child to go on (it waits with :func:`_wait`)."""
        os.write(self._go, b"g")

    def finish(self) -> None:
        try:
            os.write(self._go, b"g")
        except OSError:
            pass
        try:
            os.waitpid(self.pid, 0)
        except ChildProcessError:
            pass
        self._lines.close()
        os.close(self._go)


def _wait(go_fd: int) -> None:
    os.read(go_fd, 1)


@pytest.fixture
def strangers() -> Iterator[list[Stranger]]:
    started: list[Stranger] = []
    yield started
    for child in started:
        child.finish()




@pytest.fixture
def shared_tmp() -> Iterator[Path]:
    """A fresh directory like /tmp (mode 1777) that another user can reach (pytest's own tmp_path is 0700)."""
    path = Path(tempfile.mkdtemp(prefix="seqpacket-shared-"))
    path.chmod(0o1777)
    yield path
    shutil.rmtree(path, ignore_errors=True)


def _name() -> str:
    return f"sec-{uuid.uuid4().hex[:12]}"


def _serve(hub: SeqPacketBus, seconds: float) -> list[can.Message]:
    """Send an E-stop-sized frame and receive, as a hub in a run does, for ``seconds``; the frames received."""
    got = []
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        hub.send(can.Message(arbitration_id=0x020, is_extended_id=False, data=bytes(8)))
        msg = hub.recv(timeout=0.01)
        if msg is not None:
            got.append(msg)
    return got


# --- another user --------------------------------------------------------------------------


@needs_root
def test_another_user_joining_an_abstract_channel_is_closed_before_it_hears_or_injects_anything(
    buses: list[SeqPacketBus], strangers: list[Stranger],
) -> None:
    channel = "@" + _name()
    hub = SeqPacketBus(channel)
    buses.append(hub)
    address = parse_channel(channel).address

    def intrude(report: Callable[[dict], None], go: int) -> None:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        sock.connect(address)  # an abstract name has no permissions: the kernel lets anyone connect
        sent = 0
        try:
            for _ in range(5):
                sock.send(encode_frame(ESTOP))
                sent += 1
        except OSError:
            pass
        sock.settimeout(2.0)
        heard = 0
        try:
            while sock.recv(128):
                heard += 1
        except OSError:
            pass
        report({"sent": sent, "heard": heard})

    strangers.append(intruder := Stranger(intrude))
    got = _serve(hub, 1.0)
    report = intruder.next()
    assert "error" not in report, report
    assert report["heard"] == 0, "the intruder heard the bus's frames"
    assert [m for m in got if m.arbitration_id == ESTOP_ID] == [], "the intruder's E-stop reached the hub"
    assert hub.refused_count >= 1 and "another user" in hub.refused_peers[0]
    assert f"uid {STRANGER_UID}" in hub.refused_peers[0] and hub.peer_count == 0


@needs_root
def test_another_user_cannot_reach_a_plain_channel_at_all(buses: list[SeqPacketBus], strangers: list[Stranger]) -> None:
    channel = _name()
    hub = SeqPacketBus(channel)
    buses.append(hub)
    path = parse_channel(channel).address
    assert oct(os.stat(os.path.dirname(path)).st_mode & 0o777) == oct(0o700)

    def intrude(report: Callable[[dict], None], go: int) -> None:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        try:
            sock.connect(path)
        except OSError as err:
            report({"errno": err.errno})
            return
        report({"errno": 0})

    strangers.append(intruder := Stranger(intrude))
    assert intruder.next()["errno"] == errno.EACCES
    assert _serve(hub, 0.1) == []


@needs_root
def test_another_user_squatting_an_abstract_channel_is_refused_not_joined(
    buses: list[SeqPacketBus], strangers: list[Stranger],
) -> None:
    channel = "@" + _name()
    address = parse_channel(channel).address

    def squat(report: Callable[[dict], None], go: int) -> None:
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        listener.bind(address)
        listener.listen(4)
        report({"bound": True})
        listener.settimeout(5.0)
        heard = 0
        try:
            peer, _ = listener.accept()
            peer.settimeout(1.0)
            while peer.recv(128):
                heard += 1
        except OSError:
            pass
        report({"heard": heard})
        _wait(go)

    strangers.append(squatter := Stranger(squat))
    assert squatter.next() == {"bound": True}
    refused = rf"refused the hub on seqpacket channel .*uid {STRANGER_UID}.*another user.*nothing was sent"
    with pytest.raises(BusError, match=refused):
        SeqPacketBus(channel)
    assert squatter.next()["heard"] == 0


@needs_root
def test_a_private_directory_made_by_another_user_is_refused(
    strangers: list[Stranger], shared_tmp: Path, monkeypatch: pytest.MonkeyPatch,
) -> None:
    shared = shared_tmp
    private = shared / f"shaketable-can-{os.geteuid()}"
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    monkeypatch.setattr(channel_module, "FALLBACK_DIRECTORY", str(shared / "shaketable-can-{uid}"))
    channel = _name()

    def squat(report: Callable[[dict], None], go: int) -> None:
        os.mkdir(private, 0o777)
        os.chmod(private, 0o777)
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        listener.bind(str(private / channel))
        listener.listen(4)
        report({"bound": True})
        _wait(go)

    strangers.append(squatter := Stranger(squat))
    assert squatter.next() == {"bound": True}
    with pytest.raises(BusError, match=rf"refusing the seqpacket directory .*owned by uid {STRANGER_UID}, not by you"):
        SeqPacketBus(channel)


# --- the same user ---------------------------------------------------------------------------


def test_a_directory_others_can_write_is_refused_for_a_socket_path(tmp_path: Path) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    with pytest.raises(BusError, match=r"refusing seqpacket channel directory .*mode is 0777: every user can write it"):
        SeqPacketBus(str(shared / "bus.sock"))


def test_a_private_directory_open_to_others_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("XDG_RUNTIME_DIR", raising=False)
    monkeypatch.setattr(channel_module, "FALLBACK_DIRECTORY", str(tmp_path / "can-{uid}"))
    (tmp_path / f"can-{os.geteuid()}").mkdir(mode=0o755)
    with pytest.raises(BusError, match=r"mode is 0755; expected 0700"):
        SeqPacketBus(_name())


def test_the_private_directory_is_made_0700(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    tmp_path.chmod(0o700)
    bus = SeqPacketBus(_name())
    try:
        directory = tmp_path / "shaketable-can"
        assert directory.is_dir() and directory.stat().st_mode & 0o777 == 0o700
        assert os.path.dirname(parse_channel(bus.channel).address) == str(directory)
    finally:
        bus.shutdown()


def test_a_hub_admits_only_the_expected_process(buses: list[SeqPacketBus]) -> None:
    channel = _name()
    hub = SeqPacketBus(channel, peer_pids=[os.getpid() + 1])  # not this process
    buses.append(hub)
    node = SeqPacketBus(channel)  # this process: a relay or a stranger of the same user
    buses.append(node)
    node.send(ESTOP)
    assert _serve(hub, 0.2) == []
    assert hub.peer_count == 0 and hub.refused_count >= 1
    assert f"process {os.getpid()} " in hub.refused_peers[0] and "not the process this bus expects" in hub.refused_peers[0]


def test_a_hub_refuses_inside_its_receive_path_without_a_name_lookup_or_a_log_line(
    buses: list[SeqPacketBus], monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture,
) -> None:
    """The hub screens a connection in ``send``/``recv`` (a loop tick): no NSS lookup, no log I/O there.

    The refusal is described, with the user's name, and logged when ``refused_peers`` is first read.
    """
    import pwd

    lookups: list[int] = []
    real_getpwuid = pwd.getpwuid
    monkeypatch.setattr(pwd, "getpwuid", lambda uid: lookups.append(uid) or real_getpwuid(uid))
    channel = _name()
    hub = SeqPacketBus(channel, peer_pids=[os.getpid() + 1])  # not this process
    buses.append(hub)
    node = SeqPacketBus(channel)
    buses.append(node)
    caplog.set_level("WARNING", logger="drivers.transports.seqpacket.bus")
    assert _serve(hub, 0.2) == []
    assert hub.refused_count >= 1 and hub.peer_count == 0
    assert lookups == [] and caplog.records == [], "the tick path looked a name up or logged"
    notes = hub.refused_peers
    assert len(notes) == min(hub.refused_count, 16) and "not the process this bus expects" in notes[0]
    assert lookups and [r.getMessage() for r in caplog.records] == [f"seqpacket: {note}" for note in notes]
    assert hub.refused_peers == notes and len(caplog.records) == len(notes), "each refusal is logged once"


def test_a_node_refuses_a_hub_that_is_not_the_expected_process(buses: list[SeqPacketBus]) -> None:
    channel = _name()
    buses.append(SeqPacketBus(channel))  # sits on the channel first
    with pytest.raises(BusError, match=r"refused the hub .*not the process this bus expects .*nothing was sent"):
        SeqPacketBus(channel, peer_pids=[os.getpid() + 1])


def test_policy_admits_the_user_and_the_named_group_only() -> None:
    from drivers.transports.seqpacket.peers import PeerCredentials, PeerPolicy

    policy = PeerPolicy(uid=1000, group_gid=50, member_uids=frozenset({1001}))
    assert policy.refusal(PeerCredentials(10, 1000, 1000)) == ""
    assert policy.refusal(PeerCredentials(10, 1002, 50)) == ""  # primary group
    assert policy.refusal(PeerCredentials(10, 1001, 1001)) == ""  # listed member
    assert "another user" in policy.refusal(PeerCredentials(10, 1003, 1003))
    assert "another user" in PeerPolicy(uid=1000).refusal(PeerCredentials(10, 0, 0))  # root is not this user either


def test_an_unknown_peer_group_is_a_bus_error() -> None:
    with pytest.raises(BusError, match=r"peer group 'no-such-group-here' does not exist"):
        SeqPacketBus(_name(), peer_group="no-such-group-here")
