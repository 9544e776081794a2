"""Receive side: poll the bus inside the tick and keep the latest valid sample of each message.

The loop calls :meth:`FrameReader.poll` once per tick; it drains the bus with
``bus.recv(timeout=0)`` (no Notifier thread: a thread adds ~80 us median and milliseconds
at the tail, benchmarks/README.md, "Timing facts the loop is built on"), decodes every
frame through the :class:`~drivers.protocol.codec.Decoder`, and updates preallocated
:class:`Sample` objects in place. Besides the samples it keeps:

- error-frame and bus-off accounting in a shared :class:`~drivers.transports.bus.BusHealth`;
- frames on "foreign" IDs, by default the actuator command: any such frame that this
  process did not send means another node is commanding the actuator (a pre-arm
  check refuses to arm while :attr:`ReaderCounters.foreign_commands` is non-zero).
  This relies on the bus not echoing our own frames, python-can's default
  (``receive_own_messages=False``); never open the harness bus with it on;
- E-stop frames: a valid frame with ``active=1`` latches :attr:`FrameReader.estop_requested`,
  and so does any malformed frame on the E-stop ID (fail-safe: a stop request
  that arrives damaged is still a stop request). Only :meth:`FrameReader.clear_estop` clears it;
- on the CAN FD protocol, SENSOR_SET: a frame carries the payloads of TABLE_SENSORS, BASE_SENSORS,
  STORY_DRIFTS and FLOOR_ACCELS (:data:`SENSOR_SET_PARTS`), and the reader hands each part to that
  message's :class:`Sample` as if the message itself had arrived (values, time, freshness, status),
  so nothing downstream knows which protocol carried them. An intact frame with a value out of
  range poisons the control measurements (table and base mat), whichever block held it;
- the E-stop panel's heartbeat: the panel (``source`` 3) sends ESTOP frames with ``active=0``
  while not pressed; :meth:`FrameReader.panel_age` is the age of its newest frame that passed
  every E2E check. The harness's own ESTOP frames (source 4, supervisor) are never received
  back (no echo, as above), and the rig's (source 1) or the servo's (2) never count as the panel.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence

import can

from drivers.errors import BusError, ProtocolError
from drivers.measurements import Measurements
from drivers.protocol.codec import MessageCodec, Protocol
from drivers.protocol.datagram import HEADER
from drivers.protocol.decoder import STATUS_OF, Decoder, RxStatus
from drivers.protocol.frame_flags import ERROR, EXTENDED, FD, REMOTE, RX, FrameTap, flags_of
from drivers.protocol.frame_kernel import CAPPED, EMPTY, F_FLAGS, F_ID, F_SIZE, F_STATUS, FRAME_COLUMNS, NOT_DECODED
from drivers.protocol.protocol_values import SENSOR_SET_PARTS, DriveState, EstopSource
from drivers.transports.bus import BusHealth
from drivers.transports.datagram_path import DatagramPath, datagram_path

#: What the harness receives (sensors, actuator status, rig status, E-stop).
HARNESS_RX = ("TABLE_SENSORS", "BASE_SENSORS", "ACTUATOR_STATUS", "STORY_DRIFTS", "FLOOR_ACCELS", "RIG_STATUS", "ESTOP")
#: What the harness receives on the CAN FD protocol: the same, and SENSOR_SET, the whole sensor set in one frame.
HARNESS_RX_FD = (*HARNESS_RX, "SENSOR_SET")
#: What the rig (servo controller and virtual rig) receives (:class:`drivers.rig_reader.RigReader`).
RIG_RX = ("ACTUATOR_CMD", "HEARTBEAT", "RIG_CONTROL", "ESTOP", "DRIVE_RESET")
ESTOP_MESSAGE = "ESTOP"
#: ESTOP ``source`` of the operator panel (the DBC's value table, :class:`~drivers.protocol.protocol_values.EstopSource`).
PANEL_SOURCE = EstopSource.PANEL
#: How far in the future a frame's timestamp may lie before it is taken for another clock (s).
FUTURE_TOLERANCE_S = 0.001
#: Messages carrying the controller's measurements (x_0, xdot_0, y_b, ydot_b).
CONTROL_MEASUREMENTS = ("TABLE_SENSORS", "BASE_SENSORS")
#: Drive states in which the drive can apply force when enabled.
_DRIVE_READY_STATES = frozenset({DriveState.READY, DriveState.ENABLED})
#: Outcomes of a frame whose content cannot be read at all (unlike a bad counter or an out-of-range value).
_UNREADABLE = (RxStatus.NOT_DATA, RxStatus.WRONG_LENGTH, RxStatus.BAD_CRC)


def damaged_estop(status: RxStatus) -> bool:
    """True when a frame on the E-stop ID arrived too damaged to read: it counts as a stop request.

    Fail-safe: a stop request that arrives damaged is still a stop request. The harness's
    reader latches :attr:`FrameReader.estop_requested` on it and the rig's reader
    (:class:`drivers.rig_reader.RigReader`) reports it as an E-stop. ``status`` is the
    decoder's outcome for that frame: not a data frame, a wrong length or a bad CRC is damaged;
    ``OK``, a bad counter or an out-of-range value left the frame readable.
    """
    return status in _UNREADABLE


def estop_frame_active(
    status: RxStatus, data: bytes | bytearray | memoryview, accepted: Sequence[float], codec: MessageCodec,
    scratch: list[float], active_index: int,
) -> bool:
    """Whether a frame on the E-stop ID asks for a stop, judged fail-safe (both readers call this).

    ``accepted`` holds the values the decoder took from an ``OK`` frame. A frame too damaged to
    read (:func:`damaged_estop`) asks for a stop. An intact one the decoder refused (a repeated or
    skipped counter, a value out of range) is read again into ``scratch`` through ``codec`` and
    asks what it says: an active stop request out of sequence is still a stop request.
    """
    if status == RxStatus.OK:
        return accepted[active_index] != 0.0
    if damaged_estop(status):
        return True
    codec.unpack(data, scratch)  # CRC and length are fine here
    return scratch[active_index] != 0.0


class Sample:
    """The latest accepted values of one message, with receive time and count.

    Attributes
    ----------
    name : str
        Message name.
    values : list of float
        SI values in DBC signal order (updated in place; hold on to the list).
    rx_time : float
        Receive time of the latest accepted frame (s, the reader's clock), NaN before the first.
    count : int
        Accepted frames.
    fresh : bool
        A frame was accepted during the latest :meth:`FrameReader.poll`.
    last_status : RxStatus
        Outcome of the newest frame on this ID, accepted or not (``OK`` before the first).
    """

    __slots__ = ("name", "values", "rx_time", "count", "fresh", "last_status", "_index")

    def __init__(self, name: str, values: list[float], index: dict[str, int]):
        self.name = name
        self.values = values
        self.rx_time = math.nan
        self.count = 0
        self.fresh = False
        self.last_status = RxStatus.OK
        self._index = index

    def age(self, now: float) -> float:
        """Seconds since the latest accepted frame; infinity when none arrived yet (NaN for an unusable timestamp)."""
        return now - self.rx_time if self.count else math.inf

    def index(self, signal: str) -> int:
        """Position of ``signal`` in :attr:`values` (look it up once, outside the tick)."""
        try:
            return self._index[signal]
        except KeyError as err:
            raise ProtocolError(f"{self.name} has no signal {signal!r}; expected one of: {', '.join(self._index)}") from err

    def __getitem__(self, signal: str) -> float:
        """Value of ``signal`` by name (convenience; use :meth:`index` in the tick)."""
        return self.values[self.index(signal)]


class ReaderCounters:
    """Counts kept by a reader beyond the decoder's per-status counts.

    Attributes
    ----------
    frames : int
        Frames taken off the bus (all kinds).
    polls_capped : int
        Polls that stopped at ``max_frames`` with frames possibly left in the queue.
    foreign_commands : int
        Frames on a foreign ID (the actuator command) not sent by this process.
    estop_frames : int
        Frames on the E-stop ID, valid or not.
    panel_frames : int
        Intact ESTOP frames from the operator panel (source 3), pressed or not.
    last_foreign_time, last_estop_time, last_panel_time : float
        Reader-clock time of the latest of each (s), NaN if none.
    """

    __slots__ = (
        "frames", "polls_capped", "foreign_commands", "estop_frames", "panel_frames", "last_foreign_time",
        "last_estop_time", "last_panel_time",
    )

    def __init__(self) -> None:
        self.frames = 0
        self.polls_capped = 0
        self.foreign_commands = 0
        self.estop_frames = 0
        self.panel_frames = 0
        self.last_foreign_time = math.nan
        self.last_estop_time = math.nan
        self.last_panel_time = math.nan


class FrameReader:
    """Drains a bus each tick and keeps the latest valid sample of each received message.

    Parameters
    ----------
    bus : can.BusABC
        An open bus (see :func:`drivers.transports.bus.open_bus`).
    protocol : Protocol
        The compiled DBC.
    names : sequence of str
        Messages this node receives (:data:`HARNESS_RX` or :data:`RIG_RX`).
    foreign : sequence of str
        IDs that only this node's side may send; frames on them are counted, not decoded.
    health : BusHealth, optional
        Shared with the writer; a new one by default.
    use_msg_timestamp : bool
        Take the receive time from ``msg.timestamp`` instead of ``now``.
    max_frames : int
        Most frames one :meth:`poll` handles.
    poison_on_invalid : sequence of str
        Messages whose values turn NaN when an intact frame carries a value out of the DBC's
        range (the control measurements): the harness must see the invalid value, not keep the last.
    """

    def __init__(
        self,
        bus: can.BusABC,
        protocol: Protocol,
        names: Sequence[str],
        *,
        foreign: Sequence[str] = (),
        health: BusHealth | None = None,
        use_msg_timestamp: bool = False,
        max_frames: int = 256,
        poison_on_invalid: Sequence[str] = (),
    ):
        if max_frames < 1:
            raise ValueError(f"max_frames is {max_frames}; expected at least 1")
        self.bus = bus
        self.protocol = protocol
        self.decoder = Decoder(protocol, names, skip=foreign)
        self._batch = self.decoder.batch(max_frames)
        self.health = health if health is not None else BusHealth()
        self.counters = ReaderCounters()
        self.use_msg_timestamp = use_msg_timestamp
        self.max_frames = max_frames
        self.estop_requested = False
        #: Called with every received frame (valid or not) before it is decoded, e.g. the
        #: run recorder's CAN log (:data:`~drivers.protocol.frame_flags.FrameTap`; it must copy the data it keeps).
        self.tap: FrameTap | None = None
        #: The bus again when it offers the datagram path (:class:`~drivers.transports.datagram_path.DatagramPath`,
        #: e.g. ``seqpacket``): :meth:`poll` then builds no Message.
        self._datagrams = datagram_path(bus)
        self._samples = {
            protocol[n].frame_id: Sample(n, self.decoder.values(n), {s: i for i, s in enumerate(protocol[n].signal_names)})
            for n in names
        }
        self._by_name = {s.name: s for s in self._samples.values()}
        self._sample_list = tuple(self._samples.values())
        self._foreign_ids = frozenset(protocol[n].frame_id for n in foreign)
        self._poison_ids = frozenset(protocol[n].frame_id for n in poison_on_invalid)
        estop = protocol.messages.get(ESTOP_MESSAGE)
        self._estop_id = estop.frame_id if estop is not None and ESTOP_MESSAGE in names else -1
        self._estop_active = estop.index("active") if estop is not None else 0
        self._estop_source = estop.index("source") if estop is not None else 0
        self._estop_scratch = [0.0] * (len(estop.signals) if estop is not None else 0)
        self._set_id, self._set_parts = self._sensor_set_parts(protocol, names)

    def _sensor_set_parts(self, protocol: Protocol, names: Sequence[str]) -> tuple[int, tuple[tuple[Sample, int, bool], ...]]:
        """SENSOR_SET's ID and, per part, the receiving :class:`Sample`, the part's first index, whether it poisons.

        ``(-1, ())`` when this reader does not receive SENSOR_SET.
        """
        if "SENSOR_SET" not in names:
            return -1, ()
        codec = protocol["SENSOR_SET"]
        parts = []
        for name in SENSOR_SET_PARTS:
            part = protocol[name]
            start = codec.index(part.signal_names[0])
            if codec.signal_names[start : start + len(part.signal_names)] != part.signal_names:
                raise ProtocolError(
                    f"SENSOR_SET does not carry the signals of {name} in its order ({', '.join(part.signal_names)})"
                )
            parts.append((self.sample(name), start, part.frame_id in self._poison_ids))
        return codec.frame_id, tuple(parts)

    def _spread(self, status: RxStatus, t: float) -> None:
        """Hand a SENSOR_SET frame's parts to their messages' samples, as if each had arrived at ``t``."""
        values = self._samples[self._set_id].values
        for sample, start, poisons in self._set_parts:
            sample.last_status = status
            if status == RxStatus.OK:
                target = sample.values
                for i in range(len(target)):
                    target[i] = values[start + i]
                sample.rx_time = t
                sample.count += 1
                sample.fresh = True
            elif status == RxStatus.OUT_OF_RANGE and poisons:
                self._poison(sample, t)

    def sample(self, name: str) -> Sample:
        """The :class:`Sample` of message ``name`` (the same object for the whole run)."""
        try:
            return self._by_name[name]
        except KeyError as err:
            raise ProtocolError(f"this reader does not receive {name!r}; it receives: {', '.join(self._by_name)}") from err

    def age(self, name: str, now: float) -> float:
        """Seconds since the latest accepted frame of ``name`` (infinity if none)."""
        return self.sample(name).age(now)

    @property
    def e2e_rejects(self) -> int:
        """Frames rejected by the E2E checks so far: wrong length, bad CRC, repeated or skipped counter."""
        counts = self.decoder.counts
        return (
            counts[RxStatus.WRONG_LENGTH] + counts[RxStatus.BAD_CRC]
            + counts[RxStatus.REPEATED_COUNTER] + counts[RxStatus.SKIPPED_COUNTER]
        )

    def e2e_ok(self) -> bool:
        """True when the newest frame of every received message passed all checks."""
        for sample in self._sample_list:
            if sample.last_status != RxStatus.OK:
                return False
        return True

    @property
    def foreign_command_seen(self) -> bool:
        """True once any frame on a foreign ID arrived from another node."""
        return self.counters.foreign_commands > 0

    def panel_age(self, now: float) -> float:
        """Seconds since the newest intact ESTOP frame from the panel (source 3); infinity before the first.

        NaN when a frame's timestamp was unusable (the staleness checks treat it as invalid).
        """
        counters = self.counters
        return now - counters.last_panel_time if counters.panel_frames else math.inf

    def clear_estop(self) -> None:
        """Deliberately clear the latched E-stop request (the operator's reset)."""
        self.estop_requested = False

    def poll(self, now: float, keep_fresh: bool = False, block_s: float = 0.0) -> int:
        """Handle every frame waiting on the bus (at most ``max_frames``).

        Parameters
        ----------
        now : float
            The loop's current time (s); receive time of the frames unless ``use_msg_timestamp``.
        keep_fresh : bool
            Keep the ``fresh`` flags of an earlier poll of the same tick (several polls per tick,
            as in lockstep); by default every poll starts a new tick.
        block_s : float
            Wait up to this long for the first frame (s); 0 never blocks (the real-time tick).

        Returns
        -------
        int
            Frames handled (all kinds, valid or not).

        Raises
        ------
        BusError
            When the bus itself fails (closed, interface gone).
        """
        if not keep_fresh:
            for sample in self._sample_list:
                sample.fresh = False
        datagrams = self._datagrams
        if datagrams is not None and block_s <= 0.0 and datagrams.raw_receive_ok:
            handled = self._poll_datagrams(datagrams, now)
        else:
            handled = self._poll_messages(now, block_s)
        self.counters.frames += handled
        return handled

    def _poll_messages(self, now: float, block_s: float) -> int:
        """:meth:`poll` through python-can's ``recv``: a :class:`can.Message` per frame (any bus)."""
        handled = 0
        recv = self.bus.recv
        timeout = block_s
        while handled < self.max_frames:
            try:
                msg = recv(timeout=timeout)
            except (can.CanError, OSError, ValueError) as err:  # ValueError: select() on a closed socket
                raise BusError(f"receiving from the CAN bus failed: {err}") from err
            if msg is None:
                break
            timeout = 0.0
            handled += 1
            flags = flags_of(msg)
            data = msg.data if msg.data is not None else b""
            if self.tap is not None:
                self.tap(msg.timestamp, msg.arbitration_id, flags | RX, data, msg.channel)
            t = self._message_time(msg.timestamp, now) if self.use_msg_timestamp else now
            self._handle(msg.arbitration_id, flags, data, t)
        else:
            self.counters.polls_capped += 1
        return handled

    def _poll_datagrams(self, bus: DatagramPath, now: float) -> int:
        """:meth:`poll` straight from the datagrams of a bus that offers the datagram path, with no :class:`can.Message`.

        The tick's path on a ``seqpacket`` bus (:class:`~drivers.transports.datagram_path.DatagramPath`).
        The same frames in the same order as :meth:`_poll_messages` (the bus has no filters and no
        local echo, :attr:`~drivers.transports.datagram_path.DatagramPath.raw_receive_ok`). With one peer they
        are taken off its socket and checked and decoded in one compiled call
        (:meth:`~drivers.protocol.decoder.Decoder.receive_datagrams`); a hub relaying between peers takes
        them through the bus (:meth:`_receive_each`). Then each is accounted, in order, as
        :meth:`_handle` accounts a frame, stamped with the wall clock once for the poll (the frames
        of one poll arrived within its microseconds).
        """
        batch = self._batch
        fd = bus.direct_fd
        if fd < 0:
            frames = self._receive_each(bus, 0)
        else:
            frames, end, malformed = self.decoder.receive_datagrams(fd, batch, self.max_frames)
            bus.note_direct_receive(malformed)
            if end == CAPPED:
                self.counters.polls_capped += 1
            elif end != EMPTY:  # end of file or a failed recv: the bus's own path judges it (drops the peer, raises)
                frames = self._receive_each(bus, frames)
        if not frames:
            return 0
        stamp = time.time()
        t = self._message_time(stamp, now) if self.use_msg_timestamp else now
        tap, channel, rows, ints = self.tap, bus.channel, batch.rows, batch.flat_ints
        for k in range(frames):
            at = k * FRAME_COLUMNS
            frame_id, flags, status = ints[at + F_ID], ints[at + F_FLAGS], ints[at + F_STATUS]
            data = rows[k][HEADER.size : ints[at + F_SIZE]]
            if tap is not None:
                tap(stamp, frame_id, flags | RX, data, channel)
            if status == NOT_DECODED:
                self._handle_undecoded(frame_id, flags, data, t)
                continue
            if status == RxStatus.OK:
                self.decoder.take(batch, k)
            self._account(frame_id, flags & EXTENDED, STATUS_OF[status], data, t)
        return frames

    def _receive_each(self, bus: DatagramPath, start: int) -> int:
        """Fill ``self._batch`` from row ``start`` on through the bus's
        :meth:`~drivers.transports.datagram_path.DatagramPath.recv_datagram` (a hub relaying between peers,
        or after the compiled receive ended unusually), then decode those rows."""
        batch = self._batch
        rows, ints = batch.rows, batch.frame_ints
        recv = bus.recv_datagram
        frames = start
        while frames < self.max_frames:
            try:
                size = recv(rows[frames])
            except (can.CanError, OSError, ValueError) as err:
                raise BusError(f"receiving from the CAN bus failed: {err}") from err
            if not size:
                break
            ints[frames, F_SIZE] = size
            frames += 1
        else:
            self.counters.polls_capped += 1
        self.decoder.decode_datagrams(batch, start, frames)
        return frames

    @staticmethod
    def _message_time(timestamp: float, now: float) -> float:
        """A frame's own timestamp (wall-clock epoch s) moved onto the loop's clock (``now``).

        The frame is as old as the wall clock says (``time.time() - timestamp``, at least 0),
        counted back from ``now``. A timestamp more than :data:`FUTURE_TOLERANCE_S` in the
        future is not on this host's wall clock: the time is NaN, which the staleness checks
        treat as invalid (they trip).
        """
        delay = time.time() - timestamp
        if not delay >= -FUTURE_TOLERANCE_S:
            return math.nan
        return now - max(delay, 0.0)

    def _handle(self, frame_id: int, flags: int, data: bytes | bytearray | memoryview, t: float) -> None:
        """Check, decode and account one received frame (``flags`` of :mod:`drivers.protocol.frame_flags`) seen at ``t``."""
        if flags & ERROR or (frame_id in self._foreign_ids and not flags & EXTENDED):
            self._handle_undecoded(frame_id, flags, data, t)
            return
        extended = flags & EXTENDED
        status = self.decoder.decode(
            frame_id, data, is_data_frame=not flags & REMOTE, extended=bool(extended), fd=bool(flags & FD)
        )
        self._account(frame_id, extended, status, data, t)

    def _handle_undecoded(self, frame_id: int, flags: int, data: bytes | bytearray | memoryview, t: float) -> None:
        """An error frame, or a frame on a foreign identifier: accounted, never decoded."""
        if flags & ERROR:
            self.health.note_error_frame(frame_id, data, t)
            return
        # Every frame on a foreign ID is someone else's: the bus does not echo our own frames
        # (receive_own_messages=False). msg.is_rx cannot tell: socketcan marks frames
        # from any process on this host is_rx=False (MSG_DONTROUTE), not only ours.
        self.counters.foreign_commands += 1
        self.counters.last_foreign_time = t

    def _account(self, frame_id: int, extended: int, status: RxStatus, data: bytes | bytearray | memoryview, t: float) -> None:
        """What a decoded frame means for its sample (fresh, poisoned), SENSOR_SET's parts and the E-stop."""
        sample = None if extended else self._samples.get(frame_id)
        if sample is not None:
            sample.last_status = status
            if status == RxStatus.OK:
                sample.rx_time = t
                sample.count += 1
                sample.fresh = True
            elif status == RxStatus.OUT_OF_RANGE and frame_id in self._poison_ids:
                self._poison(sample, t)
        if frame_id == self._set_id and not extended:
            self._spread(status, t)
        elif frame_id == self._estop_id and not extended:
            self._note_estop(status, data, t)

    @staticmethod
    def _poison(sample: Sample, t: float) -> None:
        """A frame that arrived intact (CRC, counter) with a value out of the DBC's range (or NaN).

        Its values become NaN, fresh at ``t``: the measurement checks see an invalid value in the
        same tick (``sensor_invalid``), rather than the previous values growing stale.
        """
        values = sample.values
        for i in range(len(values)):
            values[i] = math.nan
        sample.rx_time = t
        sample.fresh = True

    def _note_estop(self, status: RxStatus, data: bytes | bytearray | memoryview, t: float) -> None:
        self.counters.estop_frames += 1
        self.counters.last_estop_time = t
        values = self._samples[self._estop_id].values
        if status == RxStatus.OK and values[self._estop_source] == PANEL_SOURCE:
            self.counters.panel_frames += 1
            self.counters.last_panel_time = t
        codec = self.protocol.by_id[self._estop_id]
        if estop_frame_active(status, data, values, codec, self._estop_scratch, self._estop_active):
            self.estop_requested = True


class HarnessReader(FrameReader):
    """The harness side: sensors, actuator status, rig status, E-stop; foreign actuator commands.

    On the CAN FD protocol it receives SENSOR_SET too, into the four sensor messages' samples.

    Parameters
    ----------
    bus : can.BusABC
    protocol : Protocol
    health : BusHealth, optional
        Shared with the writer; a new one by default.
    use_msg_timestamp : bool
        Take the receive time from ``msg.timestamp`` (moved onto the loop's clock) instead of ``now``.
    max_frames : int
        Most frames one :meth:`poll` handles.
    """

    def __init__(
        self, bus: can.BusABC, protocol: Protocol, health: BusHealth | None = None, *,
        use_msg_timestamp: bool = False, max_frames: int = 256,
    ):
        super().__init__(
            bus, protocol, HARNESS_RX_FD if protocol.fd else HARNESS_RX, foreign=("ACTUATOR_CMD",), health=health,
            use_msg_timestamp=use_msg_timestamp, max_frames=max_frames, poison_on_invalid=CONTROL_MEASUREMENTS,
        )
        self.table = self.sample("TABLE_SENSORS")
        self.base = self.sample("BASE_SENSORS")
        self.status = self.sample("ACTUATOR_STATUS")
        self._x0, self._xd0 = self.table.index("x_0"), self.table.index("xdot_0")
        self._yb, self._ydb = self.base.index("y_b"), self.base.index("ydot_b")
        status = self.status
        self._drive, self._pressure = status.index("drive_state"), status.index("pressure_ok")
        self._fault, self._force = status.index("fault_code"), status.index("force_measured")

    @property
    def drive_state(self) -> int:
        """Latest ACTUATOR_STATUS drive state, a :class:`~drivers.protocol.protocol_values.DriveState` value.

        ``OFF`` before any frame.
        """
        return int(self.status.values[self._drive])

    @property
    def drive_ready(self) -> bool:
        """The drive is ``READY`` or ``ENABLED`` (latest ACTUATOR_STATUS)."""
        return self.status.values[self._drive] in _DRIVE_READY_STATES

    @property
    def drive_fault(self) -> bool:
        """The drive is in ``FAULT`` (latest ACTUATOR_STATUS)."""
        return self.status.values[self._drive] == DriveState.FAULT

    @property
    def pressure_ok(self) -> bool:
        """Latest hydraulic-pressure-ok flag (False before any frame)."""
        return bool(self.status.values[self._pressure])

    @property
    def fault_code(self) -> int:
        """Latest servo fault code, a :class:`~drivers.protocol.protocol_values.FaultCode` value or any injected code (0 none)."""
        return int(self.status.values[self._fault])

    @property
    def measured_force_n(self) -> float:
        """Latest load-cell force reported by the servo controller (N)."""
        return self.status.values[self._force]

    def fill(self, measurements: Measurements) -> None:
        """Copy the latest x_0, xdot_0, y_b, ydot_b into ``measurements`` in place (SI)."""
        table, base = self.table.values, self.base.values
        measurements.set(table[self._x0], table[self._xd0], base[self._yb], base[self._ydb])

    def sensor_age(self, now: float) -> float:
        """Age of the older of the table and base-mat samples (s; infinity before both arrived)."""
        return max(self.table.age(now), self.base.age(now))
