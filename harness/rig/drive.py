"""Drive enable logic and the drive-side watchdog of the servo controller.

States and fault codes are the DBC's value tables of ACTUATOR_STATUS ``drive_state``
(:class:`~drivers.protocol_values.DriveState`: OFF, READY, ENABLED, FAULT, ESTOP) and
``fault_code`` (:class:`~drivers.protocol_values.FaultCode`).

- OFF -> READY when heartbeats arrive (the latest younger than the watchdog
  timeout) and the hydraulic pressure is ok.
- READY -> ENABLED on a command frame with ``enable = 1``; ENABLED -> READY on one
  with ``enable = 0``.
- READY or ENABLED -> FAULT (latched) when the heartbeat stops (HEARTBEAT_WATCHDOG), when
  ENABLED and the commands stop (COMMAND_WATCHDOG) for longer than the timeout, when the
  pressure is lost (PRESSURE_LOST), or on an injected drive fault (code from the fault,
  default INJECTED).
- any -> ESTOP (latched, code ESTOP) on an E-stop.
- FAULT and ESTOP clear only on :meth:`Drive.reset` (RIG_CONTROL reset), back to OFF.

Ages are measured on the wall clock the caller passes in (``now``), in lockstep too;
there the virtual rig sets a longer timeout (``rig.drive.lockstep_watchdog_timeout_s``),
because the harness paces the steps and a slow host is not a dead harness.
"""

from __future__ import annotations

import math

from drivers.protocol_values import DriveState, FaultCode

_LATCHED = (DriveState.FAULT, DriveState.ESTOP)


class Drive:
    """The servo controller's enable state machine.

    Parameters
    ----------
    watchdog_timeout_s : float
        Largest age of the latest command (when enabled) and heartbeat (s).
    """

    def __init__(self, watchdog_timeout_s: float):
        self.timeout_s = float(watchdog_timeout_s)
        self.reset()

    def reset(self) -> None:
        """Back to OFF with no fault; forget command and heartbeat times."""
        self.state = DriveState.OFF
        self.fault_code: int = FaultCode.NONE
        self.enable_requested = False
        self.command_N = 0.0
        self.last_command_time = -math.inf
        self.last_heartbeat_time = -math.inf

    @property
    def enabled(self) -> bool:
        """True when the drive applies force."""
        return self.state == DriveState.ENABLED

    def _trip(self, state: DriveState, code: int) -> None:
        self.state = state
        self.fault_code = code
        self.enable_requested = False

    def on_heartbeat(self, now: float) -> None:
        """A heartbeat frame arrived at ``now`` (s, wall clock)."""
        self.last_heartbeat_time = now

    def on_command(self, enable: bool, force_N: float, now: float) -> None:
        """A command frame arrived at ``now``: record it and apply the enable bit."""
        self.last_command_time = now
        self.enable_requested = bool(enable)
        self.command_N = float(force_N)
        if self.state == DriveState.READY and enable:
            self.state = DriveState.ENABLED
        elif self.state == DriveState.ENABLED and not enable:
            self.state = DriveState.READY

    def on_estop(self) -> None:
        """An E-stop (frame or rig fault): latch ESTOP."""
        if self.state != DriveState.ESTOP:
            self._trip(DriveState.ESTOP, FaultCode.ESTOP)

    def update(self, now: float, pressure_ok: bool, injected_code: int = 0) -> DriveState:
        """Run the watchdog and transitions at ``now`` (s); return the state.

        Parameters
        ----------
        now : float
            Wall-clock time (s), same clock as the frame times.
        pressure_ok : bool
            Hydraulic pressure present.
        injected_code : int
            Non-zero: an injected drive fault with this code.
        """
        if self.state in _LATCHED:
            return self.state
        heartbeat_ok = now - self.last_heartbeat_time <= self.timeout_s
        if self.state == DriveState.OFF:
            if heartbeat_ok and pressure_ok and not injected_code:
                self.state = DriveState.READY
            else:
                return self.state
        if injected_code:
            self._trip(DriveState.FAULT, injected_code)
        elif not pressure_ok:
            self._trip(DriveState.FAULT, FaultCode.PRESSURE_LOST)
        elif not heartbeat_ok:
            self._trip(DriveState.FAULT, FaultCode.HEARTBEAT_WATCHDOG)
        elif self.state == DriveState.ENABLED and now - self.last_command_time > self.timeout_s:
            self._trip(DriveState.FAULT, FaultCode.COMMAND_WATCHDOG)
        return self.state
