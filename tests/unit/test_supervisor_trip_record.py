"""What a trip leaves behind: its time, reason and detail in the events and the latch, its
counters over several trips, and the E-stop and operator trip watched while idle (mutation survivors)."""

from __future__ import annotations

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
