"""The DBC's value tables and the enums that name them in code: one set of names, checked both ways.

``drivers/protocol/rig.dbc`` names the values of the drive state, fault code, rig command, E-stop
source and the harness's lifecycle state (``VAL_`` lines, cantools' ``signal.choices``).
The code uses :mod:`drivers.protocol.protocol_values` and :class:`harness.safety.lifecycle.State`;
these tests keep them equal, keep the codec decoding numbers, and check that
``cantools decode`` prints the names.
"""

from __future__ import annotations

import subprocess
import sys
from enum import IntEnum
from pathlib import Path

import pytest

from drivers.errors import ProtocolError
from drivers.protocol.codec import DEFAULT_DBC, load_protocol
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.protocol.protocol_values import (
    VALUE_TABLES,
    DriveState,
    FaultCode,
    RigCommand,
    choices_of,
)
from harness.safety.lifecycle import State
from tests.conftest import edited_dbc

PROTOCOL = load_protocol()
#: Every value table of the DBC and the enum that names it in code.
ENUMS: dict[tuple[str, str], type[IntEnum]] = {**VALUE_TABLES, ("HEARTBEAT", "state"): State}


@pytest.mark.parametrize(("message", "signal"), sorted(ENUMS))
def test_every_enum_equals_its_dbc_value_table(message: str, signal: str) -> None:
    enum = ENUMS[message, signal]
    assert PROTOCOL.value_table(message, signal) == choices_of(enum), f"{message}.{signal} vs {enum.__name__}"


def test_every_dbc_value_table_has_an_enum() -> None:
    tables = {
        (message.name, sig.name)
        for message in PROTOCOL.database.messages
        for sig in message.signals
        if sig.choices
    }
    assert tables == set(ENUMS)


def test_every_named_value_fits_its_signal() -> None:
    for (message, signal), enum in ENUMS.items():
        layout = PROTOCOL[message].signals[PROTOCOL[message].index(signal)]
        for member in enum:
            assert layout.minimum <= member <= layout.maximum, f"{message}.{signal} {member.name} outside the DBC range"


def test_choice_looks_names_up_in_the_dbc() -> None:
    assert PROTOCOL.choice("ACTUATOR_STATUS", "drive_state", "FAULT") == DriveState.FAULT
    assert PROTOCOL.choice("HEARTBEAT", "state", "TRIPPED") == State.TRIPPED
    with pytest.raises(ProtocolError, match="no choice 'JUMP'.*START_TABLE"):
        PROTOCOL.choice("RIG_CONTROL", "command", "JUMP")


def test_the_codec_still_decodes_numbers() -> None:
    codec = PROTOCOL["ACTUATOR_STATUS"]
    decoder = Decoder(PROTOCOL, ["ACTUATOR_STATUS"])
    frame = codec.encode([DriveState.ESTOP, 1.0, FaultCode.ESTOP, 12.0], counter=0)
    assert decoder.decode(codec.frame_id, frame) == RxStatus.OK
    values = decoder.values("ACTUATOR_STATUS")
    assert values == [4.0, 1.0, 5.0, 12.0] and all(type(value) is float for value in values)
    assert values[0] == DriveState.ESTOP


def test_a_dbc_naming_values_otherwise_is_refused(tmp_path: Path) -> None:
    dbc = edited_dbc(tmp_path, DEFAULT_DBC, ('1 "START_TABLE" 2 "STOP_TABLE"', '1 "STOP_TABLE" 2 "START_TABLE"'))
    with pytest.raises(ProtocolError, match=r"VAL_ table of RIG_CONTROL.command .*expected .*1 \"START_TABLE\""):
        load_protocol(dbc)


def test_a_dbc_without_value_tables_is_still_accepted(tmp_path: Path) -> None:
    text = DEFAULT_DBC.read_text(encoding="cp1252")
    bare = "\n".join(line for line in text.splitlines() if not line.startswith("VAL_ ")) + "\n"
    dbc = tmp_path / "bare.dbc"
    dbc.write_text(bare, encoding="cp1252")
    assert load_protocol(dbc).value_table("RIG_CONTROL", "command") == {}


def test_cantools_decode_prints_the_names() -> None:
    status = PROTOCOL["ACTUATOR_STATUS"].encode([DriveState.FAULT, 1.0, FaultCode.HEARTBEAT_WATCHDOG, 0.0], 0)
    control = PROTOCOL["RIG_CONTROL"].encode([RigCommand.STOP_TABLE, 0.0, 0.0, 0.0], 0)
    heartbeat = PROTOCOL["HEARTBEAT"].encode([State.RUNNING], 0)
    lines = [
        f"(0.000000) vcan0 {PROTOCOL[name].frame_id:03X}#{data.hex().upper()}"
        for name, data in (("ACTUATOR_STATUS", status), ("RIG_CONTROL", control), ("HEARTBEAT", heartbeat))
    ]
    done = subprocess.run(
        [sys.executable, "-m", "cantools", "decode", str(DEFAULT_DBC)],
        input="\n".join(lines) + "\n", capture_output=True, text=True, timeout=60, check=True,
    )
    for name in ("drive_state: FAULT", "fault_code: HEARTBEAT_WATCHDOG", "command: STOP_TABLE", "state: RUNNING"):
        assert name in done.stdout, done.stdout
