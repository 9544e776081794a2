"""Fault injection of the virtual rig: ids, parameters, and the set of active faults.

A fault is a *kind* and, for message faults, a *target* message. On the bus
(RIG_CONTROL ``fault_id``/``fault_param``) and in this module its id is
``10 * kind + target``; ``fault_id = 0`` clears every fault injected at run time
(scheduled faults from the profile keep their schedule). Several faults may be
active at once. A fault injected at run time lasts until cleared; a scheduled
fault (profile ``rig.faults``) is active for ``start_s <= record time < start_s +
duration_s`` (``duration_s = 0``: until the end of the run / reset).

Targets: 0 TABLE_SENSORS, 1 BASE_SENSORS, 2 STORY_DRIFTS, 3 FLOOR_ACCELS,
4 ACTUATOR_STATUS, 5 RIG_STATUS.

======  ==============  ================  =====================================================
id      kind            targets           effect (param, SI)
======  ==============  ================  =====================================================
10+t    dropout         0-5               the message is not sent at all (4 = status frames stop)
20+t    stuck           0-3               the values freeze at the last ones sent before onset
30+t    spike           0-3               one frame with ``param`` added to its first signal
                                          (x_0, y_b, drift_1 in m; accel_1 in m/s^2)
40+t    noise_burst     0-3               extra Gaussian noise, std ``param`` in each signal's unit
50+t    corrupt_crc     0-5               frames sent with a wrong CRC (receiver counts BAD_CRC)
60+t    repeat_counter  0-5               frames repeat the previous rolling counter
70+t    skip_counter    0-5               frames skip one rolling-counter value
80      extra_delay     -                 every sensor delay grows by ``param`` s (<= 1 s)
90      bus_silence     -                 the rig sends nothing at all
100     drive_fault     -                 drive goes to FAULT, fault code ``param`` (default 4)
110     pressure_lost   -                 pressure_ok = 0; an active drive faults (code 3)
120     estop           -                 the rig sends ESTOP (source 1) and the drive goes ESTOP
130+t   sign_flip       0-3               signal number ``param`` (0, 1 or 2 in DBC order: 1 is
                                          xdot_0 / ydot_b) is sent negated, a polarity fault
140+t   polarity        0-3               every signal of the message is sent negated: a whole
                                          sensor of the wrong polarity (displacement, velocity
                                          and acceleration flipped together, self-consistent)
150     seize           -                 the bearings seize: the sliding stops at once (a blocked
                                          piston) and the base mat moves with the table while on
======  ==============  ================  =====================================================

``seize`` is a fault of the plant, not of a message: the virtual rig and the rig twin
(``harness simulate --rig-effects``, which has no bus and acts on no message fault) both act on
it through :meth:`harness.rig.table.TablePlant.set_seized`.

Drive fault codes in ACTUATOR_STATUS: see :mod:`harness.rig.drive`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.errors import HarnessError

TARGETS = ("TABLE_SENSORS", "BASE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS", "ACTUATOR_STATUS", "RIG_STATUS")
SENSOR_TARGETS = 4
KINDS = (
    "", "dropout", "stuck", "spike", "noise_burst", "corrupt_crc", "repeat_counter", "skip_counter",
    "extra_delay", "bus_silence", "drive_fault", "pressure_lost", "estop", "sign_flip", "polarity", "seize",
)
DROPOUT, STUCK, SPIKE, NOISE_BURST, CORRUPT_CRC, REPEAT_COUNTER, SKIP_COUNTER = 1, 2, 3, 4, 5, 6, 7
EXTRA_DELAY, BUS_SILENCE, DRIVE_FAULT, PRESSURE_LOST, ESTOP = 8, 9, 10, 11, 12
SIGN_FLIP, POLARITY, SEIZE = 13, 14, 15
_SENSOR_ONLY = (STUCK, SPIKE, NOISE_BURST, SIGN_FLIP, POLARITY)
_TARGETED = (DROPOUT, STUCK, SPIKE, NOISE_BURST, CORRUPT_CRC, REPEAT_COUNTER, SKIP_COUNTER, SIGN_FLIP, POLARITY)
MAX_EXTRA_DELAY_S = 1.0
#: Signals per sensor message (every sensor message carries three): valid ``sign_flip`` params.
SIGNALS_PER_SENSOR_MESSAGE = 3


class FaultError(HarnessError, ValueError):
    """A fault id, kind or target that the virtual rig does not define."""


def _check(kind: int, target: int) -> None:
    if kind not in range(1, len(KINDS)):
        last = len(KINDS) - 1
        raise FaultError(f"fault kind {kind}; expected 1..{last} (fault ids 10..{10 * last}, see harness.rig.faults)")
    if kind in _TARGETED:
        limit = SENSOR_TARGETS if kind in _SENSOR_ONLY else len(TARGETS)
        if not 0 <= target < limit:
            raise FaultError(
                f"fault {KINDS[kind]} on target {target}; expected a target 0..{limit - 1} ({', '.join(TARGETS[:limit])})"
            )
    elif target != 0:
        raise FaultError(f"fault {KINDS[kind]} takes no target; found target {target} (fault id {10 * kind + target})")


def sign_flip_signal(param: float) -> int:
    """The signal index a ``sign_flip`` fault's ``param`` names, or -1 if it names none (0, 1 or 2)."""
    index = int(param) if param == param and float(param).is_integer() else -1
    return index if 0 <= index < SIGNALS_PER_SENSOR_MESSAGE else -1


def decode_fault_id(fault_id: int) -> tuple[int, int]:
    """``(kind, target)`` of a non-zero fault id.

    Raises
    ------
    FaultError
        The id is not in the table of the module docstring.
    """
    kind, target = divmod(int(fault_id), 10)
    try:
        _check(kind, target)
    except FaultError as err:
        raise FaultError(f"unknown fault id {fault_id}: {err}") from err
    return kind, target


def fault_id_for(kind: str, target: str = "") -> int:
    """The fault id of a kind name and target message name (``""`` for none).

    Raises
    ------
    FaultError
        Unknown kind, or a target where none belongs / missing where one is needed.
    """
    if kind not in KINDS[1:]:
        raise FaultError(f"unknown fault kind {kind!r}; expected one of: {', '.join(KINDS[1:])}")
    code = KINDS.index(kind)
    if code in _TARGETED:
        if target not in TARGETS:
            raise FaultError(f"fault {kind!r} needs a target message; found {target!r}, expected one of: {', '.join(TARGETS)}")
        index = TARGETS.index(target)
    elif target:
        raise FaultError(f"fault {kind!r} takes no target; found {target!r}")
    else:
        index = 0
    _check(code, index)
    return 10 * code + index


@dataclass(frozen=True)
class ScheduledFault:
    """A fault active over ``[start_s, end_s)`` of record time."""

    kind: int
    target: int
    start_s: float
    end_s: float
    param: float


class FaultSet:
    """The active faults: run-time injections and the profile's schedule, merged.

    Query :attr:`active` ``[kind, target]`` and :attr:`param` ``[kind, target]``
    after :meth:`update`. Spikes are one-shot: :meth:`take_spike` consumes them.

    Parameters
    ----------
    schedule : sequence of ScheduledFault
    """

    def __init__(self, schedule: tuple[ScheduledFault, ...] = ()):
        shape = (len(KINDS), len(TARGETS))
        self.schedule = tuple(schedule)
        self.active = np.zeros(shape, dtype=bool)
        self.param = np.zeros(shape)
        self._runtime = np.zeros(shape, dtype=bool)
        self._runtime_param = np.zeros(shape)
        self._spike_pending = np.zeros(SENSOR_TARGETS, dtype=bool)
        self._fired = np.zeros(len(self.schedule), dtype=bool)
        self.unknown_ids = 0

    def reset_schedule(self) -> None:
        """Forget which scheduled spikes fired (at table start / reset)."""
        self._fired[:] = False

    def inject(self, fault_id: int, param: float) -> bool:
        """Apply RIG_CONTROL's ``fault_id``/``fault_param``; 0 clears. False (counted) for an unknown id."""
        if fault_id == 0:
            self._runtime[:] = False
            self._spike_pending[:] = False
            return True
        try:
            kind, target = decode_fault_id(fault_id)
        except FaultError:
            self.unknown_ids += 1
            return False
        if kind == SIGN_FLIP and sign_flip_signal(param) < 0:
            self.unknown_ids += 1  # names no signal of the message
            return False
        if kind == SPIKE:
            if not self._runtime[kind, target] or self._runtime_param[kind, target] != param:
                self._spike_pending[target] = True
        self._runtime[kind, target] = True
        self._runtime_param[kind, target] = param
        return True

    def update(self, record_time_s: float | None) -> None:
        """Recompute :attr:`active` at ``record_time_s`` (None: table not started, no schedule)."""
        np.copyto(self.active, self._runtime)
        np.copyto(self.param, self._runtime_param)
        if record_time_s is None:
            return
        for i, fault in enumerate(self.schedule):
            if fault.start_s <= record_time_s < fault.end_s:
                if fault.kind == SPIKE:
                    if not self._fired[i]:
                        self._fired[i] = True
                        self._spike_pending[fault.target] = True
                        self.param[fault.kind, fault.target] = fault.param
                    continue
                self.active[fault.kind, fault.target] = True
                self.param[fault.kind, fault.target] = fault.param

    def take_spike(self, target: int) -> float:
        """The pending spike offset of ``target`` (0.0 if none), consumed."""
        if not self._spike_pending[target]:
            return 0.0
        self._spike_pending[target] = False
        return float(self.param[SPIKE, target])

    @property
    def any_active(self) -> bool:
        """True while any fault is active (spikes count until sent)."""
        return bool(self.active.any() or self._spike_pending.any())

    def is_on(self, kind: int, target: int = 0) -> bool:
        """True when ``kind`` is active on ``target``."""
        return bool(self.active[kind, target])

    def flipped_signal(self, target: int) -> int:
        """Index of the signal of sensor message ``target`` sent negated, or -1 (no sign flip active)."""
        if not self.active[SIGN_FLIP, target]:
            return -1
        return sign_flip_signal(float(self.param[SIGN_FLIP, target]))

    def reversed_polarity(self, target: int) -> bool:
        """True while every signal of sensor message ``target`` is sent negated (a ``polarity`` fault)."""
        return bool(self.active[POLARITY, target])

    @property
    def extra_delay_s(self) -> float:
        """Extra sensor delay (s), clipped to 0..1 s."""
        if not self.active[EXTRA_DELAY, 0]:
            return 0.0
        return min(max(float(self.param[EXTRA_DELAY, 0]), 0.0), MAX_EXTRA_DELAY_S)

    def active_ids(self) -> tuple[int, ...]:
        """Ids of the active faults (for snapshots and logs)."""
        kinds, targets = np.nonzero(self.active)
        return tuple(int(10 * k + t) for k, t in zip(kinds, targets, strict=True))


def schedule_from(specs) -> tuple[ScheduledFault, ...]:
    """Scheduled faults from the profile's ``rig.faults`` entries (:class:`~harness.rig.config.FaultSpec`)."""
    result = []
    for spec in specs:
        kind, target = decode_fault_id(fault_id_for(spec.kind, spec.target))
        if kind == SIGN_FLIP and sign_flip_signal(spec.param) < 0:
            raise FaultError(
                f"fault sign_flip on {spec.target} with param {spec.param!r}; expected the index of the signal "
                f"to negate: 0, 1 or 2 in DBC order (1 is the velocity of TABLE_SENSORS and BASE_SENSORS)"
            )
        end = spec.start_s + spec.duration_s if spec.duration_s > 0 else float("inf")
        result.append(ScheduledFault(kind, target, spec.start_s, end, spec.param))
    return tuple(result)
