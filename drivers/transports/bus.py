"""Open a python-can bus by interface and channel, and keep account of bus health.

:func:`open_bus` works for any python-can interface (``virtual``, ``socketcan``,
``pcan``, ``kvaser``, ...). For socketcan it checks the kernel and the channel
first, so a missing ``vcan0`` says how to create it instead of a bare errno.

python-can's socketcan backend does not report bus-off through ``Bus.state``;
:class:`BusHealth` therefore classifies error frames by the error-class bits in
their ID and data (``linux/can/error.h``) and counts send failures (``ENOBUFS``,
"No buffer space available", when the transmit queue is full).
"""

from __future__ import annotations

import errno
import socket
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import can

from drivers.errors import BusError
from drivers.transports import seqpacket

SYS_NET = Path("/sys/class/net")
WITH_VCAN_HINT = "this project's scripts/with-vcan runs the tests inside User-Mode Linux, which has SocketCAN"

# linux/can/error.h: error class (mask) in can_id
CAN_ERR_TX_TIMEOUT = 0x001
CAN_ERR_LOSTARB = 0x002
CAN_ERR_CRTL = 0x004
CAN_ERR_PROT = 0x008
CAN_ERR_TRX = 0x010
CAN_ERR_ACK = 0x020
CAN_ERR_BUSOFF = 0x040
CAN_ERR_BUSERROR = 0x080
CAN_ERR_RESTARTED = 0x100
# linux/can/error.h: controller problems in data[1]
CAN_ERR_CRTL_RX_OVERFLOW = 0x01
CAN_ERR_CRTL_TX_OVERFLOW = 0x02
CAN_ERR_CRTL_RX_WARNING = 0x04
CAN_ERR_CRTL_TX_WARNING = 0x08
CAN_ERR_CRTL_RX_PASSIVE = 0x10
CAN_ERR_CRTL_TX_PASSIVE = 0x20
CAN_ERR_CRTL_ACTIVE = 0x40


def kernel_has_socketcan() -> bool:
    """True when this kernel lets a process open a raw CAN socket (``CONFIG_CAN`` and ``can-raw``)."""
    family = getattr(socket, "AF_CAN", None)
    if family is None:
        return False
    try:
        sock = socket.socket(family, socket.SOCK_RAW, socket.CAN_RAW)
    except OSError:
        return False
    sock.close()
    return True


#: MTU of a CAN interface that carries CAN FD frames (``struct canfd_frame``, bytes); classic CAN is 16.
CANFD_MTU = 72


def socketcan_preflight(channel: str, *, sys_net: Path = SYS_NET, kernel_ok: bool | None = None, fd: bool = False) -> None:
    """Check that a socketcan channel can be opened; raise a BusError that says how to fix it.

    Parameters
    ----------
    channel : str
        Network interface name, e.g. ``vcan0`` or ``can0``.
    sys_net : Path
        Where network interfaces are listed (for tests).
    kernel_ok : bool, optional
        Override of :func:`kernel_has_socketcan` (for tests).
    fd : bool
        The bus must carry CAN FD frames: the interface's MTU must be :data:`CANFD_MTU` (72).

    Raises
    ------
    BusError
        No SocketCAN in the kernel, no such interface, the interface is down, or (``fd``) its
        MTU is too small for CAN FD frames.
    """
    if kernel_ok is None:
        kernel_ok = kernel_has_socketcan()
    virtual = channel.startswith("vcan")
    if not kernel_ok:
        raise BusError(
            f"cannot open socketcan channel {channel!r}: this kernel has no SocketCAN support "
            f"(no AF_CAN sockets). Load it with `modprobe vcan` (and `modprobe can-raw`); "
            f"where the kernel has no CAN at all, {WITH_VCAN_HINT}"
        )
    if not (sys_net / channel).exists():
        if virtual:
            fix = f"create it with `ip link add dev {channel} type vcan && ip link set up {channel}` (as root)"
        else:
            fix = f"check the adapter is plugged in and its driver loaded, then `ip link set {channel} up type can bitrate <bps>`"
        raise BusError(f"CAN interface {channel!r} does not exist (no {sys_net / channel}); {fix}")
    operstate = sys_net / channel / "operstate"
    flags = sys_net / channel / "flags"
    if flags.exists() and not int(flags.read_text().strip(), 0) & 0x1:  # IFF_UP
        raise BusError(f"CAN interface {channel!r} is down (operstate {_read(operstate)}); `ip link set up {channel}`")
    mtu = sys_net / channel / "mtu"
    if fd and mtu.exists() and int(mtu.read_text().strip()) < CANFD_MTU:
        fix = (f"`ip link set {channel} down && ip link set {channel} mtu {CANFD_MTU} && ip link set up {channel}`" if virtual
               else f"`ip link set {channel} up type can bitrate <bps> dbitrate <bps> fd on`")
        raise BusError(
            f"CAN interface {channel!r} has MTU {mtu.read_text().strip()}, too small for CAN FD frames (can.fd is true, "
            f"expected MTU {CANFD_MTU}); {fix} (as root)"
        )


def _read(path: Path) -> str:
    try:
        return path.read_text().strip()
    except OSError:
        return "unknown"


def open_bus(
    interface: str,
    channel: str,
    bitrate_bps: int | None = None,
    *,
    can_filters: Sequence[dict[str, Any]] | None = None,
    fd: bool = False,
    data_bitrate_bps: int | None = None,
    **kwargs: Any,
) -> can.BusABC:
    """Open a python-can bus, as ``can.Bus(interface=..., channel=..., bitrate=...)`` does.

    Parameters
    ----------
    interface : str
        Any python-can interface name: ``virtual``, ``socketcan``, ``seqpacket``, ``pcan``, ``kvaser``, ...
    channel : str
        Interface channel: ``vcan0``/``can0`` for socketcan, a shared name for virtual and seqpacket.
    bitrate_bps : int, optional
        Nominal bitrate (bit/s), for interfaces that set it (socketcan takes it from ``ip link``).
    can_filters : sequence of dict, optional
        python-can filters (``{"can_id": .., "can_mask": ..}``); default: receive everything.
    fd : bool
        Open the bus for CAN FD frames (python-can's ``fd=True``; socketcan needs an MTU of 72).
    data_bitrate_bps : int, optional
        Data-phase bitrate of CAN FD frames (bit/s), for interfaces that set it (python-can's
        ``data_bitrate``; socketcan takes it from ``ip link``).
    **kwargs
        Passed to :class:`can.Bus` (e.g. ``receive_own_messages=True``).

    Returns
    -------
    can.BusABC
        The open bus; close it with ``shutdown()`` (idempotent) or a ``with`` block.

    Raises
    ------
    BusError
        Unknown interface, missing driver library, missing or down channel; says how to fix it.
    """
    seqpacket.register()  # python-can knows it from the installed entry point; this, where that is not installed
    if interface == "socketcan":
        socketcan_preflight(channel, fd=fd)
    if fd:
        kwargs.update(fd=True, data_bitrate=data_bitrate_bps)
    try:
        return can.Bus(
            interface=interface,
            channel=channel,
            bitrate=bitrate_bps,
            can_filters=list(can_filters) if can_filters else None,
            **kwargs,
        )
    except can.CanInterfaceNotImplementedError as err:
        raise BusError(
            f"python-can interface {interface!r} is not available: {err}; "
            f"expected one of {', '.join(sorted(can.VALID_INTERFACES))} with its driver installed"
        ) from err
    except (can.CanError, OSError, ValueError) as err:
        raise BusError(f"cannot open {interface} channel {channel!r}: {err}") from err


class BusHealth:
    """Counters of error frames, controller state and send failures, updated in place.

    Attributes
    ----------
    state : can.BusState
        ``ACTIVE``, ``PASSIVE`` (error passive) or ``ERROR`` (bus-off), from error frames;
        ask :attr:`bus_off` and :attr:`error_passive` rather than comparing it.
    error_frames, bus_off_events, error_passive_events, error_warning_events : int
    restarts, controller_overflows, protocol_errors, ack_errors, tx_timeouts, lost_arbitration : int
    send_failures : int
        Every failed ``send``.
    tx_queue_full : int
        Failed sends that were ``ENOBUFS`` (transmit queue full) or a full virtual queue.
    last_error_time : float
        ``now`` of the last error frame or send failure (s), NaN if none.
    last_send_error : str
        Text of the last send failure.
    """

    __slots__ = (
        "state", "error_frames", "bus_off_events", "error_passive_events", "error_warning_events",
        "restarts", "controller_overflows", "protocol_errors", "ack_errors", "tx_timeouts",
        "lost_arbitration", "send_failures", "tx_queue_full", "last_error_time", "last_send_error",
    )

    def __init__(self) -> None:
        self.state = can.BusState.ACTIVE
        self.error_frames = 0
        self.bus_off_events = 0
        self.error_passive_events = 0
        self.error_warning_events = 0
        self.restarts = 0
        self.controller_overflows = 0
        self.protocol_errors = 0
        self.ack_errors = 0
        self.tx_timeouts = 0
        self.lost_arbitration = 0
        self.send_failures = 0
        self.tx_queue_full = 0
        self.last_error_time = float("nan")
        self.last_send_error = ""

    @property
    def bus_off(self) -> bool:
        """True from a bus-off error frame until a restarted/active one."""
        return self.state is can.BusState.ERROR

    @property
    def error_passive(self) -> bool:
        """True from an error-passive controller report until an error-active or restarted one (never when bus-off)."""
        return self.state is can.BusState.PASSIVE

    def note_error_frame(self, error_class: int, data: bytes | bytearray | memoryview, now: float) -> None:
        """Classify one error frame by its error-class bits (its arbitration ID) and its data (byte 1: the controller's)."""
        cls = error_class
        ctrl = data[1] if len(data) > 1 else 0
        self.error_frames += 1
        self.last_error_time = now
        if cls & CAN_ERR_BUSOFF:
            self.bus_off_events += 1
            self.state = can.BusState.ERROR
        if cls & CAN_ERR_RESTARTED:
            self.restarts += 1
            self.state = can.BusState.ACTIVE
        if cls & CAN_ERR_CRTL:
            self._note_controller(ctrl)
        if cls & (CAN_ERR_PROT | CAN_ERR_BUSERROR | CAN_ERR_TRX):
            self.protocol_errors += 1
        if cls & CAN_ERR_ACK:
            self.ack_errors += 1
        if cls & CAN_ERR_TX_TIMEOUT:
            self.tx_timeouts += 1
        if cls & CAN_ERR_LOSTARB:
            self.lost_arbitration += 1

    def _note_controller(self, ctrl: int) -> None:
        if ctrl & (CAN_ERR_CRTL_RX_OVERFLOW | CAN_ERR_CRTL_TX_OVERFLOW):
            self.controller_overflows += 1
        if ctrl & (CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_WARNING):
            self.error_warning_events += 1
        if ctrl & (CAN_ERR_CRTL_RX_PASSIVE | CAN_ERR_CRTL_TX_PASSIVE):
            self.error_passive_events += 1
            if self.state != can.BusState.ERROR:
                self.state = can.BusState.PASSIVE
        if ctrl & CAN_ERR_CRTL_ACTIVE:
            self.state = can.BusState.ACTIVE

    def note_send_failure(self, err: BaseException, now: float) -> None:
        """Count one failed ``send`` (``can.CanOperationError`` or ``OSError``)."""
        self.send_failures += 1
        self.last_error_time = now
        self.last_send_error = str(err)
        if is_queue_full(err):
            self.tx_queue_full += 1


def is_queue_full(err: BaseException) -> bool:
    """True when a send failed because the transmit queue is full (``ENOBUFS``)."""
    code = getattr(err, "error_code", None) or getattr(err, "errno", None)
    if code == errno.ENOBUFS:
        return True
    text = str(err)
    return "No buffer space available" in text or "Transmit buffer full" in text or "Could not send message" in text
