"""Sending the rig's frames, with the frame- and value-level faults applied.

Every frame the rig sends goes through :meth:`RigPublisher.send`, which honours bus
silence, dropout, corrupted CRC and repeated/skipped rolling counters
(:mod:`harness.rig.faults`). Sensor messages go through :meth:`RigPublisher.sensor`
first, which applies stuck values, sign flips, spikes and noise bursts and saturates every
value at its DBC range (a real transducer saturates; the codec would refuse it).
Frames are the writer's preallocated :class:`~drivers.writer.TxFrame` objects.

On the CAN FD protocol the four sensor messages travel together in one SENSOR_SET frame
(:meth:`RigPublisher.sensor_set`): each message's values are measured and faulted as before
(stuck, sign flip, spike, noise burst, per target), and a frame-level fault (dropout, corrupted
CRC, repeated or skipped counter) of any of the four acts on the one frame that carries them all.
"""

from __future__ import annotations

import can

from drivers.protocol.e2e import COUNTER_MODULO
from drivers.protocol.protocol_values import SENSOR_SET_PARTS, EstopSource
from drivers.writer import RigWriter, TxFrame
from harness.rig.faults import (
    BUS_SILENCE,
    CORRUPT_CRC,
    DROPOUT,
    NOISE_BURST,
    REPEAT_COUNTER,
    SKIP_COUNTER,
    STUCK,
    TARGETS,
    FaultSet,
)
from harness.rig.sensors import MESSAGE_COLUMNS, SensorModel

#: The targets of the messages SENSOR_SET carries together, in its order.
_SENSOR_SET_TARGETS = tuple(TARGETS.index(name) for name in SENSOR_SET_PARTS)
#: Each message's target on its own, for the frame-level faults of a message sent alone.
_ALONE = tuple((target,) for target in range(len(TARGETS)))


class RigPublisher:
    """Encodes and sends the rig's messages through ``writer``'s frames.

    Parameters
    ----------
    writer : RigWriter
    faults : FaultSet
    sensors : SensorModel
    """

    def __init__(self, writer: RigWriter, faults: FaultSet, sensors: SensorModel):
        self.writer = writer
        self.faults = faults
        self.sensors = sensors
        self.frames: tuple[TxFrame, ...] = tuple(writer.frame(name) for name in TARGETS)
        self._estop = writer.frame("ESTOP")
        self._ranges = tuple(tuple((s.minimum, s.maximum) for s in tx.codec.signals) for tx in self.frames)
        self._values = tuple([0.0] * len(tx.codec.signals) for tx in self.frames)
        self._estop_values = [1.0, float(EstopSource.RIG), 0.0]  # active, source, reason
        self._panel_values = [0.0, float(EstopSource.PANEL), 0.0]
        self.panel_sent = 0
        self.sent = [0] * len(TARGETS)
        self.suppressed = 0
        #: The CAN FD protocol: the sensor messages go out together as SENSOR_SET.
        self.fd = writer.fd
        self._set = writer.frame("SENSOR_SET") if self.fd else None
        self._set_values = [0.0] * (3 * len(_SENSOR_SET_TARGETS))

    def _clip(self, target: int) -> None:
        values = self._values[target]
        for i, (lo, hi) in enumerate(self._ranges[target]):
            value = values[i]
            values[i] = lo if value < lo else hi if value > hi else value

    def sensor_messages(self, now: float, table_and_base: bool, stories: bool) -> None:
        """Send the sensor messages that are due: on classic CAN the table and base-mat messages
        (targets 0, 1) and the story messages (2, 3) each when due; on the CAN FD protocol the whole
        set as one SENSOR_SET frame, at the table and base-mat rate (:meth:`sensor_set`)."""
        if self.fd:
            if table_and_base:
                self.sensor_set(now)
            return
        if table_and_base:
            self.sensor(0, now)
            self.sensor(1, now)
        if stories:
            self.sensor(2, now)
            self.sensor(3, now)

    def sensor(self, target: int, now: float) -> bool:
        """Measure and send sensor message ``target`` (0..3); False if nothing went out."""
        return self.send(target, self._measure(target), now)

    def _measure(self, target: int) -> list[float]:
        """The values sensor message ``target`` (0..3) carries now, with its value-level faults applied."""
        faults = self.faults
        values = self._values[target]
        if faults.is_on(STUCK, target):
            return values  # the values last sent, again
        burst = faults.param[NOISE_BURST, target] if faults.is_on(NOISE_BURST, target) else 0.0
        self.sensors.read(MESSAGE_COLUMNS[target], values, abs(burst))
        flipped = faults.flipped_signal(target)
        if flipped >= 0:
            values[flipped] = -values[flipped]
        if faults.reversed_polarity(target):
            for signal in range(len(values)):
                values[signal] = -values[signal]
        values[0] += faults.take_spike(target)
        self._clip(target)
        return values

    def sensor_set(self, now: float) -> bool:
        """CAN FD protocol: measure the four sensor messages and send them as one SENSOR_SET frame.

        Each target's values are measured as :meth:`sensor` measures them; the frame-level faults of
        targets 0..3 act on the one frame. False if nothing went out.
        """
        tx = self._set
        if tx is None:
            raise ValueError("SENSOR_SET is a message of the CAN FD protocol; this rig's bus is classic (can.fd is false)")
        values = self._set_values
        for part, target in enumerate(_SENSOR_SET_TARGETS):
            measured = self._measure(target)
            base = 3 * part
            values[base], values[base + 1], values[base + 2] = measured[0], measured[1], measured[2]
        ok = self._send_faulted(tx, _SENSOR_SET_TARGETS, values, now)
        if ok:
            for target in _SENSOR_SET_TARGETS:
                self.sent[target] += 1
        return ok

    def status(self, force_N: float, drive_state: int, pressure_ok: bool, fault_code: int, now: float) -> bool:
        """Send ACTUATOR_STATUS (target 4)."""
        values = self._values[4]
        values[0], values[1], values[2], values[3] = drive_state, (1.0 if pressure_ok else 0.0), fault_code, force_N
        self._clip(4)
        return self.send(4, values, now)

    def rig_status(
        self, running: bool, lockstep: bool, fault_active: bool, record_time_s: float, step: int, now: float,
        start_refused: bool = False,
    ) -> bool:
        """Send RIG_STATUS (target 5); ``step`` is sent modulo 2**24; ``start_refused``: the last start table was refused."""
        values = self._values[5]
        values[0], values[1], values[2] = (1.0 if running else 0.0), (1.0 if lockstep else 0.0), (1.0 if fault_active else 0.0)
        # in the DBC's bit order: start_refused (bit 15) before record_time and step_index
        values[3], values[4], values[5] = (1.0 if start_refused else 0.0), record_time_s, step % (1 << 24)
        self._clip(5)
        return self.send(5, values, now)

    def estop(self, now: float) -> bool:
        """Send an active ESTOP from the rig (source ``RIG``)."""
        if self.faults.is_on(BUS_SILENCE):
            self.suppressed += 1
            return False
        return self.writer.send_frame(self._estop, self._estop_values, now)

    def panel(self, now: float, pressed: bool = False) -> bool:
        """Send the E-stop panel's frame (source ``PANEL``): its heartbeat with ``active=0``, or a press.

        The panel is a node of its own on a real rig; the virtual rig emulates it on its own
        ESTOP frame (one rolling counter for the rig's and the panel's frames on this ID).
        """
        if self.faults.is_on(BUS_SILENCE):
            self.suppressed += 1
            return False
        self._panel_values[0] = 1.0 if pressed else 0.0
        ok = self.writer.send_frame(self._estop, self._panel_values, now)
        if ok:
            self.panel_sent += 1
        return ok

    def send(self, target: int, values: list[float], now: float) -> bool:
        """Send message ``target`` with ``values``, applying the frame-level faults."""
        ok = self._send_faulted(self.frames[target], _ALONE[target], values, now)
        if ok:
            self.sent[target] += 1
        return ok

    def _on(self, kind: int, targets: tuple[int, ...]) -> bool:
        """Fault ``kind`` is on for one of ``targets`` (a loop, not ``any()``: no generator per frame)."""
        is_on = self.faults.is_on
        for target in targets:
            if is_on(kind, target):
                return True
        return False

    def _send_faulted(self, tx: TxFrame, targets: tuple[int, ...], values: list[float], now: float) -> bool:
        """Send ``tx`` with ``values``, applying the frame-level faults of ``targets`` (the messages it carries)."""
        faults = self.faults
        if faults.is_on(BUS_SILENCE) or self._on(DROPOUT, targets):
            self.suppressed += 1
            return False
        if self._on(REPEAT_COUNTER, targets) and tx.sent:
            tx.counter = (tx.counter - 1) % COUNTER_MODULO
        elif self._on(SKIP_COUNTER, targets):
            tx.counter = (tx.counter + 1) % COUNTER_MODULO
        if self._on(CORRUPT_CRC, targets):
            return self._send_corrupted(tx, values, now)
        return self.writer.send_frame(tx, values, now)

    def _send_corrupted(self, tx: TxFrame, values: list[float], now: float) -> bool:
        msg = tx.msg
        tx.codec.encode_into(msg.data, values, tx.counter)
        msg.data[0] ^= 0xA5
        msg.timestamp = now
        try:
            self.writer.bus.send(msg, timeout=0)
        except (can.CanError, OSError, ValueError) as err:
            self.writer.health.note_send_failure(err, now)
            return False
        tx.counter = (tx.counter + 1) % COUNTER_MODULO
        tx.sent += 1
        return True
