"""The rig's receive side: one frame at a time, so every command frame is one event.

The harness's :class:`~drivers.reader.FrameReader` keeps only the latest sample of each
message, which is right for a control loop but loses events for the rig: in lockstep every
ACTUATOR_CMD frame is a step, and two RIG_CONTROL frames in one poll are two commands.
:class:`RigReader` therefore takes frames off the bus one by one (blocking up to a timeout
when asked, so the lockstep thread does not spin) and checks and decodes each with the
:class:`~drivers.protocol.decoder.Decoder` (same E2E checks and counts). A frame on the E-stop ID
asks for a stop by the same fail-safe rule as the harness's reader
(:func:`drivers.reader.estop_frame_active`): too damaged to read, or intact and active even
with a repeated or skipped counter.

The rig outlives the harness: it serves run after run, each from a new harness process
whose rolling counters start again at 0. A message silent for longer than
:data:`NEW_SENDER_SILENCE_S` is therefore taken to come from a new sender: its counter
history is forgotten before its next frame is checked (the E2E receiver's re-initialisation
after a timeout), so the first RIG_CONTROL or DRIVE_RESET of a run is never lost as a
"repeated" or "skipped" counter. Within a run the harness's periodic messages are never
that silent, and the CRC, length and range checks always apply.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import can

from drivers.errors import BusError
from drivers.protocol.codec import Protocol
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.reader import RIG_RX, estop_frame_active

#: A message silent this long (s) comes from a new sender: its counter history is forgotten.
NEW_SENDER_SILENCE_S = 0.5

NOTHING, COMMAND, HEARTBEAT, CONTROL, ESTOP, REJECTED, OTHER, DRIVE_RESET = 0, 1, 2, 3, 4, 5, 6, 7


class RigReader:
    """Receives and decodes the harness's frames for the rig (virtual rig, servo controller).

    Parameters
    ----------
    bus : can.BusABC
    protocol : Protocol
    clock : callable
        Monotonic clock (s) that times the silences (:data:`NEW_SENDER_SILENCE_S`).

    Attributes
    ----------
    command, heartbeat, control, estop, drive_reset : list of float
        Latest accepted values (DBC order, SI), updated in place.
    frames : int
        Frames taken off the bus.
    """

    def __init__(self, bus: can.BusABC, protocol: Protocol, clock: Callable[[], float] = time.monotonic):
        self.bus = bus
        self.clock = clock
        self.decoder = Decoder(protocol, RIG_RX)
        self.command = self.decoder.values("ACTUATOR_CMD")
        self.heartbeat = self.decoder.values("HEARTBEAT")
        self.control = self.decoder.values("RIG_CONTROL")
        self.estop = self.decoder.values("ESTOP")
        self.drive_reset = self.decoder.values("DRIVE_RESET")
        self._kinds = {
            protocol["ACTUATOR_CMD"].frame_id: COMMAND,
            protocol["HEARTBEAT"].frame_id: HEARTBEAT,
            protocol["RIG_CONTROL"].frame_id: CONTROL,
            protocol["ESTOP"].frame_id: ESTOP,
            protocol["DRIVE_RESET"].frame_id: DRIVE_RESET,
        }
        self._estop_id = protocol["ESTOP"].frame_id
        self._estop_active = protocol["ESTOP"].index("active")
        self._estop_codec = protocol["ESTOP"]
        self._estop_scratch = [0.0] * len(self._estop_codec.signal_names)
        self.frames = 0
        self._last_heard = dict.fromkeys(self._kinds, -float("inf"))

    def receive(self, timeout_s: float = 0.0) -> int:
        """Take one frame (waiting up to ``timeout_s``) and return what it was.

        Returns
        -------
        int
            NOTHING (no frame), COMMAND, HEARTBEAT, CONTROL, DRIVE_RESET (values updated), ESTOP
            (an active stop, even out of sequence, or a damaged frame on the E-stop ID), REJECTED
            (failed a check, counted by the decoder) or OTHER (an inactive E-stop,
            an error frame, a foreign ID).

        Raises
        ------
        BusError
            The bus failed (closed, interface gone).
        """
        try:
            msg = self.bus.recv(timeout=timeout_s)
        except (can.CanError, OSError, ValueError) as err:
            raise BusError(f"the virtual rig could not receive from the CAN bus: {err}") from err
        if msg is None:
            return NOTHING
        self.frames += 1
        if msg.is_error_frame:
            return OTHER
        frame_id = msg.arbitration_id
        if frame_id in self._last_heard and not msg.is_extended_id:
            now = self.clock()
            if now - self._last_heard[frame_id] > NEW_SENDER_SILENCE_S:
                self.decoder.reset_counter(frame_id)
            self._last_heard[frame_id] = now
        status = self.decoder.decode(
            msg.arbitration_id, msg.data, is_data_frame=not msg.is_remote_frame, extended=msg.is_extended_id,
            fd=msg.is_fd,
        )
        kind = OTHER if msg.is_extended_id else self._kinds.get(msg.arbitration_id, OTHER)
        if kind == ESTOP:
            if estop_frame_active(status, msg.data, self.estop, self._estop_codec, self._estop_scratch, self._estop_active):
                return ESTOP  # fail-safe: an active stop out of sequence, or a frame too damaged to read
            return OTHER if status == RxStatus.OK else REJECTED
        if status != RxStatus.OK:
            return REJECTED if kind != OTHER else OTHER
        return kind
