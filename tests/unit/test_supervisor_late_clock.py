"""The supervisor far from t = 0, as a long run's clock is (mutation survivors that t near 0 hid):
the stopping ramp's length, the first command after a re-arm, the interlocks' times and words."""

from __future__ import annotations

import dataclasses

import pytest

from harness.safety.config import SafetyConfig, SensorConfig
from harness.safety.health import TickHealth
from harness.safety.interlocks import ForceRateLimit
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor

DT = 0.002
T0 = 100.0  # a run's clock late in a long session


def _running(t: float) -> tuple[Supervisor, TickHealth]:
    config = dataclasses.replace(SafetyConfig(), sensors=SensorConfig(stuck_samples=10**6))
    supervisor = Supervisor(config, period_s=DT)
    health = TickHealth()
    health.drive_ready = health.pressure_ok = True
    health.e2e_ok = True
    health.table_age_s = health.base_age_s = 0.001
    health.actuator_status_age_s = 0.001
    health.estop_panel_age_s = 0.01
    supervisor.arm(t, health)
    supervisor.start(t)
    return supervisor, health


def _tick(supervisor: Supervisor, health: TickHealth, t: float, raw_N: float):
    health.table_fresh = health.base_fresh = True
    health.measured_force_N = supervisor.command.force_N
    return supervisor.update(t, DT, health, raw_N)


def test_the_stopping_ramp_lasts_its_length_whatever_the_clock() -> None:
    supervisor, health = _running(T0)
    t = T0
    for _ in range(50):
        t += DT
        _tick(supervisor, health, t, 1000.0)
    supervisor.stop(t)
    stopped_at = t
    ramp = supervisor.config.run.stopping_ramp_s
    while supervisor.state is State.STOPPING:
        t += DT
        _tick(supervisor, health, t, 0.0)  # the controller asks for nothing: the ramp still takes its time
        assert t - stopped_at < ramp + 3 * DT, "the ramp ends on time"
    assert supervisor.state is State.DONE and t - stopped_at >= ramp - DT, "and not before its length"


def test_the_first_command_after_a_rearm_is_rate_limited_from_zero() -> None:
    supervisor, health = _running(T0)
    _tick(supervisor, health, T0 + DT, 50_000.0)
    supervisor.trip(T0 + 2 * DT, "operator_trip", "test")
    supervisor.reset(T0 + 3 * DT, health)
    supervisor.arm(T0 + 4 * DT, health)
    supervisor.start(T0 + 4 * DT)
    command = _tick(supervisor, health, T0 + 5 * DT, 50_000.0)
    assert command.force_N == pytest.approx(supervisor.config.force.max_force_rate_N_per_s * DT, abs=1e-9)


def test_an_interlocks_event_carries_the_ticks_time() -> None:
    supervisor, health = _running(T0)
    soft = supervisor.config.stroke.soft_limit_m
    health.meas.base_displacement_m = soft + 0.25 * supervisor.config.stroke.fade_band_m  # in the fade band
    t = T0 + DT
    _tick(supervisor, health, t, 500.0)  # outward: faded
    events: list[tuple] = []
    supervisor.events.drain(lambda *event: events.append(event))
    fades = [event for event in events if event[2] == "stroke_soft"]
    assert fades and fades[0][0] == t and fades[0][1] == "interlock"


def test_the_rate_limits_words_give_the_demanded_rate_from_the_previous_force() -> None:
    limit = ForceRateLimit(SafetyConfig().force)
    assert limit.detail(3000.0, 1000.0, 0.002) == (
        f"demanded 1e+06 N/s (1000 N to 3000 N in 2 ms), limited to +/-{limit.max_rate_N_per_s:g} N/s "
        "(safety.force.max_force_rate_N_per_s)"
    )
