"""The ``seqpacket`` bus: a CAN bus between the processes of one host over Unix ``SOCK_SEQPACKET`` sockets.

Interface name ``seqpacket`` (:mod:`drivers.transports.seqpacket`). Two or more processes that
open the same channel share a broadcast "CAN bus" with no set-up: no root, no kernel
module, no daemon. The default dry run uses it to run the virtual rig in its own process
while the harness loop (500 Hz, soft real time) and the rig both talk python-can's Bus API.

Topology
--------
Symmetric, like a bus: every node runs the same code. On opening, a node tries to
connect to the channel's address; when nobody listens there it binds and listens,
and becomes the *hub*. Later nodes connect to the hub. The hub accepts them lazily
inside ``send``/``recv`` (never blocking) and relays: a frame it receives from one
peer is forwarded to every other peer, and its own frames go to all peers, so N
processes form one broadcast bus. No node hears its own frames (python-can's
``receive_own_messages=False``; ``True`` is supported and echoes locally).

The relay runs inside the hub's ``recv``: frames between two non-hub nodes wait
until the hub process next calls ``recv``. With two processes (harness and rig) one
of them is the hub and nothing is relayed.

When the hub goes away, its peers see end-of-file or a reset, drop the connection,
and on later calls retry (at most every :data:`RETRY_INTERVAL_S`) to connect or to
become the hub themselves. Frames sent while no other node is connected are dropped
silently, as on a bus with no other node.

Why SEQPACKET, and the cost of each call
----------------------------------------
One datagram per frame (message boundaries kept, reliable, ordered, connection
oriented, so a peer that exits is noticed at once). Measured on the 2-vCPU
development VM: a round trip across two processes takes 14 us median / 22 us p99
when both sides poll without blocking, while a blocking receive costs ~130 us per
wake-up. Hence ``recv(timeout=0)`` is a direct non-blocking ``recv`` on the connected
socket(s), with no ``select``/``poll`` (~2 us when nothing waits, mostly Python's
exception). The hub checks its listening socket for new peers with a zero-timeout
``epoll`` (~0.4 us; a non-blocking ``accept`` that finds nobody costs ~8 us): in every
``send``, so a node whose connect returned hears every frame sent after that, and in
``recv(timeout=0)`` at most every :data:`ACCEPT_CHECK_INTERVAL_S`, when the peers had
nothing. ``recv`` with a timeout blocks in one ``epoll`` over all sockets (the listener
included on the hub); :meth:`SeqPacketBus.fileno` is that epoll descriptor, stable across
reconnects. ``recv`` applies the filters itself, so ``recv(timeout=0)`` drains past
rejected frames (python-can's generic loop would return None at the first one).

Sends never block (``MSG_DONTWAIT``): a peer whose socket buffer is full makes
``send`` raise :class:`can.CanOperationError` "Transmit buffer full" with
``error_code = errno.ENOBUFS`` (:func:`drivers.transports.bus.is_queue_full` counts it). The kernel
charges each queued frame ~768 bytes (skb truesize) to the sender's ``SO_SNDBUF``; the
buffer asked for (:data:`SOCKET_BUFFER_BYTES`, which the kernel doubles) holds ~2700
frames, over 1 s at 2500 frames/s, where ``net.core.wmem_max`` allows it (a warning is
logged when the kernel grants less).

Who may join
------------
Every connection is checked with the kernel's credentials of the other end (:mod:`.peers`):
the hub closes a connection it accepted from a process its :class:`~.peers.PeerPolicy`
refuses (another user, unless a member of ``peer_group``; any process but ``peer_pids`` when
given) before reading or sending anything on it, and lists it in :attr:`SeqPacketBus.refused_peers`;
a node that connected to a hub it refuses closes the connection and raises :class:`BusError`
(when opening; later it stays alone and retries). Plain channel names live in this user's private
directory, so no other user can bind one first (:mod:`.channel`).

Channels are :mod:`drivers.transports.seqpacket.channel`'s, the datagram of a frame is
:mod:`drivers.protocol.datagram`'s.
"""

from __future__ import annotations

import errno
import fcntl
import logging
import os
import select
import socket
import stat
import threading
import time
from collections import deque
from collections.abc import Collection
from typing import Any

import can
from can import BusABC, CanOperationError, CanProtocol, Message

from drivers.errors import BusError
from drivers.protocol.datagram import HEADER, MAX_DATAGRAM_BYTES, decode_frame, encode_frame
from drivers.transports.seqpacket.channel import ABSTRACT_PREFIX, check_directory, ensure_private_directory, parse_channel
from drivers.transports.seqpacket.peers import PeerCredentials, PeerPolicy, describe_refusal

LOG = logging.getLogger(__name__)

#: ``SO_SNDBUF``/``SO_RCVBUF`` asked for each socket (bytes; the kernel doubles it, up to ``wmem_max``).
SOCKET_BUFFER_BYTES = 1 << 20
#: Kernel accounting per queued small datagram (bytes, skb truesize measured on Linux 6.x).
BYTES_PER_QUEUED_FRAME = 768
#: Frames a stalled reader should be allowed to fall behind (0.5 s at 2500 frames/s).
WANTED_BACKLOG_FRAMES = 1250
#: Least time between two attempts of a disconnected node to rejoin (s).
RETRY_INTERVAL_S = 0.05
#: Least time between two checks for new peers inside the hub's ``recv(timeout=0)`` (s).
ACCEPT_CHECK_INTERVAL_S = 0.01
#: Pending connections the hub's listening socket holds before connects fail with EAGAIN.
LISTEN_BACKLOG = 64
#: Refused connections :attr:`SeqPacketBus.refused_peers` describes (later ones are only counted).
MAX_REFUSALS_KEPT = 16

_SEND_FLAGS = socket.MSG_DONTWAIT | socket.MSG_NOSIGNAL
_RECV_FLAGS = socket.MSG_DONTWAIT
_NOT_LISTENING = (errno.ECONNREFUSED, errno.ENOENT)
_PEER_GONE = (errno.EPIPE, errno.ECONNRESET, errno.ECONNREFUSED, errno.ENOTCONN, errno.ECONNABORTED, errno.EBADF)
_warned_small_buffer = False


class SeqPacketBus(BusABC):
    """A CAN bus shared by the processes of one host over Unix SOCK_SEQPACKET sockets.

    Parameters
    ----------
    channel : str
        Channel name (``harness``, ``@harness``: abstract address) or socket path (contains ``/``).
    can_filters : list of dict, optional
        python-can filters, applied in software.
    receive_own_messages : bool
        Also receive this node's own frames (echoed locally, ``is_rx=False``).
    fd : bool
        Report :attr:`can.CanProtocol.CAN_FD` (FD frames pass either way).
    socket_buffer_bytes : int
        ``SO_SNDBUF``/``SO_RCVBUF`` asked for each socket (bytes; the kernel doubles it, capped by
        ``net.core.wmem_max``/``rmem_max``).
    peer_group : str or int, optional
        A group (name or gid) whose members may join besides this user (``can.peer_group``).
    peer_pids : collection of int, optional
        The only processes that may be at the other end (a dry run and the rig process it started).
    **kwargs
        Other python-can arguments (``bitrate``, ...) are accepted and ignored.

    Attributes
    ----------
    channel : str
        The channel as given; also the received frames' ``channel``.
    socket_buffer_bytes : int
        ``SO_SNDBUF`` the kernel granted on the first socket (bytes).
    relay_drops : int
        Frames the hub could not relay to a peer whose buffer was full.
    malformed_frames : int
        Datagrams received that were not a frame (wrong size); dropped.
    refused_peers : list of str
        Why each refused connection was refused (the first :data:`MAX_REFUSALS_KEPT`).
    refused_count : int
        Connections refused, all of them.

    Raises
    ------
    BusError
        Unusable channel name, an unsafe directory, a hub this node refuses (another user, or not
        the expected process), or the address can be neither connected to nor bound.

    Notes
    -----
    One thread receives; ``send`` may run in another (python-can's ``send_periodic``):
    connections are swapped as whole tuples under a lock, never changed in place.

    The bus offers the datagram path (:class:`~drivers.transports.datagram_path.DatagramPath`:
    :meth:`send_datagram`, :meth:`recv_datagram`, :attr:`raw_receive_ok`, :attr:`direct_fd`,
    :meth:`note_direct_receive`), which the generic reader and writer use in place of
    :class:`can.Message` objects.
    """

    def __init__(
        self,
        channel: str = "harness",
        can_filters: can.typechecking.CanFilters | None = None,
        receive_own_messages: bool = False,
        fd: bool = False,
        socket_buffer_bytes: int = SOCKET_BUFFER_BYTES,
        peer_group: str | int | None = None,
        peer_pids: Collection[int] | None = None,
        **kwargs: Any,
    ) -> None:
        self._addr = parse_channel(channel)
        self._policy = PeerPolicy.make(peer_group, peer_pids)
        self._refusal_notes: list[str] = []
        self._refusals_to_describe: list[tuple[str, PeerCredentials | OSError]] = []
        self.refused_count = 0
        self.channel = channel
        self.receive_own_messages = bool(receive_own_messages)
        self._can_protocol = CanProtocol.CAN_FD if fd else CanProtocol.CAN_20
        self._buffer_request = int(socket_buffer_bytes)
        self.socket_buffer_bytes = 0
        self.relay_drops = 0
        self.malformed_frames = 0
        self._lock = threading.RLock()
        self._closed = False
        self._peers: tuple[socket.socket, ...] = ()
        self._listener: socket.socket | None = None
        self._owned_file: tuple[int, int] | None = None
        self._own: deque[Message] = deque()
        self._rr = 0
        self._next_retry = 0.0
        self._next_accept_check = 0.0
        self._buf = bytearray(MAX_DATAGRAM_BYTES + 1)
        self._ep = select.epoll()
        self._listen_ep = select.epoll()
        try:
            self._join(initial=True)
            super().__init__(channel=channel, can_filters=can_filters)
        except BaseException:
            self._close_sockets()
            raise

    # --- state ---------------------------------------------------------------------------

    @property
    def is_hub(self) -> bool:
        """True when this node listens on the channel address and relays."""
        return self._listener is not None

    @property
    def peer_count(self) -> int:
        """Connected sockets: the hub's peers, or 1 for a node connected to its hub (0 when alone)."""
        return len(self._peers)

    @property
    def channel_info(self) -> str:  # type: ignore[override]
        role = "hub" if self.is_hub else "node"
        return f"seqpacket channel {self.channel!r} ({role}, {self.peer_count} connected)"

    @property
    def state(self) -> can.BusState:
        """Always ``ACTIVE``: there is no controller that could go error-passive or bus-off."""
        return can.BusState.ACTIVE

    @state.setter
    def state(self, new_state: can.BusState) -> None:
        raise NotImplementedError("a seqpacket bus has no controller state to set")

    def fileno(self) -> int:
        """A file descriptor that is readable when a frame or a connection waits; -1 when shut down.

        It is an epoll descriptor over all of this node's sockets (listener included on
        the hub), so it stays the same across reconnects and covers every peer; an
        asyncio ``add_reader`` or a ``select`` on it works like on a socket.
        """
        return -1 if self._closed else self._ep.fileno()

    @staticmethod
    def _detect_available_configs() -> list[can.typechecking.AutoDetectedConfig]:
        """Channels are created on demand; nothing to detect."""
        return []

    # --- send ----------------------------------------------------------------------------

    def send(self, msg: Message, timeout: float | None = None) -> None:
        """Send one frame to every other node; never blocks.

        Parameters
        ----------
        msg : can.Message
            The frame (at most 64 data bytes).
        timeout : float, optional
            Accepted for the python-can API and ignored: a send never waits (s).

        Raises
        ------
        can.CanOperationError
            The bus is shut down, or a peer's socket buffer is full ("Transmit buffer full",
            ``error_code`` ``errno.ENOBUFS``; the other peers did get the frame).
        ValueError
            The frame does not fit (over 64 data bytes, ID or DLC out of range).
        """
        self.send_datagram(encode_frame(msg))
        if self.receive_own_messages:
            self._own.append(self._echo(msg))

    def send_datagram(self, frame: bytes | bytearray | memoryview) -> None:
        """Send one frame already in the wire format (:mod:`drivers.protocol.datagram`) to every other node; never blocks.

        The writer's path without a :class:`can.Message` (:class:`drivers.writer.FrameWriter` keeps each
        frame's datagram and rewrites its data in place). Never echoed locally.

        Raises
        ------
        can.CanOperationError
            As :meth:`send`.
        """
        if self._closed:
            raise CanOperationError(f"cannot send on {self.channel_info}: the bus is shut down")
        if self._listener is not None:
            if self._listen_ep.poll(0):  # ~0.4 us; a node whose connect returned hears this frame
                self._accept_pending()
        elif not self._peers:
            self._maybe_rejoin()
        peers = self._peers
        full, dropped = self._send_to(peers, frame)
        if dropped and not self._peers and self._listener is None:  # the hub went away: rejoin now
            self._maybe_rejoin()
            peers = self._peers
            full += self._send_to(peers, frame)[0]
        if full:
            raise CanOperationError(
                f"Transmit buffer full: {full} of {len(peers)} peers on {self.channel_info} are not reading "
                f"(socket buffer {self.socket_buffer_bytes} bytes, ~{self.socket_buffer_bytes // BYTES_PER_QUEUED_FRAME} frames)",
                error_code=errno.ENOBUFS,
            )

    def _send_to(self, peers: tuple[socket.socket, ...], frame: bytes | bytearray | memoryview) -> tuple[int, int]:
        """Send ``frame`` to each of ``peers``; (peers whose buffer was full, peers dropped as gone)."""
        full = dropped = 0
        for sock in peers:
            try:
                sock.send(frame, _SEND_FLAGS)
            except BlockingIOError:
                full += 1
            except OSError as err:
                self._drop_or_raise(sock, err, "sending")
                dropped += 1
        return full, dropped

    def _echo(self, msg: Message) -> Message:
        return Message(
            timestamp=time.time(), arbitration_id=msg.arbitration_id, is_extended_id=msg.is_extended_id,
            is_remote_frame=msg.is_remote_frame, is_error_frame=msg.is_error_frame, is_fd=msg.is_fd,
            bitrate_switch=msg.bitrate_switch, error_state_indicator=msg.error_state_indicator,
            dlc=msg.dlc, data=bytearray(msg.data), channel=self.channel, is_rx=False,
        )

    # --- receive -------------------------------------------------------------------------

    def _recv_internal(self, timeout: float | None) -> tuple[Message | None, bool]:
        """Next frame that passes the filters, or None when ``timeout`` (s) passes.

        ``timeout == 0`` is a non-blocking ``recv`` on the connected socket(s), no poll;
        it skips frames the filters reject, so ``recv(timeout=0)`` drains past them.
        Otherwise one ``epoll`` waits on all sockets. Filtering is done here
        (the second item is True).
        """
        msg = self._recv_nowait()
        while msg is not None:
            if self._matches_filters(msg):
                return msg, True
            msg = self._recv_nowait()
        if timeout is not None and timeout <= 0:
            return None, True
        return self._recv_blocking(timeout), True

    def _recv_nowait(self) -> Message | None:
        """One frame if any waits (own echo first); relays it on the hub; None otherwise."""
        if self._closed:
            raise CanOperationError(f"cannot receive on {self.channel_info}: the bus is shut down")
        if self._own:
            return self._own.popleft()
        size = self.recv_datagram()
        return decode_frame(self._buf, size, self.channel) if size else None

    @property
    def raw_receive_ok(self) -> bool:
        """:meth:`recv_datagram` hands over every frame :meth:`recv` would: no filters, no local echo."""
        return not self.receive_own_messages and not self.filters

    @property
    def direct_fd(self) -> int:
        """The one connected socket's descriptor when its datagrams can be read straight off it, else -1.

        That is when this node has exactly one connection (nothing to relay, no round robin); the
        caller checks :attr:`raw_receive_ok` first. The reader then takes them with its compiled receive
        (:meth:`drivers.protocol.decoder.Decoder.receive_datagrams`) and calls :meth:`note_direct_receive` after.
        """
        peers = self._peers
        if len(peers) != 1 or self._closed:
            return -1
        return peers[0].fileno()

    def note_direct_receive(self, malformed: int) -> None:
        """After the reader drained :attr:`direct_fd` itself: count ``malformed`` datagrams, and on the hub
        look for new peers as :meth:`recv_datagram` does when nothing waits."""
        self.malformed_frames += malformed
        if self._listener is not None:
            now = time.monotonic()
            if now >= self._next_accept_check:  # at most every ACCEPT_CHECK_INTERVAL_S (send checks every time)
                self._next_accept_check = now + ACCEPT_CHECK_INTERVAL_S
                if self._listen_ep.poll(0):
                    self._accept_pending()

    def recv_datagram(self, into: memoryview | bytearray | None = None) -> int:
        """Take the next waiting frame's datagram into ``into``; its size in bytes, 0 when none waits.

        Never blocks and builds no :class:`can.Message`: the reader's path
        (:meth:`drivers.reader.FrameReader.poll`) when :attr:`raw_receive_ok`. The datagram is
        :data:`drivers.protocol.datagram.HEADER` then the data, checked for size (a malformed one is counted in
        :attr:`malformed_frames` and skipped); the hub relays it as :meth:`recv` does. Filters
        and local echoes are not applied here.

        Parameters
        ----------
        into : writable bytes-like, optional
            At least :data:`drivers.protocol.datagram.MAX_DATAGRAM_BYTES` + 1 bytes; default the bus's own buffer.

        Raises
        ------
        can.CanOperationError
            The bus is shut down.
        """
        if self._closed:
            raise CanOperationError(f"cannot receive on {self.channel_info}: the bus is shut down")
        buffer = self._buf if into is None else into
        peers = self._peers
        count = len(peers)
        start = self._rr if count > 1 else 0
        for k in range(count):
            index = (start + k) % count
            sock = peers[index]
            while True:  # past malformed datagrams: the frame behind one is read in the same poll
                try:
                    size = sock.recv_into(buffer, MAX_DATAGRAM_BYTES + 1, _RECV_FLAGS)
                except BlockingIOError:
                    break
                except OSError as err:
                    self._drop_or_raise(sock, err, "receiving")
                    break
                if size == 0:  # end of file: the other side closed
                    self._drop_peer(sock)
                    break
                if not HEADER.size <= size <= MAX_DATAGRAM_BYTES:
                    self.malformed_frames += 1
                    continue
                self._rr = index + 1
                if count > 1 and self._listener is not None:
                    self._relay(sock, buffer, size)
                return size
        if self._listener is not None:
            now = time.monotonic()
            if now >= self._next_accept_check:  # at most every ACCEPT_CHECK_INTERVAL_S (send checks every time)
                self._next_accept_check = now + ACCEPT_CHECK_INTERVAL_S
                if self._listen_ep.poll(0) and self._accept_pending():
                    return self.recv_datagram(into)
        elif not peers:
            self._maybe_rejoin()
        return 0

    def _relay(self, source: socket.socket, buffer: memoryview | bytearray, size: int) -> None:
        """Forward the datagram in ``buffer[:size]`` to every peer but its source (hub only)."""
        frame = bytes(memoryview(buffer)[:size])
        for sock in self._peers:
            if sock is source:
                continue
            try:
                sock.send(frame, _SEND_FLAGS)
            except BlockingIOError:
                self.relay_drops += 1
            except OSError as err:
                self._drop_or_raise(sock, err, "relaying")

    def _recv_blocking(self, timeout: float | None) -> Message | None:
        """Wait in epoll over all sockets until a frame passes the filters or ``timeout`` (s) passes."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            wait = -1.0 if deadline is None else deadline - time.monotonic()
            if deadline is not None and wait <= 0:
                return None
            if self._listener is None and not self._peers:  # alone: wake up to retry joining
                wait = RETRY_INTERVAL_S if wait < 0 else min(wait, RETRY_INTERVAL_S)
            for fd, _ in self._ep.poll(wait):
                if self._listener is not None and fd == self._listener.fileno():
                    self._accept_pending()
            msg = self._recv_nowait()
            while msg is not None:
                if self._matches_filters(msg):
                    return msg
                msg = self._recv_nowait()

    # --- joining, accepting, dropping ----------------------------------------------------

    def _new_socket(self) -> socket.socket:
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        sock.setblocking(False)
        self._size_buffers(sock)
        return sock

    def _size_buffers(self, sock: socket.socket) -> None:
        global _warned_small_buffer
        for option in (socket.SO_SNDBUF, socket.SO_RCVBUF):
            try:
                sock.setsockopt(socket.SOL_SOCKET, option, self._buffer_request)
            except OSError:
                pass  # the kernel's default stays
        if self.socket_buffer_bytes:
            return
        self.socket_buffer_bytes = granted = sock.getsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF)
        if granted < WANTED_BACKLOG_FRAMES * BYTES_PER_QUEUED_FRAME and not _warned_small_buffer:
            _warned_small_buffer = True
            LOG.warning(
                "seqpacket: the kernel granted SO_SNDBUF %d bytes (asked %d): a stalled reader can fall only "
                "~%d frames behind before sends fail; raise net.core.wmem_max to at least %d",
                granted, self._buffer_request, granted // BYTES_PER_QUEUED_FRAME, self._buffer_request,
            )

    def _join(self, initial: bool) -> None:
        """Connect to the hub, or become it when nobody listens; stay alone on a busy hub.

        Raises (only when ``initial``) BusError when the address is unusable.
        """
        try:
            if self._addr.path is None:
                self._join_abstract()
            else:
                self._check_directory()
                with _DirectoryLock(self._addr.path):
                    self._join_path()
        except BusError:
            if initial:
                raise
            LOG.debug("seqpacket: rejoining %r failed", self.channel, exc_info=True)
        except OSError as err:
            if initial:
                raise BusError(f"cannot open seqpacket channel {self.channel!r} ({self._describe()}): {err}") from err
            LOG.debug("seqpacket: rejoining %r failed: %s", self.channel, err)

    def _check_directory(self) -> None:
        """Make the private directory, or check a socket path's directory (raises BusError)."""
        assert self._addr.path is not None
        directory = os.path.dirname(self._addr.path) or "."
        if self._addr.private:
            ensure_private_directory(directory)
        else:
            check_directory(directory, self._policy.group_gid)

    @property
    def refused_peers(self) -> list[str]:
        """Why each refused connection was refused (the first :data:`MAX_REFUSALS_KEPT`).

        A connection the hub refused during a loop tick was only screened then (no name lookup,
        no log line); it is described, and its warning logged, here, on the first read after it.
        """
        self._describe_refusals()
        return list(self._refusal_notes)

    def _describe_refusals(self) -> None:
        pending, self._refusals_to_describe = self._refusals_to_describe, []
        for role, refused in pending:
            self._note_refusal(role, describe_refusal(self._policy, refused))

    def _note_refusal(self, role: str, reason: str) -> str:
        note = f"refused {role} on seqpacket channel {self.channel!r}: {reason}"
        self._refusal_notes.append(note)
        LOG.warning("seqpacket: %s", note)
        return note

    def _refuse(self, sock: socket.socket, reason: str, role: str) -> str:
        """Close ``sock`` (a connection refused by the peer check), note why now, and return the note."""
        sock.close()
        self.refused_count += 1
        return self._note_refusal(role, reason)

    def _refuse_quietly(self, sock: socket.socket, refused: PeerCredentials | OSError, role: str) -> None:
        """Close ``sock`` and count it; describing it waits for :attr:`refused_peers` (tick-safe)."""
        sock.close()
        self.refused_count += 1
        if len(self._refusal_notes) + len(self._refusals_to_describe) < MAX_REFUSALS_KEPT:
            self._refusals_to_describe.append((role, refused))

    def _join_abstract(self) -> None:
        for _ in range(3):  # a node that lost the race to bind connects to the winner
            if self._connect() or self._become_hub():
                return

    def _join_path(self) -> None:
        if self._connect():
            return
        try:
            info = os.lstat(self._addr.address)
        except FileNotFoundError:
            pass
        else:
            if not stat.S_ISSOCK(info.st_mode):
                raise BusError(
                    f"seqpacket channel path {self.channel!r} exists and is not a socket; remove it or pick another path"
                )
            os.unlink(self._addr.address)  # stale: connect was refused (we hold the directory lock)
        self._become_hub()

    def _connect(self) -> bool:
        """True once connected to a hub (or when it is busy: then alone, retrying later)."""
        sock = self._new_socket()
        try:
            sock.connect(self._addr.address)
        except OSError as err:
            sock.close()
            if err.errno in _NOT_LISTENING:
                return False
            if err.errno in (errno.EAGAIN, errno.EWOULDBLOCK):  # the hub's accept queue is full
                LOG.warning("seqpacket: the hub of %r is not accepting; retrying", self.channel)
                return True
            raise
        refusal = self._policy.check(sock)
        if refusal:  # a hub this node does not trust: never send it a frame
            raise BusError(self._refuse(sock, refusal, "the hub") + "; nothing was sent to it")
        self._add_peer(sock)
        return True

    def _become_hub(self) -> bool:
        """Bind and listen; False when another node bound the address first."""
        listener = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
        try:
            listener.bind(self._addr.address)
        except OSError as err:
            listener.close()
            if err.errno == errno.EADDRINUSE:
                return False
            raise
        if self._addr.path is not None:  # before listen: nobody can connect yet; the directory guards the window
            os.chmod(self._addr.path, 0o600 if self._policy.group_gid is None else 0o660)
        listener.listen(LISTEN_BACKLOG)
        listener.setblocking(False)
        if self._addr.path is not None:
            info = os.stat(self._addr.path)
            self._owned_file = (info.st_dev, info.st_ino)
        with self._lock:
            self._listener = listener
            self._ep.register(listener.fileno(), select.EPOLLIN)
            self._listen_ep.register(listener.fileno(), select.EPOLLIN)
        return True

    def _maybe_rejoin(self) -> None:
        """Alone and not the hub: try to join again, at most every RETRY_INTERVAL_S."""
        now = time.monotonic()
        if now < self._next_retry:
            return
        with self._lock:
            if self._closed or self._peers or self._listener is not None:
                return
            self._next_retry = now + RETRY_INTERVAL_S
            self._join(initial=False)

    def _accept_pending(self) -> bool:
        """Accept every waiting connection (hub); True if any."""
        accepted = False
        listener = self._listener
        while listener is not None:
            try:
                sock, _ = listener.accept()
            except (BlockingIOError, InterruptedError):
                break
            except OSError as err:  # ECONNABORTED etc.: that connection is gone
                LOG.debug("seqpacket: accept on %r failed: %s", self.channel, err)
                break
            refused = self._policy.screen(sock)
            if refused is not None:  # closed before anything is read from it or sent to it
                self._refuse_quietly(sock, refused, "a connection")
                continue
            sock.setblocking(False)
            self._size_buffers(sock)
            self._add_peer(sock)
            accepted = True
        return accepted

    def _add_peer(self, sock: socket.socket) -> None:
        with self._lock:
            if self._closed:
                sock.close()
                return
            self._peers = (*self._peers, sock)
            self._ep.register(sock.fileno(), select.EPOLLIN)

    def _drop_or_raise(self, sock: socket.socket, err: OSError, doing: str) -> None:
        if isinstance(err, ConnectionError) or err.errno in _PEER_GONE:
            self._drop_peer(sock)
            return
        raise CanOperationError(f"{doing} on {self.channel_info} failed: {err}", error_code=err.errno) from err

    def _drop_peer(self, sock: socket.socket) -> None:
        """Forget a connection whose other side is gone; a lone node retries joining at once."""
        with self._lock:
            if sock not in self._peers:
                return
            self._peers = tuple(p for p in self._peers if p is not sock)
            self._unregister_and_close(sock)
            if self._listener is None and not self._peers:
                self._next_retry = 0.0

    def _unregister_and_close(self, sock: socket.socket) -> None:
        fd = sock.fileno()
        if fd >= 0:
            try:
                self._ep.unregister(fd)
            except (OSError, ValueError):
                pass
        sock.close()

    def _describe(self) -> str:
        return "abstract socket @" + self._addr.address[len(ABSTRACT_PREFIX):] if self._addr.path is None else "socket file"

    # --- shutdown ------------------------------------------------------------------------

    def shutdown(self) -> None:
        """Close every socket (the listener first, so peers cannot reconnect to a dying hub).

        Idempotent. The hub unlinks the socket file it created. Connections refused during the run
        are described and logged now, if nothing read :attr:`refused_peers` before.
        """
        self._describe_refusals()
        super().shutdown()
        with self._lock:
            if self._closed:
                return
            self._close_sockets()

    def _close_sockets(self) -> None:
        self._closed = True
        listener, self._listener = self._listener, None
        if listener is not None:
            self._unlink_owned_file()
            listener.close()
        peers, self._peers = self._peers, ()
        for sock in peers:
            sock.close()
        self._own.clear()
        self._ep.close()
        self._listen_ep.close()

    def _unlink_owned_file(self) -> None:
        if self._owned_file is None or self._addr.path is None:
            return
        try:
            info = os.stat(self._addr.path)
            if (info.st_dev, info.st_ino) == self._owned_file:
                os.unlink(self._addr.path)
        except OSError:
            pass
        self._owned_file = None


class _DirectoryLock:
    """``flock`` on the socket file's directory, so two nodes never both unlink and bind a path."""

    def __init__(self, path: str):
        self._directory = os.path.dirname(path) or "."
        self._fd = -1

    def __enter__(self) -> _DirectoryLock:
        self._fd = os.open(self._directory, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        fcntl.flock(self._fd, fcntl.LOCK_EX)
        return self

    def __exit__(self, *exc: object) -> None:
        fcntl.flock(self._fd, fcntl.LOCK_UN)
        os.close(self._fd)

