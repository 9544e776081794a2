"""Why the servo drive faulted, from a run's ``can.log``: the ``fault_code`` of its ACTUATOR_STATUS frames, named.

``signals.csv`` records the drive state (FAULT is 3) but not the servo's fault code, and a
``drive_fault`` trip's detail says only that the drive reports a fault. The code travels in
every ACTUATOR_STATUS frame, which ``can.log`` keeps: :func:`drive_faults` reads it back and
names each code by :class:`drivers.protocol.protocol_values.FaultCode` (the DBC's value table).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from drivers.protocol.codec import MessageCodec, load_protocol
from drivers.protocol.protocol_values import DriveState, FaultCode
from harness.errors import EXPECTED_ERRORS
from harness.recording.reader import RunData


@dataclass(frozen=True)
class DriveFault:
    """One fault code the drive reported: its number, its name, and the first log time it was seen (s)."""

    code: int
    first_log_time_s: float

    @property
    def name(self) -> str:
        """``HEARTBEAT_WATCHDOG (2)``, or ``code 77`` for a code the protocol does not name (an injected fault)."""
        try:
            return f"{FaultCode(self.code).name} ({self.code})"
        except ValueError:
            return f"code {self.code}"


def _dbc_path(run: RunData) -> str | None:
    can = run.profile.get("can")
    path = can.get("dbc_path") if isinstance(can, dict) else None
    return str(path) if path else None


def drive_faults(run: RunData) -> list[DriveFault]:
    """Each distinct fault code the drive reported while in FAULT, in order; empty without a readable can.log."""
    if run.can_log is None:
        return []
    try:
        codec = load_protocol(_dbc_path(run))["ACTUATOR_STATUS"]
    except (KeyError, OSError) + EXPECTED_ERRORS:
        return []
    return _scan(run.can_log, codec)


def _scan(path: Path, codec: MessageCodec) -> list[DriveFault]:
    state_at, code_at = codec.index("drive_state"), codec.index("fault_code")
    values = [0.0] * len(codec.signal_names)
    found: dict[int, DriveFault] = {}
    try:
        with open(path, encoding="ascii", errors="replace") as handle:
            for line in handle:
                parts = line.split()
                if len(parts) < 3 or "#" not in parts[2]:
                    continue
                ident, _, payload = parts[2].partition("#")
                if int(ident, 16) != codec.frame_id or len(payload) != 2 * codec.length:
                    continue
                codec.unpack(bytes.fromhex(payload), values)
                code = int(values[code_at])
                if values[state_at] == DriveState.FAULT and code not in found:
                    found[code] = DriveFault(code, float(parts[0].strip("()")))
    except (OSError, ValueError):
        return list(found.values())
    return list(found.values())


def fault_text(run: RunData) -> str:
    """``servo fault: HEARTBEAT_WATCHDOG (2)`` (all codes seen, joined), or "" when the drive never faulted."""
    faults = drive_faults(run)
    return "servo fault: " + ", ".join(fault.name for fault in faults) if faults else ""
