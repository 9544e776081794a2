"""The one ordered list of safety checks: the supervisor's order, each check's bit, its documentation.

:data:`CHECKS` names every interlock and detector once, in the order the supervisor evaluates
them, with the check's bit number. Everything else is built from it:

- :data:`CHECK_NAMES`, the names in bit order, and :func:`bit`, :func:`index`, :func:`names_of`;
- the supervisor's detector tuple (:func:`build_detectors`);
- the safety table of docs/SAFETY.md (:data:`harness.safety.checks_doc.SAFETY_TABLE`).

A check's ``NAME`` is its trip reason, the key of its act counter and, through its bit number
``i``, the flag ``1 << i`` in :attr:`~harness.safety.supervisor.SupervisedCommand.acted`. The bit
numbers are recorded in runs (the ``interlock_flags`` column, the reason of the supervisor's ESTOP
frame) and in the console's status block, so they never change: a new check takes the next free
bit, wherever it stands in the order (logs/README.md lists them).

To add a check: write its class (the five documentation attributes of :class:`DocumentedCheck`;
a :class:`~harness.safety.detector_base.Detector` unless the supervisor performs it inline), add
one :class:`Check` here at its place in the order with the next bit, give it a trip class in
:data:`harness.safety.config.TRIP_CLASS_OF` if it can trip, a row in docs/SAFETY.md and a line in
logs/README.md (tests/unit/test_safety_checks.py, test_trip_actions.py, test_safety_doc.py and
test_logs_readme.py fail until all agree). docs/ARCHITECTURE.md has the whole recipe.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple, Protocol

from harness.safety.actuator_detectors import (
    ActuatorStatusStale,
    CompensationFault,
    DriveFault,
    ForceTracking,
    HydraulicPressure,
    LoadCellLimit,
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
from harness.safety.config import SafetyConfig
from harness.safety.detector_base import Detector
from harness.safety.events import Action
from harness.safety.interlocks import ForceClamp, ForceRateLimit, StrokeHardLimit, StrokePredictiveLimit, StrokeSoftFade
from harness.safety.operator_detectors import EStop, EStopLost, LoopStall, OperatorStop, OperatorTrip
from harness.safety.oscillation_detectors import ForceOscillation
from harness.safety.sensor_detectors import (
    SensorDisagree,
    SensorInvalid,
    SensorJump,
    SensorPolarity,
    SensorSignFlip,
    SensorStale,
    SensorStuck,
)
from harness.safety.supervisor_checks import ControllerOutput, LoopTiming, StopRamp, TickException
from harness.safety.table_record import TableRecordCheck, TableRecordMarginal, TableRecordMismatch


class DocumentedCheck(Protocol):
    """What every check class says about itself (class attributes; they build docs/SAFETY.md)."""

    NAME: str
    ACTION: Action
    DETECTS: str
    BOUND: str
    RESET: str


#: Builds a detector from the safety configuration and the table check the supervisor shares with it.
DetectorFactory = Callable[[SafetyConfig, TableRecordCheck], Detector]


class Check(NamedTuple):
    """One check of :data:`CHECKS`."""

    #: Its bit number: its position in :data:`CHECK_NAMES`, its flag ``1 << bit_number``. Never changes.
    bit_number: int
    #: The class that performs or documents it (its ``NAME`` is the check's name).
    kind: type[DocumentedCheck]
    #: For a detector, how the supervisor builds it; None for what the supervisor performs itself
    #: (the interlocks, at fixed points of the tick, and the checks of :mod:`.supervisor_checks`).
    build: DetectorFactory | None = None

    @property
    def name(self) -> str:
        """The check's stable name."""
        return self.kind.NAME


#: Every check, in the order the supervisor evaluates it in ARMED, RUNNING and STOPPING (the first
#: trip wins and later checks are not evaluated on that tick), with its bit number.
CHECKS: tuple[Check, ...] = (
    # the loop's own time
    Check(22, LoopTiming),
    # the operator: in IDLE and DONE too, estop and operator_trip are watched
    Check(25, EStop, lambda config, table: EStop()),
    Check(30, EStopLost, lambda config, table: EStopLost(config.estop)),
    Check(27, OperatorTrip, lambda config, table: OperatorTrip()),
    Check(26, OperatorStop, lambda config, table: OperatorStop()),
    # the loop's stalls: a stall is the first cause of what it lets happen while the loop is away (the drive's
    # watchdog fault, a sensor that moved further than a jump between two samples, seen in the same tick), so it
    # is judged before the checks that would see those; the operator's requests are no consequence of it
    # (docs/SAFETY.md, "Stall attribution")
    Check(21, LoopStall, lambda config, table: LoopStall(config.run)),
    # the sensors; a sign flip usually trips sensor_disagree too, later: on a tick where both hold,
    # the more specific sensor_sign_flip is the reason
    Check(5, SensorInvalid, lambda config, table: SensorInvalid(config.sensors)),
    Check(6, SensorStale, lambda config, table: SensorStale(config.sensors)),
    Check(7, SensorJump, lambda config, table: SensorJump(config.sensors)),
    Check(8, SensorStuck, lambda config, table: SensorStuck(config.sensors)),
    Check(29, SensorSignFlip, lambda config, table: SensorSignFlip(config.sensors)),
    # a flip held below the sign check's floor (a compensator's flow term damps the base mat on the wrong sensor)
    Check(36, SensorPolarity, lambda config, table: SensorPolarity(config.sensors)),
    Check(9, SensorDisagree, lambda config, table: SensorDisagree(config.sensors)),
    # the CAN link
    Check(15, BusGone, lambda config, table: BusGone()),
    Check(13, BusOff, lambda config, table: BusOff()),
    Check(12, BusErrorPassive, lambda config, table: BusErrorPassive(config.comms)),
    Check(11, BusErrorFrames, lambda config, table: BusErrorFrames(config.comms)),
    Check(10, E2eRejects, lambda config, table: E2eRejects(config.comms)),
    Check(14, BusSendFailures, lambda config, table: BusSendFailures(config.comms)),
    Check(16, ForeignCommand, lambda config, table: ForeignCommand()),
    # the actuator
    Check(17, DriveFault, lambda config, table: DriveFault()),
    Check(18, HydraulicPressure, lambda config, table: HydraulicPressure()),
    Check(19, ActuatorStatusStale, lambda config, table: ActuatorStatusStale(config.actuator)),
    # the load path's own limit, on the force fed back (a servo controller's limit detector)
    Check(35, LoadCellLimit, lambda config, table: LoadCellLimit(config.force)),
    Check(20, ForceTracking, lambda config, table: ForceTracking(config.force)),
    Check(33, CompensationFault, lambda config, table: CompensationFault(config.force)),
    Check(34, ForceOscillation, lambda config, table: ForceOscillation(config.force)),
    # the table against its record: the mismatch adds the tick's sample and judges when due
    Check(31, TableRecordMismatch, lambda config, table: TableRecordMismatch(table)),
    Check(32, TableRecordMarginal, lambda config, table: TableRecordMarginal(table)),
    # the controller's output, then the stroke trips
    Check(24, ControllerOutput),
    Check(3, StrokeHardLimit),
    Check(4, StrokePredictiveLimit),
    # force shaping: clamp, stopping ramp (zero target in ARMED), rate limit, stroke fade
    Check(0, ForceClamp),
    Check(28, StopRamp),
    Check(1, ForceRateLimit),
    Check(2, StrokeSoftFade),
    # reported by the loop, from any state
    Check(23, TickException),
)


def _in_bit_order(checks: tuple[Check, ...]) -> tuple[Check, ...]:
    """``checks`` sorted by bit number, which must run 0, 1, ... without gap or repeat, names unique."""
    ordered = tuple(sorted(checks, key=lambda check: check.bit_number))
    indices = [check.bit_number for check in ordered]
    if indices != list(range(len(ordered))):
        raise RuntimeError(f"safety check bits are {indices}; expected each of 0..{len(ordered) - 1} once")
    names = [check.name for check in ordered]
    if len(set(names)) != len(names):
        raise RuntimeError(f"safety check names repeat: {names}")
    return ordered


#: :data:`CHECKS` in bit order.
CHECKS_BY_BIT: tuple[Check, ...] = _in_bit_order(CHECKS)

#: Stable names of all checks, in bit order.
CHECK_NAMES: tuple[str, ...] = tuple(check.name for check in CHECKS_BY_BIT)

_INDEX: dict[str, int] = {name: i for i, name in enumerate(CHECK_NAMES)}


def bit(name: str) -> int:
    """The bit flag of the check called ``name``.

    Raises
    ------
    KeyError
        If ``name`` is not one of :data:`CHECK_NAMES`.
    """
    try:
        return 1 << _INDEX[name]
    except KeyError as err:
        raise KeyError(f"unknown safety check {name!r}; expected one of {', '.join(CHECK_NAMES)}") from err


def index(name: str) -> int:
    """The position of ``name`` in :data:`CHECK_NAMES` (its counter slot and bit number)."""
    return bit(name).bit_length() - 1


def names_of(flags: int) -> tuple[str, ...]:
    """Decode bit flags into check names (for reports; allocates, never call per tick)."""
    return tuple(name for i, name in enumerate(CHECK_NAMES) if flags >> i & 1)


def build_detectors(config: SafetyConfig, table_record: TableRecordCheck) -> tuple[Detector, ...]:
    """The supervisor's detectors, in the order of :data:`CHECKS`, built from ``config``.

    ``table_record`` is the state the two table checks share with the supervisor.
    """
    return tuple(check.build(config, table_record) for check in CHECKS if check.build is not None)
