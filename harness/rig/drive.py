"""Drive enable logic and the drive-side watchdog of the servo controller.

States and fault codes are the DBC's value tables of ACTUATOR_STATUS ``drive_state``
(:class:`~drivers.protocol.protocol_values.DriveState`: OFF, READY, ENABLED, FAULT, ESTOP) and
``fault_code`` (:class:`~drivers.protocol.protocol_values.FaultCode`).

- OFF -> READY when heartbeats arrive (the latest younger than the watchdog
  timeout) and the hydraulic pressure is ok.
- READY -> ENABLED on a command frame with ``enable = 1``; ENABLED -> READY on one
  with ``enable = 0``.
- READY or ENABLED -> FAULT (latched) when the heartbeat stops (HEARTBEAT_WATCHDOG), when
  ENABLED and the commands stop (COMMAND_WATCHDOG) for longer than the timeout, when the
  pressure is lost (PRESSURE_LOST), or on an injected drive fault (code from the fault,
  default INJECTED).
- any -> ESTOP (latched, code ESTOP) on an E-stop.
- FAULT and ESTOP clear on the operator's reset (:meth:`Drive.request_reset`, a DRIVE_RESET
  frame), back to OFF, when the latched code is reset-able
  (:data:`~drivers.protocol.protocol_values.RESETTABLE_FAULTS`), its cause is gone and the frame names
  it; otherwise the reset is refused, the drive stays latched and its fault code names the
  condition still present. :meth:`Drive.reset` (RIG_CONTROL reset: the virtual rig's power
  cycle) clears any latch.
- A reset arms nothing: after it the drive needs fresh heartbeats to be READY again, and a
  command frame with ``enable = 0`` before one with ``enable = 1`` enables it (a stale enable
  never re-enables a drive that was reset). A reset is ignored while the drive is not latched,
  and refused while the harness's heartbeat says ARMED, RUNNING or STOPPING.

Ages are measured on the wall clock the caller passes in (``now``), in lockstep too;
there the virtual rig sets a longer timeout (``rig.drive.lockstep_watchdog_timeout_s``),
because the harness paces the steps and a slow host is not a dead harness.
"""

from __future__ import annotations

import math
from enum import Enum

from drivers.protocol.protocol_values import RESETTABLE_FAULTS, DriveState, FaultCode, fault_name
from harness.safety.lifecycle import State

_LATCHED = (DriveState.FAULT, DriveState.ESTOP)
#: HEARTBEAT states of a harness that may be driving the actuator: a reset is refused then.
_HARNESS_ACTIVE = (State.ARMED, State.RUNNING, State.STOPPING)


class ResetVerdict(Enum):
    """What the drive made of a reset request (:meth:`Drive.request_reset`)."""

    CLEARED = "cleared"
    NOT_LATCHED = "ignored: no latched fault"
    HARNESS_ACTIVE = "refused: the harness's heartbeat says it is armed, running or stopping"
    CAUSE_PRESENT = "refused: the fault's cause is still present"
    NOT_RESETTABLE = "refused: not a reset-able fault"
    WRONG_CODE = "refused: the reset names another fault code"

    def describe(self, acknowledged_code: int, latched_code: int) -> str:
        """One line for the rig's terminal: the verdict, the fault the reset named and the one latched now."""
        return f"drive reset of {fault_name(acknowledged_code)} {self.value} (fault now {fault_name(latched_code)})"


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
        """Back to OFF with no fault; forget command and heartbeat times (the virtual rig's power cycle)."""
        self.state = DriveState.OFF
        self.fault_code: int = FaultCode.NONE
        self.enable_requested = False
        self.command_N = 0.0
        self.last_command_time = -math.inf
        self.last_heartbeat_time = -math.inf
        self.harness_state = int(State.IDLE)
        #: After an operator reset: a command with enable=0 must come before one with enable=1 enables.
        self.awaiting_enable_low = False

    @property
    def enabled(self) -> bool:
        """True when the drive applies force."""
        return self.state == DriveState.ENABLED

    def _trip(self, state: DriveState, code: int) -> None:
        self.state = state
        self.fault_code = code
        self.enable_requested = False

    def on_heartbeat(self, now: float, harness_state: int = State.IDLE) -> None:
        """A heartbeat frame arrived at ``now`` (s, wall clock) with the harness's lifecycle ``harness_state``."""
        self.last_heartbeat_time = now
        self.harness_state = int(harness_state)

    def on_command(self, enable: bool, force_N: float, now: float) -> None:
        """A command frame arrived at ``now``: record it and apply the enable bit."""
        self.last_command_time = now
        self.enable_requested = bool(enable)
        self.command_N = float(force_N)
        if not enable:
            self.awaiting_enable_low = False
        if self.state == DriveState.READY and enable and not self.awaiting_enable_low:
            self.state = DriveState.ENABLED
        elif self.state == DriveState.ENABLED and not enable:
            self.state = DriveState.READY

    def on_estop(self) -> None:
        """An E-stop (frame or rig fault): latch ESTOP."""
        if self.state != DriveState.ESTOP:
            self._trip(DriveState.ESTOP, FaultCode.ESTOP)

    def request_reset(
        self, acknowledged_code: int, now: float, *, pressure_ok: bool, injected_code: int = 0, estop_asserted: bool = False,
    ) -> ResetVerdict:
        """The operator's reset (a DRIVE_RESET frame naming ``acknowledged_code``) at ``now`` (s); see the module.

        Parameters
        ----------
        acknowledged_code : int
            The fault code the reset names (the code the operator saw).
        now : float
            Wall-clock time (s), same clock as the frame times.
        pressure_ok : bool
            Hydraulic pressure present.
        injected_code : int
            Non-zero: an injected drive fault with this code is present.
        estop_asserted : bool
            An E-stop is asserted now (a rig E-stop, the panel pressed, a recent active ESTOP frame).

        Returns
        -------
        ResetVerdict
            CLEARED (back to OFF, nothing armed or enabled) or why not.
        """
        if self.state not in _LATCHED:
            return ResetVerdict.NOT_LATCHED
        if now - self.last_heartbeat_time <= self.timeout_s and self.harness_state in _HARNESS_ACTIVE:
            return ResetVerdict.HARNESS_ACTIVE
        if estop_asserted:
            self._trip(DriveState.ESTOP, FaultCode.ESTOP)
            return ResetVerdict.CAUSE_PRESENT
        if injected_code:
            self._trip(DriveState.FAULT, injected_code)
            return ResetVerdict.CAUSE_PRESENT
        if not pressure_ok:
            self._trip(DriveState.FAULT, FaultCode.PRESSURE_LOST)
            return ResetVerdict.CAUSE_PRESENT
        if self.fault_code not in RESETTABLE_FAULTS:
            return ResetVerdict.NOT_RESETTABLE
        if int(acknowledged_code) != self.fault_code:
            return ResetVerdict.WRONG_CODE
        self.state = DriveState.OFF
        self.fault_code = FaultCode.NONE
        self.enable_requested = False
        self.command_N = 0.0
        self.last_command_time = -math.inf
        self.last_heartbeat_time = -math.inf  # READY again only on fresh heartbeats
        self.awaiting_enable_low = True
        return ResetVerdict.CLEARED

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
