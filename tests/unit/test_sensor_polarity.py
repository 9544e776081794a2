"""The polarity check (``sensor_polarity``): a sign flip held below ``sensor_sign_flip``'s floor.

docs/SAFETY.md, "A sign flip held below the floor: sensor_polarity", derives the floor, the window and
the bound; the fault-injection dry runs under every compensation are in
tests/integration/test_fault_injection.py.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from harness.safety.config import SafetyConfig, SensorConfig
from harness.safety.events import Action
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.sensor_detectors import SensorPolarity, SensorSignFlip
from harness.safety.supervisor import Supervisor
from tests.unit.test_detectors import RIG_DT, _noisy_channels
from tests.unit.test_force_limits import armed_supervisor

DT = 0.001
SENSORS = SensorConfig()
#: Without the pair filter, the product is exactly -v^2 from the tick after the flip (closed forms below).
UNFILTERED = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
PAIRS = {"table": ("table_displacement_m", "table_velocity_m_s"), "base": ("base_displacement_m", "base_velocity_m_s")}


def _ramp(config: SensorConfig, pair: str, speed_m_s: float, ticks: int, flipped_until: int | None = None):
    """One pair moving at ``speed_m_s`` with its velocity negated from tick 0 (to ``flipped_until``); the fire tick."""
    det = SensorPolarity(config)
    disp, vel = PAIRS[pair]
    health = TickHealth()
    for k in range(ticks):
        flipped = flipped_until is None or k < flipped_until
        setattr(health.meas, disp, speed_m_s * k * DT)
        setattr(health.meas, vel, -speed_m_s if flipped else speed_m_s)
        if det.update(k * DT, DT, health):
            return k, det
    return None, det


def _expected_fire_tick(config: SensorConfig, speed_m_s: float) -> int:
    """Closed form: tick 0 primes both filters at -v (product +v^2 into a mean at 0), then the product is
    -v^2, so m_k = -v^2 + (m_0 + v^2) r^k with r = T / (T + dt); the condition holds from the first k with
    m_k < -floor^2 and fires sign_flip_time_s later."""
    v2, f2, window = speed_m_s**2, config.polarity_floor_m_s**2, config.polarity_window_s
    m0 = v2 * DT / (window + DT)
    r = window / (window + DT)
    crossing = math.floor(math.log((v2 - f2) / (m0 + v2)) / math.log(r)) + 1
    return crossing + round(config.sign_flip_time_s / DT)


@pytest.mark.parametrize("pair", sorted(PAIRS))
def test_fires_at_its_bound_above_the_floor_and_never_below_it(pair: str) -> None:
    floor = UNFILTERED.polarity_floor_m_s
    for speed in (1.01 * floor, 2.0 * floor, 10.0 * floor):
        fired, _ = _ramp(UNFILTERED, pair, speed, 20_000)
        assert fired == _expected_fire_tick(UNFILTERED, speed), speed
    # just below the floor the mean settles at -v^2 > -floor^2: never
    assert _ramp(UNFILTERED, pair, 0.99 * floor, 20_000)[0] is None
    # the condition must hold for sign_flip_time_s: polarity restored one tick before it fires, no trip
    fire = _expected_fire_tick(UNFILTERED, 2.0 * floor)
    restored = fire - round(UNFILTERED.sign_flip_time_s / DT) + 1
    assert _ramp(UNFILTERED, pair, 2.0 * floor, restored + 5, flipped_until=restored)[0] is None
    assert SensorPolarity.ACTION is Action.TRIP


def test_a_slow_flip_below_the_sign_floor_is_caught_where_the_sign_check_is_blind() -> None:
    """A base mat swaying at 1.5 mm/s peak (below sign_flip_floor_m_s, 2 mm/s) with ydot_b negated."""
    polarity, sign = SensorPolarity(SENSORS), SensorSignFlip(SENSORS)
    health = TickHealth()
    w = 2 * math.pi * 1.0
    amplitude = 0.0015
    fired = {}
    for k in range(5000):
        t = k * DT
        health.meas.base_displacement_m = amplitude / w * math.sin(w * t)
        health.meas.base_velocity_m_s = -amplitude * math.cos(w * t)
        for det in (polarity, sign):
            if det.NAME not in fired and det.update(t, DT, health):
                fired[det.NAME] = t
    assert "sensor_sign_flip" not in fired
    # mean of the product -> -A^2 / 2 = -1.1e-6 m^2/s^2, below -floor^2 = -2.5e-7 within about a window
    assert fired["sensor_polarity"] < SENSORS.polarity_window_s + SENSORS.sign_flip_time_s + 0.1


@pytest.mark.parametrize("amplitude_m_s", [0.001, 0.01, 0.3])
@pytest.mark.parametrize("frequency_hz", [0.5, 2.0, 12.0])
def test_quiet_for_sound_pairs_in_motion(amplitude_m_s: float, frequency_hz: float) -> None:
    det = SensorPolarity(SENSORS)
    health = TickHealth()
    w = 2 * math.pi * frequency_hz
    for k in range(5000):
        t = k * DT
        for disp, vel in PAIRS.values():
            setattr(health.meas, disp, amplitude_m_s / w * math.sin(w * t))
            setattr(health.meas, vel, amplitude_m_s * math.cos(w * t))
        assert not det.update(t, DT, health), t
    assert det.mean_m2_s2(0) > 0.0 and det.mean_m2_s2(1) > 0.0


def test_quiet_on_the_profiles_sensor_noise_at_rest_with_margin() -> None:
    """The rig's own sensor model at rest for 60 s at 500 Hz: the running mean stays within a fifth of the threshold."""
    det = SensorPolarity(SENSORS)
    read = _noisy_channels(seed=7)
    health = TickHealth()
    worst = 0.0
    for k in range(30_000):
        read(health)
        assert not det.update(k * RIG_DT, RIG_DT, health)
        worst = min(worst, det.mean_m2_s2(0), det.mean_m2_s2(1))
    assert worst > 0.2 * det.threshold_m2_s2, worst


def test_a_product_not_finite_fires_and_reset_clears() -> None:
    det = SensorPolarity(UNFILTERED)
    health = TickHealth()
    health.meas.base_velocity_m_s = math.nan
    fired = [det.update(k * DT, DT, health) for k in range(round(UNFILTERED.sign_flip_time_s / DT) + 3)]
    assert fired[-1]
    det.reset()
    health.meas.base_velocity_m_s = 0.0
    assert det.mean_m2_s2(1) == 0.0 and not det.update(1.0, DT, health)


def test_the_supervisor_trips_sensor_polarity_and_names_the_pair() -> None:
    config = SafetyConfig(sensors=UNFILTERED)
    supervisor, health = armed_supervisor(config)
    speed = 2.0 * UNFILTERED.polarity_floor_m_s
    for k in range(1, 5000):
        health.meas.base_displacement_m = speed * k * DT
        health.meas.base_velocity_m_s = -speed * (1.0 + 1e-3 * (k % 3))  # a live sensor's last bits move
        health.base_fresh = True
        command = supervisor.update(k * DT, DT, health, 0.0)
        if command.trip_reason:
            break
    assert command.trip_reason == "sensor_polarity"
    assert "y_b/ydot_b" in supervisor.trip_detail
    assert isinstance(supervisor, Supervisor) and supervisor.state is State.TRIPPED


@pytest.mark.parametrize("after_reset", [False, True])
def test_the_first_product_is_averaged_into_a_mean_at_zero_also_after_a_reset(after_reset: bool) -> None:
    """The running means start primed at zero (at construction and after a reset): the first product, +v^2
    while both filters prime at the same velocity, moves the mean by ``dt / (window + dt)`` of it; a mean
    that took its first input as is would start at v^2 (or at -v^2 for a flipped pair, and fire early)."""
    speed = 0.01
    det = SensorPolarity(UNFILTERED)
    health = TickHealth()
    if after_reset:
        health.meas.base_displacement_m, health.meas.base_velocity_m_s = 0.003, 0.2
        det.update(0.0, DT, health)
        det.reset()
    health.meas.base_displacement_m, health.meas.base_velocity_m_s = 0.0, speed
    det.update(DT, DT, health)
    expected = speed**2 * DT / (UNFILTERED.polarity_window_s + DT)
    assert det.mean_m2_s2(1) == pytest.approx(expected, rel=1e-9)


def test_a_mean_exactly_on_the_threshold_is_not_a_fault() -> None:
    """The condition is ``mean < -floor^2``: a mean that sits exactly on it holds (the boundary, to the bit)."""
    det = SensorPolarity(SENSORS)
    floor = SENSORS.polarity_floor_m_s
    det._deriv[0].y, det._vel[0].y = floor, -floor  # the product is exactly the threshold ...
    det._mean[0].reset(det.threshold_m2_s2, True)  # ... and so is the mean: it stays there
    det._dt = DT
    assert det.threshold_m2_s2 == -floor * floor
    assert not det._bad(0)
    det._mean[0].reset(math.nextafter(det.threshold_m2_s2, -math.inf), True)
    det._deriv[0].y = math.nextafter(floor, math.inf)
    assert det._bad(0)


def test_the_detail_word_for_word() -> None:
    det = SensorPolarity(SENSORS)
    det._pair = 1
    det._mean[1].reset(-2.5e-6, True)
    floor = SENSORS.polarity_floor_m_s
    assert det.detail(TickHealth()) == (
        "polarity of y_b/ydot_b: running mean of dy_b/dt * ydot_b (filtered) = -2.5e-06 m^2/s^2, "
        f"expected at least {-floor * floor:.6g} m^2/s^2 "
        f"(-({floor:g} m/s)^2): the velocity moves against the displacement (a polarity or wiring fault the "
        "sign check's floor hides)"
    )
