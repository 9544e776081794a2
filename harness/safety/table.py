"""The safety table: one record per check, for docs/SAFETY.md.

Built from the checks' own class attributes so the table cannot drift from the
code; the four checks the supervisor performs inline have their records here.
Actions are the defaults; ``bus_error_frames``, ``bus_error_passive`` and
``force_tracking`` take theirs from the configuration.
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

from harness.safety.actuator_detectors import (
    ActuatorStatusStale,
    DriveFault,
    ForceTracking,
    HydraulicPressure,
)
from harness.safety.comms_detectors import (
    BusErrorFrames,
    BusErrorPassive,
    BusGone,
    BusOff,
    BusSendFailures,
    E2eRejects,
    ForeignCommand,
)
from harness.safety.events import CHECK_NAMES, Action
from harness.safety.interlocks import (
    ForceClamp,
    ForceRateLimit,
    StrokeHardLimit,
    StrokePredictiveLimit,
    StrokeSoftFade,
)
from harness.safety.operator_detectors import (
    EStop,
    EStopLost,
    LoopStall,
    OperatorStop,
    OperatorTrip,
)
from harness.safety.sensor_detectors import (
    SensorDisagree,
    SensorInvalid,
    SensorJump,
    SensorSignFlip,
    SensorStale,
    SensorStuck,
)
from harness.safety.table_record import TableRecordMarginal, TableRecordMismatch


class SafetyRecord(NamedTuple):
    """One row of the safety table."""

    name: str
    detects: str
    bound: str
    action: str
    reset: str


class _DocumentedCheck(Protocol):
    """What a check class says about itself (class attributes of every detector and interlock)."""

    NAME: str
    ACTION: Action
    DETECTS: str
    BOUND: str
    RESET: str


_CLASSES: tuple[type[_DocumentedCheck], ...] = (
    ForceClamp, ForceRateLimit, StrokeSoftFade, StrokeHardLimit, StrokePredictiveLimit,
    SensorInvalid, SensorStale, SensorJump, SensorStuck, SensorDisagree, SensorSignFlip,
    E2eRejects, BusErrorFrames, BusErrorPassive, BusOff, BusSendFailures, BusGone, ForeignCommand,
    DriveFault, HydraulicPressure, ActuatorStatusStale, ForceTracking,
    LoopStall, EStop, OperatorStop, OperatorTrip, EStopLost, TableRecordMismatch, TableRecordMarginal,
)

_INLINE = (
    SafetyRecord("loop_timing", "t not finite, or dt not finite or <= 0", "same tick", "trip", "explicit reset"),
    SafetyRecord("tick_exception", "the tick raised (reported by the loop)", "same tick", "trip", "explicit reset"),
    SafetyRecord("controller_output", "controller output not finite (NaN or inf)", "same tick", "trip", "explicit reset"),
    SafetyRecord(
        "stop_ramp", "STOPPING: force scaled from 1 to 0 over stopping_ramp_s", "stopping_ramp_s",
        "clamp", "DONE once the force is zero; then reset",
    ),
)


def _record(cls: type[_DocumentedCheck]) -> SafetyRecord:
    action = Action(cls.ACTION).name.lower()
    return SafetyRecord(cls.NAME, cls.DETECTS, cls.BOUND, action, cls.RESET)


def _build() -> tuple[SafetyRecord, ...]:
    by_name = {r.name: r for r in (*map(_record, _CLASSES), *_INLINE)}
    missing = [name for name in CHECK_NAMES if name not in by_name]
    if missing:
        raise RuntimeError(f"safety table has no record for {missing}; expected one per CHECK_NAMES entry")
    return tuple(by_name[name] for name in CHECK_NAMES)


#: One record per check, in :data:`~harness.safety.events.CHECK_NAMES` (bit) order.
SAFETY_TABLE: tuple[SafetyRecord, ...] = _build()
