"""``--reset-drive``: the operator's reset of the servo drive's latched fault, sent once before arming.

A servo drive latches a fault when its watchdog sees the harness stop talking, which happens
at the end of every run (the harness disconnects) and when a harness dies. Like a real drive,
the virtual rig's stays latched until the operator resets it. ``harness run --reset-drive``
and ``harness dry-run --external-rig --reset-drive`` do that through :func:`reset_drive`,
after the bus is open and before anything is armed:

1. wait for the drive's ACTUATOR_STATUS (and a panel period, to hear a pressed E-stop);
2. no latched fault: nothing is sent;
3. refuse (:class:`DriveResetRefused`, exit status 2, nothing sent) when the latched fault is
   not one a reset may clear (:data:`~drivers.protocol.protocol_values.RESETTABLE_FAULTS`), an E-stop
   is asserted, or the pressure is still lost;
4. send a DRIVE_RESET naming the latched code and wait for the drive to leave its latch (up to
   :data:`ATTEMPTS` frames, in case the first is rejected for its rolling counter); a drive that
   stays latched refused it, and its fault code says why (refused, exit 2).

The reset arms nothing: the drive goes to OFF, is READY again only on the loop's heartbeats,
and enables only through the supervisor's arming (and a command with enable=0 first). It is
never sent from the tick, so never while the harness is armed or running; the drive also
refuses one while the harness's heartbeat says so (:mod:`harness.rig.drive`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from drivers.link import HarnessLink
from drivers.protocol.protocol_values import RESETTABLE_FAULTS, DriveState, FaultCode, fault_name
from harness.errors import SafetyError

#: Longest wait for the drive's first ACTUATOR_STATUS (s).
STATUS_TIMEOUT_S = 2.0
#: Shortest listening before judging (s): four periods of the E-stop panel's 20 Hz heartbeat.
LISTEN_S = 0.2
#: Longest wait for the drive to leave its latch after the reset (s), over every attempt.
VERDICT_TIMEOUT_S = 1.0
#: Frames sent when no verdict comes: the drive's receiver may take a new harness's first frame for a
#: repeated or skipped rolling counter (the rig's previous harness used the same counters); the next
#: one is then in sequence. A drive that cleared its latch ignores any further reset.
ATTEMPTS = 3
_LATCHED = (DriveState.FAULT, DriveState.ESTOP)


class DriveResetRefused(SafetyError):
    """``--reset-drive`` was refused: the drive's fault is not one a reset may clear, or the drive kept it."""


@dataclass(frozen=True)
class DriveReset:
    """What ``--reset-drive`` found and did, for the run's events and metadata.

    Attributes
    ----------
    sent : bool
        A DRIVE_RESET frame was sent.
    state_before, fault_before : str
        The drive's state and fault code before (DBC names).
    state_after, fault_after : str
        The same after the reset (before, when nothing was sent).
    """

    sent: bool
    state_before: str
    fault_before: str
    state_after: str
    fault_after: str

    def summary(self) -> str:
        """One line for the console and ``events.jsonl``."""
        if not self.sent:
            return f"drive reset not needed: the drive reports {self.state_before} with no latched fault; nothing sent"
        return (f"drive reset: {self.state_before} {self.fault_before} cleared, the drive reports {self.state_after}; "
                "it arms only through the pre-arm checks")

    def as_dict(self) -> dict:
        """Plain data for ``metadata.json``."""
        return {"sent": self.sent, "state_before": self.state_before, "fault_before": self.fault_before,
                "state_after": self.state_after, "fault_after": self.fault_after}


def _state_name(state: int) -> str:
    try:
        return DriveState(state).name
    except ValueError:
        return f"state {state}"


def latched_fault_note(link: HarnessLink) -> str:
    """A sentence on the drive's latched fault and its reset, or "" when the drive reports none.

    For the arm refusal's message: a run that cannot arm because of a latched watchdog says so.
    """
    reader = link.reader
    if not reader.status.count or reader.drive_state not in _LATCHED:
        return ""
    code = reader.fault_code
    note = f"the drive reports a latched {_state_name(reader.drive_state)} {fault_name(code)}"
    if code in RESETTABLE_FAULTS:
        return note + "; the operator's reset clears it: run again with --reset-drive"
    return note + ", which a reset over CAN cannot clear (on the virtual rig: restart `harness rig`)"


def _poll(link: HarnessLink, done, timeout_s: float, at_least_s: float = 0.0) -> bool:
    """Poll the bus until ``done()`` (after ``at_least_s``) or ``timeout_s``; return ``done()``."""
    start = time.monotonic()
    while True:
        link.reader.poll(0.0, block_s=0.01)  # pre-arm: ages are judged from the loop's first tick
        elapsed = time.monotonic() - start
        if elapsed >= at_least_s and done():
            return True
        if elapsed > timeout_s:
            return bool(done())


def _refusal(link: HarnessLink) -> str:
    """Why the latched fault must not be reset now ("" when it may be)."""
    reader = link.reader
    code = reader.fault_code
    if reader.estop_requested:
        return "an E-stop is asserted (an ESTOP frame with active=1 arrived): release it first"
    if code not in RESETTABLE_FAULTS:
        return (f"fault {fault_name(code)} is the drive's own fault, not one a reset may clear "
                f"(reset-able: {', '.join(sorted(fault_name(c) for c in RESETTABLE_FAULTS))}); clear it at the drive "
                "(on the virtual rig: restart `harness rig`)")
    if code == FaultCode.PRESSURE_LOST and not reader.pressure_ok:
        return "the hydraulic pressure is still lost: restore it first"
    return ""


def reset_drive(
    link: HarnessLink, status_timeout_s: float = STATUS_TIMEOUT_S, verdict_timeout_s: float = VERDICT_TIMEOUT_S,
) -> DriveReset:
    """Reset the drive's latched fault before arming (see the module); return what was done.

    Parameters
    ----------
    link : HarnessLink
        The open harness link (the loop has not started: nothing is armed).
    status_timeout_s, verdict_timeout_s : float
        Longest waits for the drive's status and for its verdict (s).

    Raises
    ------
    DriveResetRefused
        No status from the drive, a fault a reset may not clear, or a drive that kept its fault.
    """
    reader, status = link.reader, link.reader.status
    if not _poll(link, lambda: status.count > 0, status_timeout_s, LISTEN_S):
        raise DriveResetRefused(f"--reset-drive: no ACTUATOR_STATUS from the drive within {status_timeout_s:g} s, so "
                                "its fault is unknown; nothing was sent")
    state, code = reader.drive_state, reader.fault_code
    before = (_state_name(state), fault_name(code))
    if state not in _LATCHED:
        return DriveReset(False, *before, *before)
    refusal = _refusal(link)
    if refusal:
        raise DriveResetRefused(f"--reset-drive refused: the drive reports {before[0]} {before[1]}; {refusal}; "
                                "nothing was sent")
    cleared = False
    for _ in range(ATTEMPTS):
        link.writer.drive_reset(code, 0.0)
        cleared = _poll(link, lambda: reader.drive_state not in _LATCHED, verdict_timeout_s / ATTEMPTS)
        if cleared or reader.fault_code != code:  # cleared, or refused with another cause
            break
    if not cleared:
        raise DriveResetRefused(
            f"--reset-drive: the drive kept its latch: it reports {_state_name(reader.drive_state)} "
            f"{fault_name(reader.fault_code)} (was {before[1]}) after the reset; the fault code names what is still "
            "present"
        )
    return DriveReset(True, *before, _state_name(reader.drive_state), fault_name(reader.fault_code))
