"""Transmit side: protected frames encoded into preallocated, reused ``can.Message`` objects.

Each message a node sends has one :class:`TxFrame`: a ``can.Message`` built at
configure time whose ``data`` bytearray is overwritten in place on every send, and
the message's rolling counter. On a bus that offers the datagram path
(:class:`~drivers.transports.datagram_path.DatagramPath`, e.g. ``seqpacket``) the frame is encoded
instead into its preallocated datagram (:mod:`drivers.protocol.datagram`, header written once) and
handed to its :meth:`~drivers.transports.datagram_path.DatagramPath.send_datagram`: the same bytes on
the wire without python-can's per-message path. The counter advances only when ``bus.send``
succeeded, so a frame the bus refused leaves no gap for the receiver to count.

``send`` never blocks (``timeout=0``) and never raises on a bus failure: a full
transmit queue (``ENOBUFS``, "No buffer space available") or another send error
is counted in the shared :class:`~drivers.transports.bus.BusHealth` and reported by the
return value, so the tick decides what to do (the supervisor trips on it).
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import can

from drivers.errors import ProtocolError
from drivers.protocol.codec import MessageCodec, Protocol
from drivers.protocol.datagram import HEADER
from drivers.protocol.e2e import COUNTER_MODULO
from drivers.protocol.frame_flags import FrameTap, flags_of
from drivers.protocol.protocol_values import EstopSource
from drivers.transports.bus import BusHealth
from drivers.transports.datagram_path import datagram_path

#: What the harness sends.
HARNESS_TX = ("ACTUATOR_CMD", "HEARTBEAT", "ESTOP", "RIG_CONTROL", "DRIVE_RESET")
#: What the rig (servo controller and virtual rig) sends.
RIG_TX = ("TABLE_SENSORS", "BASE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS", "ACTUATOR_STATUS", "RIG_STATUS", "ESTOP")
#: What it sends on the CAN FD protocol besides: the whole sensor set in one frame.
RIG_TX_FD = (*RIG_TX, "SENSOR_SET")
STEP_INDEX_MODULO = 1 << 24


class TxFrame:
    """One message's preallocated frame and rolling counter.

    Attributes
    ----------
    codec : MessageCodec
    msg : can.Message
        The reused frame (its ``data`` is rewritten in place); a CAN FD frame, with the bit-rate
        switch the DBC names, where the message is one.
    counter : int
        The counter the next frame will carry (0..15).
    sent : int
        Frames sent successfully.
    flags : int
        Its kind (:mod:`drivers.protocol.frame_flags`).
    datagram : bytearray
        The frame in the datagram layout (:mod:`drivers.protocol.datagram`; header written here, data rewritten in place).
    payload : memoryview
        The data field of :attr:`datagram`.
    """

    __slots__ = ("codec", "msg", "counter", "sent", "flags", "datagram", "payload")

    def __init__(self, codec: MessageCodec):
        self.codec = codec
        self.msg = can.Message(
            arbitration_id=codec.frame_id, is_extended_id=False, dlc=codec.length, data=bytearray(codec.length),
            is_rx=False, is_fd=codec.is_fd, bitrate_switch=codec.bitrate_switch,
        )
        self.counter = 0
        self.sent = 0
        self.flags = flags_of(self.msg)
        self.datagram = bytearray(HEADER.size + codec.length)
        HEADER.pack_into(self.datagram, 0, codec.frame_id, self.flags, codec.length)
        self.payload = memoryview(self.datagram)[HEADER.size :]


class FrameWriter:
    """Encodes and sends this node's messages.

    Parameters
    ----------
    bus : can.BusABC
        An open bus.
    protocol : Protocol
        The compiled DBC.
    names : sequence of str
        Messages this node sends (:data:`HARNESS_TX` or :data:`RIG_TX`).
    health : BusHealth, optional
        Shared with the reader; a new one by default.

    Attributes
    ----------
    fd : bool
        The protocol is the CAN FD variant (every frame an FD frame).
    """

    def __init__(self, bus: can.BusABC, protocol: Protocol, names: Sequence[str], health: BusHealth | None = None):
        self.bus = bus
        self.fd = protocol.fd
        self.health = health if health is not None else BusHealth()
        self._frames = {name: TxFrame(protocol[name]) for name in names}
        channel = getattr(bus, "channel_id", getattr(bus, "channel", None))  # virtual: channel_id
        for tx in self._frames.values():  # logs name the channel the frame went out on
            tx.msg.channel = channel if isinstance(channel, (str, int)) else None
        self._channel = channel if isinstance(channel, (str, int)) else None
        #: Called with every frame the bus took, e.g. the run recorder's CAN log
        #: (:data:`~drivers.protocol.frame_flags.FrameTap`; the data is rewritten by the next send: copy it).
        self.tap: FrameTap | None = None
        #: The bus again when it offers the datagram path (:class:`~drivers.transports.datagram_path.DatagramPath`,
        #: e.g. ``seqpacket``): frames are then sent without a Message.
        self._datagrams = datagram_path(bus)

    def frame(self, name: str) -> TxFrame:
        """The :class:`TxFrame` of message ``name``."""
        try:
            return self._frames[name]
        except KeyError as err:
            raise ProtocolError(f"this writer does not send {name!r}; it sends: {', '.join(self._frames)}") from err

    @property
    def send_failures(self) -> int:
        """Failed sends so far (shared :class:`BusHealth`)."""
        return self.health.send_failures

    def send(self, name: str, values: Sequence[float], now: float) -> bool:
        """Encode ``values`` (SI, DBC order) with the next counter and CRC, and send.

        Returns
        -------
        bool
            True if the bus took the frame; False if the send failed (counted).

        Raises
        ------
        ProtocolError
            A value is outside the DBC range or the count is wrong (a caller bug).
        """
        return self.send_frame(self.frame(name), values, now)

    def send_frame(self, tx: TxFrame, values: Sequence[float], now: float) -> bool:
        """As :meth:`send`, for a :class:`TxFrame` looked up once beforehand."""
        datagrams = self._datagrams
        data: bytearray | memoryview = tx.payload if datagrams is not None else tx.msg.data
        tx.codec.encode_into(data, values, tx.counter)  # a ProtocolError here is the caller's bug: it propagates
        try:
            if datagrams is not None:
                datagrams.send_datagram(tx.datagram)
            else:
                tx.msg.timestamp = now
                self.bus.send(tx.msg, timeout=0)
        except (can.CanError, OSError, ValueError) as err:  # ValueError: select() on a closed socket
            self.health.note_send_failure(err, now)
            return False
        tx.counter = (tx.counter + 1) % COUNTER_MODULO
        tx.sent += 1
        if self.tap is not None:
            self.tap(time.time(), tx.codec.frame_id, tx.flags, data, self._channel)
        return True


class HarnessWriter(FrameWriter):
    """The harness side: actuator command, heartbeat, E-stop, rig control, drive reset."""

    def __init__(self, bus: can.BusABC, protocol: Protocol, health: BusHealth | None = None):
        super().__init__(bus, protocol, HARNESS_TX, health)
        self._cmd = self.frame("ACTUATOR_CMD")
        self._hb = self.frame("HEARTBEAT")
        self._estop = self.frame("ESTOP")
        self._ctrl = self.frame("RIG_CONTROL")
        self._cmd_values = [0.0, 0.0]  # enable, force
        self._hb_values = [0.0]
        self._estop_values = [0.0, 0.0, 0.0]
        self._ctrl_values = [0.0, 0.0, 0.0, 0.0]
        self._reset = self.frame("DRIVE_RESET")
        self._reset_values = [0.0]

    def command(self, force_n: float, enable: bool, now: float) -> bool:
        """Send ACTUATOR_CMD: ``force_n`` (N, |force| <= 30 kN) and the enable bit."""
        values = self._cmd_values
        values[0] = 1.0 if enable else 0.0
        values[1] = force_n
        return self.send_frame(self._cmd, values, now)

    def heartbeat(self, state: int, now: float) -> bool:
        """Send HEARTBEAT with the harness lifecycle ``state`` (0..15; the DBC's value table names 0..5)."""
        self._hb_values[0] = state
        return self.send_frame(self._hb, self._hb_values, now)

    def estop(self, active: bool, now: float, source: int = EstopSource.HARNESS, reason: int = 0) -> bool:
        """Send ESTOP (``source`` an :class:`~drivers.protocol.protocol_values.EstopSource`, ``reason`` 0..255).

        Repeat while active.
        """
        values = self._estop_values
        values[0], values[1], values[2] = (1.0 if active else 0.0), source, reason
        return self.send_frame(self._estop, values, now)

    def rig_control(self, command: int, lockstep: bool, now: float, fault_id: int = 0, fault_param: float = 0.0) -> bool:
        """Send RIG_CONTROL: ``command`` a :class:`~drivers.protocol.protocol_values.RigCommand`, the lockstep flag,
        fault injection."""
        values = self._ctrl_values
        values[0], values[1], values[2], values[3] = command, (1.0 if lockstep else 0.0), fault_id, fault_param
        return self.send_frame(self._ctrl, values, now)

    def drive_reset(self, fault_code: int, now: float) -> bool:
        """Send DRIVE_RESET: the operator's reset of the drive's latched fault ``fault_code`` (0..255).

        Send it once, before arming (never from the tick): the drive clears only a reset-able
        latched fault whose code is ``fault_code`` (``drivers/protocol/PROTOCOL.md``).
        """
        self._reset_values[0] = fault_code
        return self.send_frame(self._reset, self._reset_values, now)


class RigWriter(FrameWriter):
    """The rig side (virtual rig / sensor concentrator / servo controller): sensors and status.

    On the CAN FD protocol (``protocol.fd``) it also sends SENSOR_SET (:meth:`sensor_set`).
    """

    def __init__(self, bus: can.BusABC, protocol: Protocol, health: BusHealth | None = None):
        super().__init__(bus, protocol, RIG_TX_FD if protocol.fd else RIG_TX, health)
        self._table = self.frame("TABLE_SENSORS")
        self._base = self.frame("BASE_SENSORS")
        self._drifts = self.frame("STORY_DRIFTS")
        self._accels = self.frame("FLOOR_ACCELS")
        self._status = self.frame("ACTUATOR_STATUS")
        self._rig = self.frame("RIG_STATUS")
        self._estop = self.frame("ESTOP")
        self._v3 = [0.0, 0.0, 0.0]
        self._v4 = [0.0, 0.0, 0.0, 0.0]
        self._v5 = [0.0] * 6

    def _send3(self, tx: TxFrame, a: float, b: float, c: float, now: float) -> bool:
        values = self._v3
        values[0], values[1], values[2] = a, b, c
        return self.send_frame(tx, values, now)

    def table(self, x0: float, xd0: float, xdd0: float, now: float) -> bool:
        """Send TABLE_SENSORS: x_0 (m), xdot_0 (m/s), xddot_0 (m/s^2)."""
        return self._send3(self._table, x0, xd0, xdd0, now)

    def base(self, yb: float, ydb: float, yddb: float, now: float) -> bool:
        """Send BASE_SENSORS: y_b (m), ydot_b (m/s), yddot_b (m/s^2)."""
        return self._send3(self._base, yb, ydb, yddb, now)

    def drifts(self, d1: float, d2: float, d3: float, now: float) -> bool:
        """Send STORY_DRIFTS: drifts of stories 1-3 (m)."""
        return self._send3(self._drifts, d1, d2, d3, now)

    def accels(self, a1: float, a2: float, a3: float, now: float) -> bool:
        """Send FLOOR_ACCELS: absolute accelerations of floors 1-3 (m/s^2)."""
        return self._send3(self._accels, a1, a2, a3, now)

    def sensor_set(self, values: Sequence[float], now: float) -> bool:
        """Send SENSOR_SET (CAN FD protocol only): x_0, xdot_0, xddot_0, y_b, ydot_b, yddot_b (m, m/s, m/s^2),
        drift_1..3 (m), accel_1..3 (m/s^2), in that order."""
        return self.send("SENSOR_SET", values, now)

    def estop(self, active: bool, now: float, source: int = EstopSource.RIG, reason: int = 0) -> bool:
        """Send ESTOP from the rig (``source`` ``EstopSource.RIG`` or ``EstopSource.SERVO``)."""
        return self._send3(self._estop, 1.0 if active else 0.0, source, reason, now)

    def actuator_status(self, force_n: float, drive_state: int, pressure_ok: bool, fault_code: int, now: float) -> bool:
        """Send ACTUATOR_STATUS: ``drive_state`` (:class:`~drivers.protocol.protocol_values.DriveState`), pressure ok,
        ``fault_code`` (:class:`~drivers.protocol.protocol_values.FaultCode` or an injected code), force (N)."""
        values = self._v4
        values[0], values[1], values[2], values[3] = drive_state, (1.0 if pressure_ok else 0.0), fault_code, force_n
        return self.send_frame(self._status, values, now)

    def rig_status(
        self, running: bool, lockstep: bool, fault_active: bool, record_time_s: float, step: int, now: float,
        start_refused: bool = False,
    ) -> bool:
        """Send RIG_STATUS; ``record_time_s`` 0..1677 s, ``step`` is sent modulo 2**24; ``start_refused``: the last
        start table was refused (the table already ran)."""
        values = self._v5
        values[0], values[1], values[2] = (1.0 if running else 0.0), (1.0 if lockstep else 0.0), (1.0 if fault_active else 0.0)
        # in the DBC's bit order: start_refused (bit 15) before record_time and step_index
        values[3], values[4], values[5] = (1.0 if start_refused else 0.0), record_time_s, step % STEP_INDEX_MODULO
        return self.send_frame(self._rig, values, now)
