"""Tests of each fault detector at and around its threshold, within its stated bound."""

from __future__ import annotations

import dataclasses
import math

import pytest

from harness.safety.actuator_detectors import ActuatorStatusStale, DriveFault, ForceTracking, HydraulicPressure
from harness.safety.comms_detectors import (
    BusErrorFrames,
    BusErrorPassive,
    BusGone,
    BusOff,
    BusSendFailures,
    E2eRejects,
    ForeignCommand,
)
from harness.safety.config import ActuatorConfig, CommsConfig, ForceConfig, RunConfig, SensorConfig
from harness.safety.detector_base import Persistence, WindowCounter
from harness.safety.events import CHECK_NAMES, Action
from harness.safety.health import TickHealth
from harness.safety.operator_detectors import EStop, LoopOverruns, OperatorStop, OperatorTrip
from harness.safety.sensor_detectors import SensorDisagree, SensorInvalid, SensorJump, SensorStale, SensorStuck
from harness.safety.table import SAFETY_TABLE

DT = 0.001
SENSORS = SensorConfig()
CHANNEL_ATTRS = ("table_displacement_m", "table_velocity_m_s", "base_displacement_m", "base_velocity_m_s")


def _health(**values: float) -> TickHealth:
    health = TickHealth()
    for name, value in values.items():
        setattr(health.meas if name in CHANNEL_ATTRS else health, name, value)
    return health


# ------------------------------------------------------------------ sensor_invalid


@pytest.mark.parametrize("channel", CHANNEL_ATTRS)
def test_sensor_invalid_at_and_around_range(channel: str) -> None:
    limit = SENSORS.velocity_range_m_s if "velocity" in channel else SENSORS.displacement_range_m
    det = SensorInvalid(SENSORS)
    assert not det.update(0.0, DT, _health(**{channel: limit}))
    assert not det.update(0.0, DT, _health(**{channel: -limit}))
    for bad in (limit * (1 + 1e-9), -limit * 1.01, math.nan, math.inf, -math.inf):
        health = _health(**{channel: bad})
        assert det.update(0.0, DT, health)
        assert det.present(health) and channel.split("_")[0][0] in det.detail(health)
    assert det.present(_health()) == ""
    assert det.ACTION is Action.TRIP


# ------------------------------------------------------------------ sensor_stale


@pytest.mark.parametrize("which", ["table_age_s", "base_age_s"])
def test_sensor_stale_at_and_around_max_age(which: str) -> None:
    det = SensorStale(SENSORS)
    limit = SENSORS.max_sensor_age_s
    assert not det.update(0.0, DT, _health(**{which: limit}))
    assert det.update(0.0, DT, _health(**{which: limit * (1 + 1e-9)}))
    assert det.update(0.0, DT, _health(**{which: math.nan}))
    assert det.present(_health(**{which: 1.0})) and not det.present(_health())


# ------------------------------------------------------------------ sensor_jump


@pytest.mark.parametrize(("channel", "limit"), [
    ("table_displacement_m", SENSORS.jump_limit_m), ("base_displacement_m", SENSORS.jump_limit_m),
    ("table_velocity_m_s", SENSORS.jump_limit_m_s), ("base_velocity_m_s", SENSORS.jump_limit_m_s),
])
def test_sensor_jump_at_and_around_the_limit(channel: str, limit: float) -> None:
    det = SensorJump(SENSORS)
    health = _health()
    assert not det.update(0.0, DT, health)  # primes
    setattr(health.meas, channel, limit * 0.999)
    assert not det.update(DT, DT, health)
    setattr(health.meas, channel, limit * 0.999 - limit * 0.999)  # back by just under the limit
    assert not det.update(2 * DT, DT, health)
    setattr(health.meas, channel, limit * 1.001)
    assert det.update(3 * DT, DT, health)  # first sample after the jump
    assert "changed by" in det.detail(health)


def test_sensor_jump_ignores_ticks_without_a_fresh_sample_and_reset_clears_history() -> None:
    det = SensorJump(SENSORS)
    health = _health(base_displacement_m=0.0)
    det.update(0.0, DT, health)
    health.base_fresh = False
    health.meas.base_displacement_m = 1.0  # not a new sample: not compared
    assert not det.update(DT, DT, health)
    det.reset()
    health.base_fresh = True
    assert not det.update(2 * DT, DT, health)  # primes again after reset
    health.meas.base_displacement_m = 1.0 + SENSORS.jump_limit_m * 2
    assert det.update(3 * DT, DT, health)


# ------------------------------------------------------------------ sensor_stuck


@pytest.mark.parametrize("frozen", ["table_displacement_m", "base_displacement_m", "base_velocity_m_s"])
def test_sensor_stuck_fires_on_the_nth_repeat_while_the_table_moves(frozen: str) -> None:
    config = dataclasses.replace(SENSORS, stuck_samples=10)
    det = SensorStuck(config)
    health = _health(table_velocity_m_s=0.1)
    fired = None
    for k in range(30):
        # every channel changes each sample except the frozen one (xdot_0 varies around 0.1 m/s)
        for name in CHANNEL_ATTRS:
            if name != frozen:
                setattr(health.meas, name, (0.1 if name == "table_velocity_m_s" else 0.0) + 1e-6 * (k % 7 + 1) * (1 + k))
        if det.update(k * DT, DT, health):
            fired = k
            break
    # sample 0 primes, samples 1..10 are the 10 repeats
    assert fired == 10
    assert "repeated 10 times" in det.detail(health)


def test_sensor_stuck_does_not_fire_below_n_repeats_or_when_the_table_is_still() -> None:
    config = dataclasses.replace(SENSORS, stuck_samples=10)
    det = SensorStuck(config)
    health = _health(table_velocity_m_s=0.1)
    for k in range(10):  # 9 repeats of every channel but xdot_0
        health.meas.table_velocity_m_s = 0.1 + 1e-6 * k
        assert not det.update(k * DT, DT, health)
    still = SensorStuck(config)
    quiet = _health(table_velocity_m_s=config.stuck_table_speed_m_s)  # at the threshold: not moving
    for k in range(100):
        assert not still.update(k * DT, DT, quiet)


def test_sensor_stuck_counts_fresh_samples_only() -> None:
    config = dataclasses.replace(SENSORS, stuck_samples=5)
    det = SensorStuck(config)
    health = _health(table_velocity_m_s=0.1, base_displacement_m=0.01)
    health.base_fresh = False
    for k in range(50):
        health.meas.table_displacement_m = 1e-4 * k
        health.meas.table_velocity_m_s = 0.1 + 1e-6 * k
        assert not det.update(k * DT, DT, health)


# ------------------------------------------------------------------ sensor_disagree


def _disagree_run(offset_m_s: float, ticks: int) -> int | None:
    det = SensorDisagree(SENSORS)
    health = _health()
    for k in range(ticks):
        t = k * DT
        v = 0.2 * math.sin(2 * math.pi * t)
        health.meas.base_displacement_m = 0.2 / (2 * math.pi) * (1 - math.cos(2 * math.pi * t))
        health.meas.base_velocity_m_s = v + offset_m_s
        health.meas.table_displacement_m = 0.01 * t
        health.meas.table_velocity_m_s = 0.01
        if det.update(t, DT, health):
            return k
    return None


def test_sensor_disagree_quiet_for_consistent_signals_and_below_tolerance() -> None:
    assert _disagree_run(0.0, 2000) is None
    assert _disagree_run(SENSORS.disagree_tolerance_m_s * 0.8, 2000) is None


def test_sensor_disagree_fires_within_its_bound() -> None:
    offset = SENSORS.disagree_tolerance_m_s * 2
    fired = _disagree_run(offset, 2000)
    assert fired is not None
    # the filtered error crosses the tolerance after about tau*ln(2) (+ finite-difference error);
    # then it must persist disagree_time_s.
    cross_s = SENSORS.disagree_filter_s * math.log(2)
    assert fired * DT >= SENSORS.disagree_time_s
    assert fired * DT <= cross_s + SENSORS.disagree_time_s + 5 * DT


# ------------------------------------------------------------------ rate windows


def test_window_counter_at_and_around_the_count() -> None:
    window = WindowCounter(max_count=3, window_s=1.0)
    assert not window.update(0.0, 100)  # primes; earlier counts are not events
    assert not window.update(0.1, 103)  # 3 events: at the limit
    assert window.update(0.2, 104)  # the 4th within 1 s
    assert window.update(1.1, 104)  # window (0.1 .. 1.1] still holds 4
    assert not window.update(1.15, 104)  # three left in the window


def test_window_counter_spread_events_and_counter_going_backwards() -> None:
    window = WindowCounter(max_count=2, window_s=1.0)
    window.update(0.0, 0)
    for k, t in enumerate((0.5, 1.1, 1.7, 2.3), start=1):
        assert not window.update(t, k)  # never more than two within 1 s
    assert not window.update(2.4, 0)  # driver restart: resync without counting
    assert not window.update(2.8, 1)  # 2.3 and 2.8 within 1 s: two, at the limit
    assert window.update(2.9, 2)


@pytest.mark.parametrize(("cls", "counter", "limit_key", "window_key"), [
    (E2eRejects, "e2e_rejects", "max_e2e_rejects", "e2e_window_s"),
    (BusErrorFrames, "error_frames", "max_error_frames", "error_frame_window_s"),
    (BusSendFailures, "send_failures", "max_send_failures", "send_failure_window_s"),
])
def test_rate_detectors_fire_on_the_count_above_the_limit(cls: type, counter: str, limit_key: str, window_key: str) -> None:
    config = CommsConfig()
    limit = getattr(config, limit_key)
    window_s = getattr(config, window_key)
    det = cls(config)
    health = TickHealth()
    det.update(0.0, DT, health)
    step = window_s / (2 * (limit + 1))
    for n in range(1, limit + 1):
        setattr(health, counter, n)
        assert not det.update(n * step, DT, health)
    setattr(health, counter, limit + 1)
    assert det.update((limit + 1) * step, DT, health)
    assert str(limit) in det.detail(health)
    det.reset()
    assert not det.update(10.0, DT, health)


def test_error_frame_and_error_passive_actions_are_configurable() -> None:
    assert BusErrorFrames(CommsConfig()).action is Action.SAFE_STOP
    assert BusErrorFrames(CommsConfig(error_frame_action="indicate")).action is Action.INDICATE
    assert BusErrorPassive(CommsConfig(error_passive_action="trip")).action is Action.TRIP


# ------------------------------------------------------------------ flags


@pytest.mark.parametrize(("det", "attr", "bad", "action"), [
    (BusErrorPassive(CommsConfig()), "error_passive", True, Action.SAFE_STOP),
    (BusOff(), "bus_off", True, Action.TRIP),
    (BusGone(), "bus_gone", True, Action.TRIP),
    (ForeignCommand(), "foreign_command", True, Action.TRIP),
    (DriveFault(), "drive_fault", True, Action.TRIP),
    (HydraulicPressure(), "pressure_ok", False, Action.TRIP),
    (EStop(), "estop", True, Action.TRIP),
    (OperatorStop(), "operator_stop", True, Action.SAFE_STOP),
    (OperatorTrip(), "operator_trip", True, Action.TRIP),
])
def test_flag_detectors_fire_on_the_same_tick(det, attr: str, bad: bool, action: Action) -> None:
    health = TickHealth()
    assert not det.update(0.0, DT, health) and det.present(health) == ""
    setattr(health, attr, bad)
    assert det.update(DT, DT, health)
    assert det.present(health) == det.detail(health) != ""
    assert det.action is action


def test_actuator_status_stale_at_and_around_max_age() -> None:
    det = ActuatorStatusStale(ActuatorConfig(max_status_age_s=0.05))
    assert not det.update(0.0, DT, TickHealth(actuator_status_age_s=0.05))
    assert det.update(0.0, DT, TickHealth(actuator_status_age_s=0.0501))
    assert det.present(TickHealth(actuator_status_age_s=math.inf))


# ------------------------------------------------------------------ force tracking


def _track(det: ForceTracking, command_N: float, measured_N: float, ticks: int) -> int | None:
    health = TickHealth(measured_force_N=measured_N)
    for k in range(ticks):
        det.command_N = command_N
        if det.update(k * DT, DT, health):
            return k
    return None


def test_force_tracking_at_and_around_tolerance_without_lag() -> None:
    config = ForceConfig(tracking_tolerance_N=1000.0, tracking_time_s=0.05, actuator_time_constant_s=0.0)
    assert _track(ForceTracking(config), 3000.0, 2000.0, 500) is None  # error == tolerance
    fired = _track(ForceTracking(config), 3000.0, 1999.0, 500)
    assert fired == round(0.05 / DT)  # onset at tick 0, fires tracking_time_s later


def test_force_tracking_with_lag_accepts_a_first_order_actuator() -> None:
    tau = 0.02
    config = ForceConfig(tracking_tolerance_N=500.0, tracking_time_s=0.02, actuator_time_constant_s=tau)
    lagged, unlagged = ForceTracking(config), ForceTracking(dataclasses.replace(config, actuator_time_constant_s=0.0))
    health = TickHealth()
    fired_lagged = fired_unlagged = False
    for k in range(400):
        command = 5000.0 if k >= 10 else 0.0
        # an actuator that is exactly a first-order lag (exact discretisation) of the command
        health.measured_force_N += (1 - math.exp(-DT / tau)) * (lagged.command_N - health.measured_force_N)
        for det in (lagged, unlagged):
            det.command_N = command
        fired_lagged |= lagged.update(k * DT, DT, health)
        fired_unlagged |= unlagged.update(k * DT, DT, health)
    assert not fired_lagged
    assert fired_unlagged


def test_persistence_restarts_when_the_condition_clears() -> None:
    timer = Persistence(0.01)
    assert not any(timer.update(k * DT, True) for k in range(10))
    assert not timer.update(10 * DT, False)
    assert not any(timer.update((11 + k) * DT, True) for k in range(10))
    assert timer.update(21 * DT, True)


# ------------------------------------------------------------------ loop


def test_loop_overruns_at_and_around_n() -> None:
    det = LoopOverruns(RunConfig(max_consecutive_overruns=3))
    assert not det.update(0.0, DT, TickHealth(consecutive_overruns=2))
    assert det.update(0.0, DT, TickHealth(consecutive_overruns=3))
    assert "3 consecutive" in det.detail(TickHealth(consecutive_overruns=3))


# ------------------------------------------------------------------ the table


def test_safety_table_has_one_complete_record_per_check() -> None:
    assert tuple(r.name for r in SAFETY_TABLE) == CHECK_NAMES
    for record in SAFETY_TABLE:
        assert all(record), record
        assert record.action in {"indicate", "clamp", "fade", "safe_stop", "trip"}


@pytest.mark.parametrize("cls", [
    SensorInvalid, SensorStale, SensorJump, SensorStuck, SensorDisagree, E2eRejects, BusErrorFrames,
    BusErrorPassive, BusOff, BusGone, BusSendFailures, ForeignCommand, DriveFault, HydraulicPressure,
    ActuatorStatusStale, ForceTracking, LoopOverruns, EStop, OperatorStop, OperatorTrip,
])
def test_each_detector_documents_detects_bound_action_reset(cls: type) -> None:
    doc = cls.__doc__ or ""
    for word in ("Detects", "Bound", "Action", "Reset"):
        assert word in doc, f"{cls.__name__} docstring lacks {word}"
    assert cls.NAME in CHECK_NAMES
