"""A refused request and a reset, as the operator and the event log see them (mutation survivors)."""

from __future__ import annotations

import pytest

from harness.safety.config import SafetyConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import IllegalTransition, Lifecycle, Request, State
from harness.safety.supervisor import Supervisor


def test_a_refused_request_names_itself_its_state_and_what_is_legal_there() -> None:
    lifecycle = Lifecycle()
    with pytest.raises(IllegalTransition) as refused:
        lifecycle.start(0.0)
    assert refused.value.state is State.IDLE and refused.value.request is Request.START
    assert str(refused.value) == "request START refused in state IDLE; legal requests there: ARM, TRIP"
    lifecycle.arm(0.0)
    with pytest.raises(IllegalTransition) as refused:
        lifecycle.reset(0.1)
    assert str(refused.value) == "request RESET refused in state ARMED; legal requests there: START, STOP, TRIP"


def test_a_reset_is_stamped_with_its_time_in_the_event_and_the_state() -> None:
    supervisor = Supervisor(SafetyConfig(), period_s=0.002)
    health = TickHealth()
    supervisor.trip(1.0, "operator_trip", "test")
    supervisor.events.drain(lambda *event: None)
    supervisor.reset(2.5, health)
    events: list[tuple] = []
    supervisor.events.drain(lambda *event: events.append(event))
    assert (2.5, "state", "IDLE", "TRIPPED -> IDLE: reset") in events
    assert supervisor.lifecycle.state is State.IDLE and supervisor.lifecycle.entered_s == 2.5
    assert supervisor.command.t == 2.5 and not supervisor.command.enable and supervisor.command.force_N == 0.0
