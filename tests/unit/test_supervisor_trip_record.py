"""What a trip leaves behind: its time, reason and detail in the events and the latch, its
counters over several trips, and the E-stop and operator trip watched while idle (mutation survivors)."""

from __future__ import annotations

import dataclasses

import pytest

from harness.safety.checks import CHECK_NAMES, bit
from harness.safety.config import SafetyConfig
from harness.safety.health import TickHealth
from harness.safety.interlocks import StrokeSoftFade
from harness.safety.lifecycle import Lifecycle, State
from harness.safety.supervisor import Supervisor

PERIOD_S = 0.002


def _drained(supervisor: Supervisor) -> list[tuple]:
    events: list[tuple] = []
    supervisor.events.drain(lambda *event: events.append(event))
    return events


@pytest.mark.parametrize(("flag", "reason"), [("estop", "estop"), ("operator_trip", "operator_trip")])
def test_an_estop_or_an_operator_trip_while_idle_trips_at_once(flag: str, reason: str) -> None:
    supervisor = Supervisor(SafetyConfig(), period_s=PERIOD_S)
    health = TickHealth()
    setattr(health, flag, True)
    command = supervisor.update(3.25, PERIOD_S, health, 0.0)
    assert command.state is State.TRIPPED and not command.enable and command.force_N == 0.0
    assert supervisor.lifecycle.trip_reason == reason and supervisor.lifecycle.entered_s == 3.25
    detector = supervisor._estop if flag == "estop" else supervisor._operator_trip
    assert supervisor.lifecycle.trip_detail == detector.detail(health) != ""
    events = _drained(supervisor)
    assert (3.25, "fault", reason, detector.detail(health)) in events
    assert (3.25, "state", "TRIPPED", f"IDLE -> TRIPPED: {reason}") in events


def test_each_trip_counts_and_flags_its_check_and_stamps_its_time() -> None:
    supervisor = Supervisor(SafetyConfig(), period_s=PERIOD_S)
    health = TickHealth()
    slot = CHECK_NAMES.index("operator_trip")
    for k in range(2):
        t = 1.0 + k
        command = supervisor.trip(t, "operator_trip", f"pressed {k}")
        assert command.t == t and command.state is State.TRIPPED
        assert command.acted == bit("operator_trip")
        assert supervisor.lifecycle.entered_s == t and supervisor.lifecycle.trip_detail == f"pressed {k}"
        assert (t, "fault", "operator_trip", f"pressed {k}") in _drained(supervisor)
        supervisor.reset(t + 0.5, health)
        assert supervisor.lifecycle.trip_detail == "" and supervisor.lifecycle.trip_reason == ""
    assert supervisor.act_ticks[slot] == 2 and supervisor.act_counts() == {"operator_trip": 2}


def test_a_trip_keeps_what_else_acted_in_its_tick() -> None:
    supervisor = Supervisor(SafetyConfig(), period_s=PERIOD_S)
    supervisor.command.acted = bit("force_clamp")  # the clamp acted earlier in this tick
    supervisor.trip(1.0, "operator_trip", "pressed")
    assert supervisor.command.acted == bit("force_clamp") | bit("operator_trip")


def test_the_lifecycle_clears_the_trips_detail_on_reset() -> None:
    lifecycle = Lifecycle()
    assert lifecycle.trip(0.5, "estop", "the panel's button")
    assert lifecycle.trip_detail == "the panel's button"
    lifecycle.reset(1.0)
    assert (lifecycle.state, lifecycle.trip_reason, lifecycle.trip_detail, lifecycle.entered_s) == (State.IDLE, "", "", 1.0)


def test_the_soft_fade_scales_nothing_inside_the_soft_limit_and_says_so() -> None:
    fade = StrokeSoftFade(SafetyConfig().stroke)
    soft, band = fade.soft_m, fade.band_m
    assert fade.scale(0.0) == fade.scale(soft) == 1.0
    assert fade.scale(soft + band / 4) == pytest.approx(0.75)
    assert fade.detail(1000.0, soft / 2).endswith("outward force 1000 N faded to 1000 N")


def _running(config: SafetyConfig | None = None) -> tuple[Supervisor, TickHealth]:
    supervisor = Supervisor(config or SafetyConfig(), period_s=PERIOD_S)
    health = TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    _drained(supervisor)
    return supervisor, health


@pytest.mark.parametrize(("velocity", "reason"), [(0.0, "stroke_hard"), (0.5, "stroke_predictive")])
def test_a_stroke_trip_says_where_the_base_mat_was_in_the_latch_and_its_event(velocity: float, reason: str) -> None:
    supervisor, health = _running()
    hard = supervisor.config.stroke.hard_limit_m
    x_b = hard * (1.01 if reason == "stroke_hard" else 0.9)
    health.meas.base_displacement_m, health.meas.base_velocity_m_s = x_b, velocity
    assert supervisor.update(1.5, PERIOD_S, health, 0.0).trip_reason == reason
    detail = supervisor.lifecycle.trip_detail
    assert f"{x_b:.6g} m" in detail and f"{hard:g} m" in detail
    assert (1.5, "fault", reason, detail) in _drained(supervisor)


def test_a_setpoint_not_finite_trips_at_the_ticks_own_time() -> None:
    supervisor, health = _running()
    command = supervisor.update(2.75, PERIOD_S, health, 100.0, setpoint_N=float("nan"))
    assert command.trip_reason == "controller_output" and supervisor.lifecycle.entered_s == 2.75
    assert (2.75, "fault", "controller_output", "controller setpoint not finite: nan N") in _drained(supervisor)


@pytest.mark.parametrize("action", ["safe_stop", "indicate"])
def test_a_check_that_does_not_trip_records_what_it_saw_in_its_event_and_a_safe_stop(action: str) -> None:
    """The force-tracking check set to act short of a trip (safety.force.tracking_action): its detail reads the tick's health."""
    config = SafetyConfig()
    config = dataclasses.replace(
        config, force=dataclasses.replace(config.force, tracking_action=action, actuator_time_constant_s=0.0),
        sensors=dataclasses.replace(config.sensors, stuck_samples=10**6),  # the still sensors are not the subject
    )
    supervisor, health = _running(config)
    t, faults = 0.0, []
    while not faults and t < 1.0:
        t += PERIOD_S
        health.measured_force_N = 2.0 * config.force.tracking_tolerance_N  # nothing commanded: the error is this force
        supervisor.update(t, PERIOD_S, health, 0.0)
        faults = [event for event in _drained(supervisor) if event[1] == "fault"]
    assert faults and faults[0][2] == "force_tracking"
    assert f"measured {health.measured_force_N:.6g} N" in faults[0][3]
    if action == "safe_stop":
        assert supervisor.state is State.STOPPING
        assert supervisor.stop_reason == "force_tracking" and supervisor.stop_detail == faults[0][3]
    else:
        assert supervisor.state is State.RUNNING and supervisor.stop_detail == ""
