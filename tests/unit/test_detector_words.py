"""What each detector tells the operator when it fires, checked whole: the channel, the numbers and the bound.

The event log, the console and the trip message show these lines, and the operator decides from
them what to fix; a detail that names the wrong channel or drops the bound is a safety defect of
its own. Each test drives one detector to fire and matches the whole line.
"""

from __future__ import annotations

import dataclasses
import math
import re

from harness.safety.config import RunConfig, SensorConfig
from harness.safety.health import TickHealth
from harness.safety.operator_detectors import HOST_TIMING_REMEDIES, LoopStall
from harness.safety.sensor_detectors import (
    CHANNELS,
    SensorInvalid,
    SensorJump,
    SensorSignFlip,
    SensorStale,
    SensorStuck,
)

DT = 0.001
SENSORS = SensorConfig()
NUMBER = r"([-+0-9.e]+)"


def test_sensor_invalid_names_the_channel_its_value_and_its_range() -> None:
    det = SensorInvalid(SENSORS)
    health = TickHealth()
    assert det.detail(health) == "all measurements valid" and det.present(health) == ""
    health.meas.base_velocity_m_s = math.inf
    assert det.update(0.0, DT, health)
    limit = det.limits[CHANNELS.index("ydot_b")]
    assert det.detail(health) == f"ydot_b = inf, expected finite and within +/-{limit:g}"
    assert det.present(health) == det.detail(health)
    health.meas.base_velocity_m_s = 0.0
    health.meas.table_displacement_m = 1e3
    det.update(DT, DT, health)
    assert det.detail(health) == f"x_0 = 1000.0, expected finite and within +/-{det.limits[0]:g}"


def test_sensor_stale_gives_both_ages_and_the_limit() -> None:
    det = SensorStale(SENSORS)
    health = TickHealth(table_age_s=0.0251, base_age_s=0.0005)
    assert det.update(0.0, DT, health)
    assert det.detail(health) == (
        f"table sensor frame age 25.100 ms, base-mat 0.500 ms, expected 0 <= age <= {det.max_age_s * 1e3:.3f} ms "
        "(judged after polling the bus)"
    )
    assert det.present(health) == det.detail(health)
    assert det.present(TickHealth()) == ""


def test_sensor_jump_names_the_channel_the_step_and_the_limit() -> None:
    det = SensorJump(SENSORS)
    health = TickHealth()
    health.table_fresh = health.base_fresh = True
    det.update(0.0, DT, health)
    limit = det.limits[CHANNELS.index("y_b")]
    health.meas.base_displacement_m = 2 * limit
    assert det.update(DT, DT, health)
    assert det.detail(health) == f"y_b changed by {2 * limit:.6g} in one sample, expected at most {limit:g}"


def test_sensor_stuck_names_the_channel_its_value_the_count_and_the_remedy() -> None:
    det = SensorStuck(SENSORS)
    health = TickHealth()
    health.table_fresh = health.base_fresh = True
    k = 0
    while not det.update(k * DT, DT, health):
        health.meas.table_displacement_m = 0.001 * k  # the table's displacement moves; the other channels do not
        k += 1
        assert k <= SENSORS.stuck_samples + 1
    detail = det.detail(health)
    found = re.fullmatch(
        r"(\S+) = (\S+) repeated to the bit (\d+) times in a row, expected fewer than (\d+) \(a healthy sensor's "
        r"noise moves its last bits; a sensor whose noise is below its quantization step needs a larger "
        r"safety\.sensors\.stuck_samples: docs/SAFETY\.md\)",
        detail,
    )
    assert found, detail
    channel, value, repeats, samples = found.groups()
    assert channel in ("xdot_0", "y_b", "ydot_b") and float(value) == 0.0
    assert int(repeats) == int(samples) == SENSORS.stuck_samples


def test_sensor_sign_flip_names_the_pair_both_filtered_values_and_how_long() -> None:
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
    det = SensorSignFlip(config)
    health = TickHealth()
    speed = 0.1
    k = 0
    while True:
        health.meas.base_displacement_m = speed * k * DT
        health.meas.base_velocity_m_s = -speed if k >= 10 else speed
        if det.update(k * DT, DT, health):
            break
        k += 1
        assert k < 1000, "the flip must be caught"
    detail = det.detail(health)
    found = re.fullmatch(
        rf"sign flip on y_b/ydot_b: dy_b/dt filtered = {NUMBER} m/s, ydot_b filtered = {NUMBER} m/s, opposite signs "
        rf"above {NUMBER} m/s for {NUMBER} ms \(limit {NUMBER} ms\); expected the same sign \(polarity or wiring "
        r"fault: the controller would push the wrong way\)",
        detail,
    )
    assert found, detail
    derivative, velocity, floor, held_ms, limit_ms = (float(g) for g in found.groups())
    assert math.isclose(derivative, speed, rel_tol=1e-3) and math.isclose(velocity, -speed, rel_tol=1e-3)
    assert floor == config.sign_flip_floor_m_s
    assert math.isclose(limit_ms, config.sign_flip_time_s * 1e3, abs_tol=0.05)
    assert limit_ms <= held_ms <= limit_ms + 2 * DT * 1e3, "held as long as the bound, give or take a tick"


def test_loop_stall_gives_the_gap_the_missed_periods_the_budget_and_the_remedies() -> None:
    det = LoopStall(RunConfig(max_stall_s=0.02))
    health = TickHealth(stall_s=0.0456, missed_periods=22)
    assert det.update(0.0, DT, health)
    assert det.detail(health) == (
        "the loop went 45.6 ms without a command (22 missed periods), expected at most 20.0 ms (the stall budget): "
        "the host did not run the loop in time; " + HOST_TIMING_REMEDIES
    )
    assert det.present(health) == "", "a stall is over once the loop runs again"
    assert not det.update(0.0, DT, TickHealth(stall_s=0.02, missed_periods=9)), "on the budget: ridden through"
