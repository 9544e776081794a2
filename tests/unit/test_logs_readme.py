"""logs/README.md says what the run folders hold: the event kinds written and the integer codes' meanings."""

from __future__ import annotations

import re

from drivers.protocol.protocol_values import DriveState, FaultCode
from harness.safety.checks import CHECK_NAMES
from harness.safety.events import EventKind
from harness.safety.lifecycle import State
from tests.conftest import REPO

README = (REPO / "logs" / "README.md").read_text(encoding="utf-8")
#: Kinds written outside the supervisor's ring: the loop's timing events, the session's notices, the recorder's.
OTHER_KINDS = ("timing", "safety", "warning")


def _table_rows(heading: str) -> list[list[str]]:
    section = README.split(heading, 1)[1]
    return [[cell.strip() for cell in line.strip().strip("|").split("|")] for line in section.splitlines()
            if line.startswith("| ") and not line.startswith("|---")]


def test_every_event_kind_written_is_documented() -> None:
    rows = _table_rows("## events.jsonl")
    documented = {row[0].strip("`") for row in rows[1:]}
    written = {EventKind.STATE, EventKind.INTERLOCK, EventKind.FAULT, *OTHER_KINDS}
    assert written <= documented, f"undocumented kinds: {written - documented}"
    assert "lifecycle" not in documented and "trip" not in documented


def test_every_interlock_flag_bit_is_documented_in_bit_order() -> None:
    rows = [row for row in _table_rows("`interlock_flags` is the sum") if row[0].isdigit()]
    assert [(int(row[0]), int(row[1]), row[2].strip("`")) for row in rows] == [
        (i, 1 << i, name) for i, name in enumerate(CHECK_NAMES)]


def test_state_drive_state_and_fault_codes_are_documented() -> None:
    state = next(row for row in _table_rows("`state` is the run state") if row[0] == "state")
    assert state[1:] == [member.name for member in State]
    drive = next(row for row in _table_rows("`drive_state` is the servo") if row[0] == "drive_state")
    assert drive[1:] == [member.name for member in DriveState]
    for member in FaultCode:
        assert re.search(rf"\b{int(member)} {member.name}\b", README), member
