"""Tests of each fault detector at and around its threshold, within its stated bound."""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from harness.hydraulics.servo_controller import steady_bleed_N
from harness.profile import load_profile
from harness.rig.sensors import MESSAGE_COLUMNS, SIGNALS, SensorModel
from harness.safety.actuator_detectors import (
    ActuatorStatusStale,
    DriveFault,
    ForceTracking,
    HydraulicPressure,
)
from harness.safety.checks import CHECK_NAMES
from harness.safety.checks_doc import SAFETY_TABLE
from harness.safety.comms_detectors import (
    BusErrorFrames,
    BusErrorPassive,
    BusGone,
    BusOff,
    BusSendFailures,
    E2eRejects,
    ForeignCommand,
)
from harness.safety.config import (
    ActuatorConfig,
    CommsConfig,
    ForceConfig,
    RunConfig,
    SensorConfig,
)
from harness.safety.detector_base import TIME_EPS_S, Persistence, WindowCounter
from harness.safety.events import Action
from harness.safety.health import TickHealth
from harness.safety.operator_detectors import (
    EStop,
    LoopStall,
    OperatorStop,
    OperatorTrip,
)
from harness.safety.sensor_detectors import (
    CHANNELS,
    SensorDisagree,
    SensorInvalid,
    SensorJump,
    SensorSignFlip,
    SensorStale,
    SensorStuck,
)
from tests.conftest import PROFILES

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
    assert det.update(0.0, DT, _health(**{which: limit + 1e-6}))  # beyond the 1 ns float tolerance
    assert det.update(0.0, DT, _health(**{which: math.nan}))
    assert det.present(_health(**{which: 1.0})) and not det.present(_health())


@pytest.mark.parametrize("which", ["table_age_s", "base_age_s"])
def test_sensor_stale_exactly_on_its_bound_with_the_clock_tolerance_is_fresh(which: str) -> None:
    """The bound is ``max_sensor_age_s`` plus the clock tolerance, inclusive, for each sensor."""
    det = SensorStale(SENSORS)
    bound = SENSORS.max_sensor_age_s + TIME_EPS_S
    assert not det.update(0.0, DT, _health(**{which: bound}))
    assert det.update(0.0, DT, _health(**{which: math.nextafter(bound, 1.0)}))


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


@pytest.mark.parametrize(("channel", "limit"), [
    ("table_displacement_m", SENSORS.jump_limit_m), ("table_velocity_m_s", SENSORS.jump_limit_m_s),
])
def test_sensor_jump_of_exactly_the_limit_is_allowed(channel: str, limit: float) -> None:
    """The limit is the largest change allowed in one sample: a change of exactly it does not fire."""
    det = SensorJump(SENSORS)
    health = _health()
    assert not det.update(0.0, DT, health)  # primes at 0
    setattr(health.meas, channel, limit)
    assert not det.update(DT, DT, health)
    setattr(health.meas, channel, math.nextafter(2.0 * limit, 1.0))  # a change of just over the limit
    assert det.update(2 * DT, DT, health)


@pytest.mark.parametrize(("channel", "limit"), [
    ("table_displacement_m", SENSORS.jump_limit_m), ("base_displacement_m", SENSORS.jump_limit_m),
    ("table_velocity_m_s", SENSORS.jump_limit_m_s), ("base_velocity_m_s", SENSORS.jump_limit_m_s),
])
@pytest.mark.parametrize("start", [0.0, 0.1, -0.1])
def test_sensor_jump_catches_a_downward_jump_as_an_upward_one(channel: str, limit: float, start: float) -> None:
    det = SensorJump(SENSORS)
    health = _health(**{channel: start})
    assert not det.update(0.0, DT, health)  # primes
    setattr(health.meas, channel, start - limit * 0.999)
    assert not det.update(DT, DT, health)  # down by just under the limit
    setattr(health.meas, channel, start - limit * 0.999 - limit * 1.001)
    assert det.update(2 * DT, DT, health)  # down by just over it: the first sample after the jump
    assert det.detail(health).startswith(f"{CHANNELS[CHANNEL_ATTRS.index(channel)]} changed by -")


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

#: The shipped profile's rig: its sensors' noise and quantization, and its loop rate.
RIG = load_profile(PROFILES / "nceer_4dof.yaml").rig
RIG_DT = 0.002  # 500 Hz: one sensor frame per tick
#: Samples of a long run for the false-alarm budget: one hour at 500 Hz (a record is 30 s).
RUN_SAMPLES = 3600 * 500


def _noisy_channels(seed: int, truth: float = 0.0):
    """x_0, xdot_0, y_b, ydot_b at rest (or at ``truth``) as the rig's own SensorModel reads them."""
    model = SensorModel(RIG.sensors, RIG.physics_substep_s, 0.1, np.random.default_rng(seed))
    model.reset(np.full(len(SIGNALS), truth))
    model.set_delays(0.0, None)
    table, base = [0.0] * 3, [0.0] * 3

    def read(health: TickHealth) -> None:
        model.read(MESSAGE_COLUMNS[0], table)
        model.read(MESSAGE_COLUMNS[1], base)
        health.meas.table_displacement_m, health.meas.table_velocity_m_s = table[0], table[1]
        health.meas.base_displacement_m, health.meas.base_velocity_m_s = base[0], base[1]

    return read


def _largest_cell_probability(noise_std: float, step: float) -> float:
    """Largest probability of one cell of a quantized normal: the truth at a cell's centre."""
    return math.erf(step / 2 / noise_std / math.sqrt(2))


@pytest.mark.parametrize("table_velocity_m_s", [0.0, 0.1])  # at rest, and with the table moving
@pytest.mark.parametrize("frozen", CHANNEL_ATTRS)
def test_sensor_stuck_fires_on_the_nth_repeat_at_rest_and_not_before(frozen: str, table_velocity_m_s: float) -> None:
    n = SENSORS.stuck_samples
    det = SensorStuck(SENSORS)
    read = _noisy_channels(seed=5)
    health = _health()
    fired = None
    for k in range(3 * n):
        read(health)  # every channel noisy, the table still (or moving) ...
        if frozen != "table_velocity_m_s":
            health.meas.table_velocity_m_s += table_velocity_m_s
        setattr(health.meas, frozen, 0.0123)  # ... except the frozen one, bit-identical every sample
        if det.update(k * RIG_DT, RIG_DT, health):
            fired = k
            break
    # sample 0 primes, samples 1..n are the n repeats: quiet on the (n-1)-th, fires on the n-th
    assert fired == n
    detail = det.detail(health)
    assert f"{CHANNELS[CHANNEL_ATTRS.index(frozen)]} = 0.0123 repeated to the bit {n} times" in detail
    assert det.ACTION is Action.TRIP and det.present(health) == ""


def test_sensor_stuck_restarts_its_count_when_the_value_moves_and_on_reset() -> None:
    config = dataclasses.replace(SENSORS, stuck_samples=10)
    det = SensorStuck(config)
    health = _health()  # every channel 0.0: noise-free, so every sample repeats
    for k in range(10):  # prime + 9 repeats
        assert not det.update(k * DT, DT, health)
    health.meas.base_velocity_m_s = 5e-5  # one channel moves by one step: its count restarts ...
    assert det.update(10 * DT, DT, health)  # ... but the others reach 10 repeats
    det.reset()
    for k in range(10):
        assert not det.update(k * DT, DT, health)
    assert det.update(10 * DT, DT, health)


def test_sensor_stuck_quiet_on_the_profiles_noise_at_rest_over_10000_samples() -> None:
    det = SensorStuck(SENSORS)
    for seed in (0, 1):
        read = _noisy_channels(seed)
        health = _health()
        longest, runs, previous = [0] * 4, [0] * 4, [math.nan] * 4
        for k in range(10_000):
            read(health)
            assert not det.update(k * RIG_DT, RIG_DT, health), det.detail(health)
            for c, name in enumerate(CHANNEL_ATTRS):
                value = getattr(health.meas, name)
                runs[c] = runs[c] + 1 if value == previous[c] else 0
                previous[c] = value
                longest[c] = max(longest[c], runs[c])
        # a healthy channel does repeat now and then, but nowhere near stuck_samples in a row
        assert 0 < max(longest) < SENSORS.stuck_samples // 2, longest
        det.reset()


def test_sensor_stuck_false_alarm_probability_of_the_profiles_noise() -> None:
    """docs/SAFETY.md, "Stuck sensors": P(N repeats) <= p_max**N per start, union over channels and samples."""
    n = SENSORS.stuck_samples
    bound = 0.0
    for group in (RIG.sensors.displacement, RIG.sensors.velocity):
        noise_std, _, step, _ = group.as_tuple()
        p_max = _largest_cell_probability(noise_std, step)
        bound += 2 * RUN_SAMPLES * p_max**n  # two channels of each kind
    assert bound < 1e-9
    # the arithmetic SAFETY.md shows: LVDT 5 um noise on 5 um steps, velocity 0.2 mm/s on 0.05 mm/s steps
    assert _largest_cell_probability(5e-6, 5e-6) == pytest.approx(0.3829, abs=1e-4)
    assert _largest_cell_probability(2e-4, 5e-5) == pytest.approx(0.0995, abs=1e-4)
    assert 0.3829**n < 1.5e-21
    # and the repeat rate a SensorModel shows agrees with the quantized normal (sum of p_i**2 <= p_max)
    read = _noisy_channels(seed=2)
    health = _health()
    repeats, previous = 0, math.nan
    for _ in range(20_000):
        read(health)
        repeats += health.meas.table_displacement_m == previous
        previous = health.meas.table_displacement_m
    cells = [math.erf((j + 0.5) / math.sqrt(2)) / 2 - math.erf((j - 0.5) / math.sqrt(2)) / 2 for j in range(-8, 9)]
    assert repeats / 20_000 == pytest.approx(sum(p * p for p in cells), abs=0.02)


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


def test_sensor_disagree_detail_names_the_pair_and_both_filtered_values() -> None:
    det = SensorDisagree(SENSORS)
    health = _health()
    for k in range(200):  # the base mat stands still and says it moves at 0.3 m/s
        health.meas.base_velocity_m_s = 0.3
        if det.update(k * DT, DT, health):
            break
    detail = det.detail(health)
    found = re.fullmatch(r"dy_b/dt filtered = (\S+) m/s, ydot_b filtered = (\S+) m/s, expected within 0.05 m/s", detail)
    assert found, detail
    assert abs(float(found[2]) - float(found[1])) > SENSORS.disagree_tolerance_m_s  # the two values that disagreed


# ------------------------------------------------------------------ sensor_sign_flip

#: Filters that pass their input through (tau << DT), so the sign-flip condition is the raw one.
UNFILTERED = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
PAIRS = {"table": ("table_displacement_m", "table_velocity_m_s", "x_0/xdot_0"),
         "base": ("base_displacement_m", "base_velocity_m_s", "y_b/ydot_b")}


def _ramp_run(config: SensorConfig, pair: str, speed_m_s: float, flipped_ticks, ticks: int) -> int | None:
    """One pair moving at ``speed_m_s``; its velocity sent negated on ``flipped_ticks``; the other pair at rest."""
    det = SensorSignFlip(config)
    disp, vel, _ = PAIRS[pair]
    health = _health()
    for k in range(ticks):
        setattr(health.meas, disp, speed_m_s * k * DT)
        setattr(health.meas, vel, -speed_m_s if k in flipped_ticks else speed_m_s)
        if det.update(k * DT, DT, health):
            return k
    return None


@pytest.mark.parametrize("pair", sorted(PAIRS))
def test_sensor_sign_flip_at_and_around_its_time_and_floor(pair: str) -> None:
    n = round(SENSORS.sign_flip_time_s / DT)  # ticks the condition must hold
    speed = SENSORS.sign_flip_floor_m_s * 1.01
    # the flip starts at tick 100, where the velocity's endpoint mean (+v, -v) is 0; the condition
    # holds from tick 101 and fires on the first tick with t - onset >= sign_flip_time_s ...
    assert _ramp_run(UNFILTERED, pair, speed, range(100, 10_000), 1000) == 101 + n
    # ... and not when the signs agree again one tick earlier
    assert _ramp_run(UNFILTERED, pair, speed, range(100, 101 + n), 1000) is None
    # opposite signs below the floor are not judged
    assert _ramp_run(UNFILTERED, pair, SENSORS.sign_flip_floor_m_s * 0.99, range(100, 10_000), 1000) is None
    det = SensorSignFlip(UNFILTERED)
    assert det.ACTION is Action.TRIP


def _sine_run(flip: str, amplitude_m_s: float, flip_at_s: float, ticks: int, config: SensorConfig = SENSORS):
    """Base mat moving as a sine; from ``flip_at_s`` one of its signals is negated. Fire tick of each check."""
    flip_det, disagree = SensorSignFlip(config), SensorDisagree(config)
    fired: dict[str, int] = {}
    health = _health()
    w = 2 * math.pi
    for k in range(ticks):
        t = k * DT
        v = amplitude_m_s * math.cos(w * t)
        x = amplitude_m_s / w * math.sin(w * t)
        if flip != "none" and t >= flip_at_s:
            x, v = (-x, v) if flip == "displacement" else (x, -v)
        health.meas.base_displacement_m, health.meas.base_velocity_m_s = x, v
        health.meas.table_displacement_m, health.meas.table_velocity_m_s = 0.01 * t, 0.01
        for det in (flip_det, disagree):
            if det.NAME not in fired and det.update(t, DT, health):
                fired[det.NAME] = k
        if len(fired) == 2:
            break
    return fired, flip_det


@pytest.mark.parametrize("amplitude_m_s", [0.01, 0.03, 0.1, 0.5])
def test_sensor_sign_flip_fires_within_its_bound_and_before_sensor_disagree(amplitude_m_s: float) -> None:
    # the flip comes at a peak of the speed (t = 1 s: cos = 1); the filtered velocity, primed at +v,
    # has to cross -floor: tau * ln(2 v / (v - floor)), then the condition must hold sign_flip_time_s
    fired, det = _sine_run("velocity", amplitude_m_s, 1.0, 3000)
    tau, floor = SENSORS.disagree_filter_s, SENSORS.sign_flip_floor_m_s
    onset_s = tau * math.log(2 * amplitude_m_s / (amplitude_m_s - floor))
    latency_s = fired["sensor_sign_flip"] * DT - 1.0
    assert SENSORS.sign_flip_time_s <= latency_s <= onset_s + SENSORS.sign_flip_time_s + 3 * DT
    assert "sign flip on y_b/ydot_b" in det.detail(_health())
    # sensor_disagree sees the same flip only once 2|v| > its tolerance, and always later: the sign flip is named
    if "sensor_disagree" in fired:
        assert fired["sensor_sign_flip"] < fired["sensor_disagree"]
    if amplitude_m_s >= 2 * SENSORS.disagree_tolerance_m_s:
        assert "sensor_disagree" in fired  # it does catch a fast flip, as a disagreement
    if 2 * amplitude_m_s <= SENSORS.disagree_tolerance_m_s:
        assert "sensor_disagree" not in fired  # a slow flip it never sees


def test_sensor_sign_flip_of_the_displacement_trips_too() -> None:
    fired, det = _sine_run("displacement", 0.1, 1.0, 3000)  # as the displacement crosses zero: no jump
    tau, floor = SENSORS.disagree_filter_s, SENSORS.sign_flip_floor_m_s
    onset_s = tau * math.log(2 * 0.1 / (0.1 - floor))
    latency_s = fired["sensor_sign_flip"] * DT - 1.0
    assert SENSORS.sign_flip_time_s <= latency_s <= onset_s + SENSORS.sign_flip_time_s + 3 * DT
    assert "sign flip on y_b/ydot_b" in det.detail(_health())


def test_sensor_sign_flip_quiet_for_consistent_signals_and_for_noise_around_zero() -> None:
    for amplitude in (0.001, 0.01, 0.2, 1.0):  # consistent signs through every reversal, at any speed
        fired, _ = _sine_run("none", amplitude, 0.0, 4000)
        assert "sensor_sign_flip" not in fired, amplitude
    det = SensorSignFlip(SENSORS)
    for seed in (0, 1):  # the profile's sensor noise at rest, from the rig's own SensorModel
        read = _noisy_channels(seed)
        health = _health()
        for k in range(10_000):
            read(health)
            assert not det.update(k * RIG_DT, RIG_DT, health), det.detail(health)
        det.reset()


def _stalled_sine_worst_held(det, frequency_hz: float, stall_s: float, stall_at_s: float, dt: float = 0.01) -> float:
    """Longest time (s) ``det``'s base-mat condition held, the base mat moving as a consistent sine at
    0.1 m/s and ``frequency_hz``, the loop ticking every ``dt`` with one stall of ``stall_s`` at
    ``stall_at_s``; ``t`` and ``dt`` as the loop gives them (skipped deadlines included)."""
    health = _health(table_fresh=True, base_fresh=True)
    w = 2 * math.pi * frequency_hz
    t, step, worst = 0.0, dt, 0.0
    while t < 1.6:
        health.meas.base_velocity_m_s = 0.1 * math.cos(w * t)
        health.meas.base_displacement_m = 0.1 / w * math.sin(w * t)
        det.update(t, step, health)
        worst = max(worst, det._timers[1].held_s(t))
        step = stall_s + dt if stall_at_s <= t < stall_at_s + dt else dt
        t += step
    return worst


@pytest.mark.parametrize("frequency_hz", [2.0, 5.0])
@pytest.mark.parametrize("stall_s", [0.04, 0.08, 0.13])
def test_pair_checks_quiet_through_a_reversal_after_a_stall(frequency_hz: float, stall_s: float) -> None:
    """A stall the loop rides through, just before a reversal, with consistent signals: no condition at all.

    The derivative across a stall is the mean velocity over it, centred half a stall back; judged
    against the newest velocity it had the opposite sign for up to 140 ms at 100 Hz (a false
    sensor_sign_flip in a real-time dry run on a slow host). Every stall position before the
    reversal is tried."""
    reversal_s = 1.0 + 0.25 / frequency_hz
    for k in range(30):
        stall_at_s = reversal_s - (stall_s + 0.03) * k / 30
        for det in (SensorSignFlip(SENSORS), SensorDisagree(SENSORS)):
            assert _stalled_sine_worst_held(det, frequency_hz, stall_s, stall_at_s) == 0.0, (det.NAME, stall_at_s)


@pytest.mark.parametrize("flipped_from", ["start", "stall"])
def test_a_flip_trips_within_its_bound_after_a_stall(flipped_from: str) -> None:
    """A gap starts the pair again; a flip that was there before the stall (not yet tripped) or that
    begins with it trips within the bound counted from the stall's end: the filtered velocity's
    onset tau ln(2 v / (v - floor)), then sign_flip_time_s."""
    det = SensorSignFlip(SENSORS)
    speed, stall_tick = 0.05, 20  # the stall comes before a flip from the start has tripped (~34 ms)
    health = _health(table_fresh=True, base_fresh=True)
    t, k, fired_at, stall_end = 0.0, 0, None, None
    while t < 2.0 and fired_at is None:
        step = 0.08 if k == stall_tick else DT
        t += step
        k += 1
        if k == stall_tick + 1:
            stall_end = t
        flipped = flipped_from == "start" or stall_end is not None
        health.meas.base_displacement_m = speed * t
        health.meas.base_velocity_m_s = -speed if flipped else speed
        if det.update(t, step, health):
            fired_at = t
    assert fired_at is not None and stall_end is not None and fired_at > stall_end
    tau, floor = SENSORS.disagree_filter_s, SENSORS.sign_flip_floor_m_s
    bound_s = tau * math.log(2 * speed / (speed - floor)) + SENSORS.sign_flip_time_s + 3 * DT
    assert SENSORS.sign_flip_time_s <= fired_at - stall_end <= bound_s


def test_sensor_sign_flip_restarts_when_the_signs_agree_and_on_reset() -> None:
    n = round(SENSORS.sign_flip_time_s / DT)
    speed = SENSORS.sign_flip_floor_m_s * 2
    # two flipped stretches of n - 1 ticks each, separated by one consistent tick: never n in a row
    flipped = [k for k in range(100, 100 + 2 * n) if k != 100 + n - 1]
    assert _ramp_run(UNFILTERED, "base", speed, flipped, 1000) is None
    det = SensorSignFlip(UNFILTERED)
    health = _health(base_velocity_m_s=-speed)
    for k in range(n):  # primes, then n - 1 ticks of opposite signs
        health.meas.base_displacement_m = speed * k * DT
        assert not det.update(k * DT, DT, health)
    det.reset()  # forgets filters and onset: primes again, then takes a full sign_flip_time_s
    for k in range(n, 2 * n + 1):
        health.meas.base_displacement_m = speed * k * DT
        assert not det.update(k * DT, DT, health)
    health.meas.base_displacement_m = speed * (2 * n + 1) * DT
    assert det.update((2 * n + 1) * DT, DT, health)


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


def test_window_counter_at_a_steady_rate_replaces_the_oldest_event_first() -> None:
    # one event a second, max 2 in 2.5 s: from the third on, three always sit within the window
    window = WindowCounter(max_count=2, window_s=2.5)
    window.update(0.0, 0)
    fired = [window.update(float(k), k) for k in range(1, 12)]
    assert fired == [False, False] + [True] * 9  # the ring wraps several times and always drops the oldest
    assert window.count(11.0) == 3


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


def test_actuator_status_stale_exactly_on_its_bound_with_the_clock_tolerance_is_fresh() -> None:
    """The bound is ``max_age_s`` plus the clock tolerance, inclusive (docs/SAFETY.md)."""
    det = ActuatorStatusStale(ActuatorConfig(max_status_age_s=0.05))
    assert not det.update(0.0, DT, TickHealth(actuator_status_age_s=0.05 + TIME_EPS_S))
    assert det.update(0.0, DT, TickHealth(actuator_status_age_s=math.nextafter(0.05 + TIME_EPS_S, 1.0)))


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


def test_loop_stall_at_and_around_the_budget() -> None:
    det = LoopStall(RunConfig(max_stall_s=0.02))
    assert not det.update(0.0, DT, TickHealth(stall_s=0.02))
    assert det.update(0.0, DT, TickHealth(stall_s=0.0201))
    detail = det.detail(TickHealth(stall_s=0.045, missed_periods=22))
    assert "45.0 ms" in detail and "22 missed periods" in detail and "20.0 ms" in detail
    assert "host" in detail and "--rate" in detail and "--lockstep" in detail  # says it is host timing and what to do
    long = LoopStall(RunConfig(max_stall_s=0.5)).detail(TickHealth(stall_s=0.75, missed_periods=374))
    assert long.startswith("the loop went 750.0 ms without a command (374 missed periods), expected at most 500.0 ms")


# ------------------------------------------------------------------ the table


def test_safety_table_has_one_complete_record_per_check() -> None:
    assert tuple(r.name for r in SAFETY_TABLE) == CHECK_NAMES
    for record in SAFETY_TABLE:
        assert all(record), record
        assert record.action in {"indicate", "clamp", "fade", "safe_stop", "trip"}


def test_force_tracking_reset_clears_the_actuator_lag_to_zero_and_keeps_it_lagging() -> None:
    tau, dt = 0.01, 0.002
    det = ForceTracking(ForceConfig(actuator_time_constant_s=tau))
    health = TickHealth(measured_force_N=0.0)
    det.command_N = 5_000.0
    for k in range(200):
        det.update(k * dt, dt, health)
    assert det.expected_N() == pytest.approx(5_000.0)
    det.reset()
    assert det.expected_N() == 0.0 and det.command_N == 0.0  # what a disabled actuator delivers
    det.command_N = 5_000.0
    det.update(1.0, dt, health)
    assert det.expected_N() == pytest.approx(5_000.0 * dt / (tau + dt))  # lags from zero, does not jump to the command


@pytest.mark.parametrize("pair", sorted(PAIRS))
@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_sensor_sign_flip_quiet_when_one_signal_is_small_but_of_the_same_sign(pair: str, direction: float) -> None:
    # moving above the floor while the velocity reads half the floor, same sign: slow, not flipped
    det = SensorSignFlip(UNFILTERED)
    disp, vel, _ = PAIRS[pair]
    health = _health()
    speed = direction * SENSORS.sign_flip_floor_m_s * 2.0
    for k in range(500):
        setattr(health.meas, disp, speed * k * DT)
        setattr(health.meas, vel, 0.25 * speed)
        assert not det.update(k * DT, DT, health), k


def test_window_counter_reset_forgets_the_counter_so_the_next_update_only_primes() -> None:
    window = WindowCounter(max_count=2, window_s=1.0)
    window.update(0.0, 0)
    window.update(0.1, 2)
    window.reset()
    assert not window.update(0.2, 50)  # 48 counted before the reset are not events now
    assert window.count(0.2) == 0
    assert window.update(0.3, 53)  # three new ones within the window are


def test_force_tracking_bleed_without_a_supply_force_is_the_linear_share_the_feed_forward_leaves() -> None:
    """No ``supply_force_N``: ``(1 - alpha) c v``, whatever the load (SPEC 7a')."""
    det = ForceTracking(ForceConfig(velocity_feedback_Ns_per_m=94000.0, velocity_feedforward_gain=0.25,
                                    supply_force_N=None))
    assert det.bleed_N(0.1, 0.0) == pytest.approx(0.75 * 94000.0 * 0.1)
    assert det.bleed_N(0.1, 8000.0) == pytest.approx(0.75 * 94000.0 * 0.1)


def test_force_tracking_bleed_with_a_supply_force_has_the_orifice_and_holds_the_load_to_two_thirds() -> None:
    """With ``supply_force_N`` the orifice's share comes in (non-zero at full feed-forward under load), both signs."""
    supply_N, c, v = 15000.0, 94000.0, 0.1
    det = ForceTracking(ForceConfig(velocity_feedback_Ns_per_m=c, velocity_feedforward_gain=1.0, supply_force_N=supply_N))
    for load_N in (5000.0, -5000.0):
        expected = steady_bleed_N(c, v, load_N, supply_N, 1.0)
        assert expected != 0.0 and det.bleed_N(v, load_N) == pytest.approx(expected)
    for beyond_N, held_N in ((14000.0, 10000.0), (-14000.0, -10000.0)):
        assert det.bleed_N(v, beyond_N) == pytest.approx(steady_bleed_N(c, v, held_N, supply_N, 1.0))
