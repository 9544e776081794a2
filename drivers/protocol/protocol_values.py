"""The protocol's named numbers: its version and the value tables of ``drivers/protocol/rig.dbc``.

The DBC is the source of truth: each enum here mirrors one ``VAL_`` table of the
DBC (cantools reads it as ``signal.choices``, and ``cantools decode`` prints the
names), member for member. :func:`drivers.protocol.codec.load_protocol` refuses a DBC whose
value table for one of these signals differs (:data:`VALUE_TABLES`), and a unit test
checks the packaged DBC, so the names in code and on the bus cannot drift apart.

The enums are written out rather than built from the DBC at run time so that they
can be imported (and type-checked) without parsing anything; this module imports
nothing heavy. The harness's lifecycle state, sent in HEARTBEAT ``state``, is the
harness's own enum (``harness.safety.lifecycle.State``); the DBC's table for it is
checked by the same test.

Every enum is an :class:`~enum.IntEnum`: a member compares equal to the raw value
the codec decodes (``2.0 == DriveState.ENABLED``), so the tick compares decoded
floats with names without converting or allocating anything.
"""

from __future__ import annotations

from enum import IntEnum

#: The ``ProtocolVersion`` of the packaged ``drivers/protocol/rig.dbc``.
CURRENT_PROTOCOL_VERSION = 1

#: CAN FD protocol (``drivers/protocol/rig_fd.dbc``): the messages whose payloads SENSOR_SET carries, in its
#: order, three signals each; on that protocol they are not sent on their own.
SENSOR_SET_PARTS: tuple[str, ...] = ("TABLE_SENSORS", "BASE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS")


class EstopSource(IntEnum):
    """ESTOP ``source``: who requested the stop."""

    HARNESS = 0
    RIG = 1
    SERVO = 2
    PANEL = 3
    SUPERVISOR = 4


class DriveState(IntEnum):
    """ACTUATOR_STATUS ``drive_state``: the servo controller's enable state."""

    OFF = 0
    READY = 1
    ENABLED = 2
    FAULT = 3
    ESTOP = 4


class FaultCode(IntEnum):
    """ACTUATOR_STATUS ``fault_code``: why the drive faulted (an injected fault may send any code 0..255)."""

    NONE = 0
    COMMAND_WATCHDOG = 1
    HEARTBEAT_WATCHDOG = 2
    PRESSURE_LOST = 3
    INJECTED = 4
    ESTOP = 5


class RigCommand(IntEnum):
    """RIG_CONTROL ``command``: what the harness asks of the (virtual) rig's table."""

    NONE = 0
    START_TABLE = 1
    STOP_TABLE = 2
    RESET = 3


#: Latched fault codes a DRIVE_RESET frame may clear, once their cause is gone: the watchdogs (the
#: harness that stopped talking is back: it sent the reset), an E-stop latch (no E-stop asserted any
#: more) and a pressure loss (pressure back). Any other code is the drive's own fault (INJECTED on the
#: virtual rig, or a code of the drive's): not reset-able over CAN.
RESETTABLE_FAULTS: frozenset[int] = frozenset(
    {FaultCode.COMMAND_WATCHDOG, FaultCode.HEARTBEAT_WATCHDOG, FaultCode.PRESSURE_LOST, FaultCode.ESTOP}
)


def fault_name(code: int) -> str:
    """The DBC's name of fault ``code`` (``"HEARTBEAT_WATCHDOG"``), or ``"code N"`` for one it does not name."""
    try:
        return FaultCode(int(code)).name
    except ValueError:
        return f"code {int(code)}"


#: (message, signal) -> the enum that names its values; each must equal the DBC's ``VAL_`` table.
VALUE_TABLES: dict[tuple[str, str], type[IntEnum]] = {
    ("ESTOP", "source"): EstopSource,
    ("ACTUATOR_STATUS", "drive_state"): DriveState,
    ("ACTUATOR_STATUS", "fault_code"): FaultCode,
    ("RIG_CONTROL", "command"): RigCommand,
    ("DRIVE_RESET", "fault_code"): FaultCode,
}


def choices_of(enum: type[IntEnum]) -> dict[int, str]:
    """``{value: name}`` of ``enum``, the form of a DBC value table (``signal.choices``)."""
    return {int(member): member.name for member in enum}
