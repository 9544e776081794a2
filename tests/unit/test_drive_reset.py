"""The operator's reset of the servo drive (harness/rig/drive.py, DRIVE_RESET) and the rig's journal.

The drive clears a reset-able latched fault whose cause is gone and that the reset names,
back to OFF; it arms and enables nothing by itself; it refuses, with the cause in its fault
code, whatever else. Simulated wall time: no sleeping.
"""

from __future__ import annotations

import pytest

from drivers.protocol.protocol_values import RESETTABLE_FAULTS, DriveState, FaultCode, fault_name
from harness.rig.drive import Drive, ResetVerdict
from harness.rig.journal import JOURNAL_LINES, RigJournal
from harness.safety.lifecycle import State

TIMEOUT_S = 0.05


def enabled_drive(now: float = 0.0) -> Drive:
    drive = Drive(TIMEOUT_S)
    drive.on_heartbeat(now, State.RUNNING)
    drive.update(now, True)
    drive.on_command(True, 1000.0, now)
    assert drive.state == DriveState.ENABLED
    return drive


def watchdog_latched(now: float = 1.0) -> Drive:
    """Enabled at 0, then the harness went silent: FAULT HEARTBEAT_WATCHDOG at ``now``."""
    drive = enabled_drive()
    assert drive.update(now, True) == DriveState.FAULT and drive.fault_code == FaultCode.HEARTBEAT_WATCHDOG
    return drive


def test_a_reset_clears_the_heartbeat_watchdog_back_to_off_and_arms_nothing():
    drive = watchdog_latched()
    verdict = drive.request_reset(FaultCode.HEARTBEAT_WATCHDOG, 2.0, pressure_ok=True)
    assert verdict is ResetVerdict.CLEARED
    assert drive.state == DriveState.OFF and drive.fault_code == FaultCode.NONE and drive.command_N == 0.0
    assert drive.update(2.01, True) == DriveState.OFF, "READY only on fresh heartbeats, not on the old ones"
    drive.on_command(True, 5000.0, 2.02)  # a stale enable (the old harness's last wish) never enables
    assert drive.update(2.02, True) == DriveState.OFF
    drive.on_heartbeat(2.03, State.IDLE)
    assert drive.update(2.03, True) == DriveState.READY
    drive.on_command(True, 5000.0, 2.04)
    assert drive.state == DriveState.READY, "enable=1 after a reset needs an enable=0 first"
    drive.on_command(False, 0.0, 2.05)
    drive.on_command(True, 100.0, 2.06)
    assert drive.state == DriveState.ENABLED, "the harness's own arming (enable 0 then 1) enables it"


def test_a_command_watchdog_and_a_released_estop_are_reset_able_too():
    drive = enabled_drive()
    drive.on_heartbeat(0.06, State.RUNNING)
    assert drive.update(0.06, True) == DriveState.FAULT and drive.fault_code == FaultCode.COMMAND_WATCHDOG
    drive.on_heartbeat(1.0, State.TRIPPED)
    assert drive.request_reset(FaultCode.COMMAND_WATCHDOG, 1.0, pressure_ok=True) is ResetVerdict.CLEARED
    drive = enabled_drive()
    drive.on_estop()
    assert drive.request_reset(FaultCode.ESTOP, 1.0, pressure_ok=True) is ResetVerdict.CLEARED
    assert drive.state == DriveState.OFF


@pytest.mark.parametrize(
    ("conditions", "state", "code"),
    [
        ({"injected_code": 42}, DriveState.FAULT, 42),
        ({"injected_code": FaultCode.INJECTED}, DriveState.FAULT, FaultCode.INJECTED),
        ({"pressure_ok": False}, DriveState.FAULT, FaultCode.PRESSURE_LOST),
        ({"estop_asserted": True}, DriveState.ESTOP, FaultCode.ESTOP),
    ],
)
def test_a_reset_is_refused_while_a_cause_is_present_and_the_code_names_it(conditions, state, code):
    drive = watchdog_latched()
    kwargs = {"pressure_ok": True, **conditions}
    verdict = drive.request_reset(FaultCode.HEARTBEAT_WATCHDOG, 2.0, **kwargs)
    assert verdict is ResetVerdict.CAUSE_PRESENT
    assert drive.state == state and drive.fault_code == code, "stays latched; ACTUATOR_STATUS says why"
    assert drive.update(2.1, True, kwargs.get("injected_code", 0)) == state


def test_the_drives_own_fault_is_not_reset_able_even_once_its_injection_is_cleared():
    drive = enabled_drive()
    drive.on_heartbeat(0.01, State.RUNNING)
    drive.update(0.01, True, injected_code=FaultCode.INJECTED)
    assert drive.state == DriveState.FAULT and FaultCode.INJECTED not in RESETTABLE_FAULTS
    assert drive.request_reset(FaultCode.INJECTED, 2.0, pressure_ok=True) is ResetVerdict.NOT_RESETTABLE
    assert drive.state == DriveState.FAULT and drive.fault_code == FaultCode.INJECTED
    drive.reset()  # the virtual rig's power cycle (RIG_CONTROL reset) clears any latch
    assert drive.state == DriveState.OFF


def test_a_reset_naming_another_fault_is_refused():
    drive = watchdog_latched()
    assert drive.request_reset(FaultCode.COMMAND_WATCHDOG, 2.0, pressure_ok=True) is ResetVerdict.WRONG_CODE
    assert drive.state == DriveState.FAULT and drive.fault_code == FaultCode.HEARTBEAT_WATCHDOG


def test_a_reset_never_touches_a_drive_that_is_not_latched():
    drive = enabled_drive()
    assert drive.request_reset(FaultCode.NONE, 0.01, pressure_ok=True) is ResetVerdict.NOT_LATCHED
    assert drive.state == DriveState.ENABLED and drive.command_N == 1000.0


@pytest.mark.parametrize("harness_state", [State.ARMED, State.RUNNING, State.STOPPING])
def test_a_reset_is_refused_while_the_harness_says_it_is_armed_or_running(harness_state):
    drive = enabled_drive()
    drive.on_estop()
    drive.on_heartbeat(0.5, harness_state)
    assert drive.request_reset(FaultCode.ESTOP, 0.51, pressure_ok=True) is ResetVerdict.HARNESS_ACTIVE
    assert drive.state == DriveState.ESTOP
    # the same heartbeat long gone (a harness that died running): the reset is the operator's again
    assert drive.request_reset(FaultCode.ESTOP, 0.5 + 2 * TIMEOUT_S, pressure_ok=True) is ResetVerdict.CLEARED


def test_fault_names_come_from_the_dbc_table():
    assert fault_name(FaultCode.HEARTBEAT_WATCHDOG) == "HEARTBEAT_WATCHDOG"
    assert fault_name(42) == "code 42"


def test_the_journal_reports_each_change_once_and_stays_bounded():
    journal = RigJournal(clock=lambda: 100.0)
    journal.watch(DriveState.OFF, FaultCode.NONE, None, False, 0.0)
    assert journal.drain() == [], "nothing changed"
    journal.watch(DriveState.READY, FaultCode.NONE, State.IDLE, False, 0.0)
    journal.watch(DriveState.READY, FaultCode.NONE, State.RUNNING, True, 0.0)
    journal.watch(DriveState.READY, FaultCode.NONE, State.RUNNING, True, 0.5)
    journal.watch(DriveState.ESTOP, FaultCode.ESTOP, State.TRIPPED, False, 1.25)
    journal.watch(DriveState.FAULT, FaultCode.HEARTBEAT_WATCHDOG, State.TRIPPED, False, 1.25)
    lines = [line for _, line in journal.drain()]
    assert lines == [
        "drive READY", "harness IDLE", "harness RUNNING: run started", "table started: record from 0 s",
        "drive ESTOP, fault ESTOP; an E-stop; release it, then the next run needs --reset-drive",
        "harness TRIPPED: run ended: tripped", "table stopped at record time 1.25 s",
        "drive FAULT, fault HEARTBEAT_WATCHDOG; the harness's heartbeats stopped (a run ended, or the harness died); "
        "the next run needs --reset-drive",
    ]
    assert journal.drain() == []
    for k in range(JOURNAL_LINES + 10):
        journal.note(f"line {k}")
    kept = journal.drain()
    assert len(kept) == JOURNAL_LINES and kept[-1] == (100.0, f"line {JOURNAL_LINES + 9}"), "a terminal that never drains"
