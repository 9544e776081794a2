"""Edges of the safety layer and the tick that the third mutation run found without a test.

Each test states a behaviour a maintainer could break with a one-character change (a
comparison, a loop's ``continue``, a time stamp handed on): the boundaries of the stroke
fade, the ring of the window counter, the stopping ramp's end, a jump on the base mat while
the table is silent, the time stamps of trips and events, the counters of the trip outputs.
"""

from __future__ import annotations

import dataclasses
import math
import re

import numpy as np
import pytest

from harness.errors import ProfileError
from harness.loop.status import LoopStatus
from harness.loop.tick import ControlTick
from harness.loop.trip_outputs import TripOutputs
from harness.safety.actuator_detectors import CompensationFault, ForceTracking
from harness.safety.checks import CHECK_NAMES, CHECKS_BY_BIT, _in_bit_order, bit
from harness.safety.config import (
    TRIP_CLASS_OF,
    TRIP_CLASSES,
    ForceConfig,
    SafetyConfig,
    SensorConfig,
    StrokeConfig,
    TripActionsConfig,
    check_config,
)
from harness.safety.detector_base import TIME_EPS_S, LowPass, Persistence, WindowCounter
from harness.safety.events import Action, EventRing
from harness.safety.health import TickHealth
from harness.safety.interlocks import ForceClamp, ForceRateLimit, StrokeHardLimit, StrokePredictiveLimit, StrokeSoftFade
from harness.safety.lifecycle import Lifecycle, State
from harness.safety.operator_detectors import EStopLost
from harness.safety.prearm import pre_arm_failures
from harness.safety.sensor_detectors import SensorDisagree, SensorJump, SensorSignFlip, SensorStuck
from harness.safety.supervisor import Supervisor
from harness.safety.table_record import NO_RECORD, TableRecordCheck
from tests.unit.test_control_tick import PERIOD_S, Bench
from tests.unit.test_prearm_words import _healthy
from tests.unit.test_trip_actions import BOTH, EVERY, RecordingWriter, TableStop

STROKE = StrokeConfig()
#: A fade band wider than the soft-to-hard gap: a configuration check_config refuses.
BAND_PAST_HARD_LIMIT = StrokeConfig(soft_limit_m=0.07, fade_band_m=0.01, hard_limit_m=0.075)
SENSORS = SensorConfig()
DT = 0.001


# ------------------------------------------------------------------ the stroke fade and its neighbours
def test_no_force_beyond_the_soft_limit_is_not_a_fade() -> None:
    fade = StrokeSoftFade(STROKE)
    x_b = STROKE.soft_limit_m + 0.5 * STROKE.fade_band_m
    assert fade.apply(0.0, x_b) == 0.0
    assert fade.acted is False, "nothing was faded, so no stroke_soft event is due"


def test_a_small_outward_force_beyond_the_soft_limit_is_faded_too() -> None:
    fade = StrokeSoftFade(STROKE)
    x_b = STROKE.soft_limit_m + 0.5 * STROKE.fade_band_m
    for force_N in (10.0, -10.0):  # force * x_b well below 1 N m: still outward
        assert fade.apply(force_N, math.copysign(x_b, force_N)) == pytest.approx(0.5 * force_N)
        assert fade.acted is True


def test_an_inward_force_leaves_the_fade_not_acting() -> None:
    fade = StrokeSoftFade(STROKE)
    x_b = STROKE.soft_limit_m + 0.5 * STROKE.fade_band_m
    fade.apply(100.0, x_b)
    assert fade.acted is True
    assert fade.apply(-100.0, x_b) == -100.0
    assert fade.acted is False


def test_the_clamp_and_the_rate_limit_say_false_when_they_did_not_act() -> None:
    force = ForceConfig()
    clamp, rate = ForceClamp(force), ForceRateLimit(force)
    clamp.apply(2.0 * force.max_force_N)
    rate.apply(force.max_force_rate_N_per_s, 0.0, 0.01)
    assert clamp.acted is True and rate.acted is True
    clamp.apply(0.0)
    rate.apply(0.0, 0.0, 0.01)
    assert clamp.acted is False and rate.acted is False


# ------------------------------------------------------------------ the window counter
def test_the_window_counter_counts_the_events_of_a_ring_not_yet_full() -> None:
    counter = WindowCounter(max_count=3, window_s=1.0)
    counter.update(4.0, 0)  # primes
    counter.update(5.0, 2)  # two events at t = 5 s; two slots of four still empty
    assert counter.count(5.0) == 2
    assert counter.count(5.5) == 2
    assert counter.count(6.5) == 0


def test_an_event_exactly_one_window_old_still_counts() -> None:
    window_s = 0.5
    counter = WindowCounter(max_count=2, window_s=window_s)
    counter.update(-1.0, 0)
    counter.update(0.0, 1)
    assert counter.count(window_s + TIME_EPS_S) == 1, "on the window's edge, within the clock tolerance"
    assert counter.count(window_s + 10 * TIME_EPS_S) == 0


# ------------------------------------------------------------------ sensor detectors
def test_a_jump_on_the_base_mat_is_caught_while_the_table_sends_nothing() -> None:
    det = SensorJump(SENSORS)
    health = TickHealth()
    assert det.update(0.0, DT, health) is False  # primes every channel
    health.table_fresh = False  # the table's frame is late this tick; the base mat's arrived
    health.meas.base_displacement_m = 2.0 * SENSORS.jump_limit_m
    assert det.update(DT, DT, health) is True
    assert det.detail(health).startswith("y_b changed by")


def test_a_quiet_jump_check_answers_false() -> None:
    det = SensorJump(SENSORS)
    health = TickHealth()
    assert det.update(0.0, DT, health) is False
    assert det.update(DT, DT, health) is False


def test_the_sign_flip_message_gives_its_times_in_whole_milliseconds_at_a_1_ms_tick() -> None:
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9, sign_flip_time_s=0.2)
    det = SensorSignFlip(config)
    health = TickHealth()
    speed = 0.1
    for k in range(2000):
        health.meas.base_displacement_m = speed * k * DT
        health.meas.base_velocity_m_s = -speed if k >= 10 else speed
        if det.update(k * DT, DT, health):
            break
    else:
        pytest.fail("the flip must be caught")
    found = re.search(r"for (\S+) ms \(limit (\S+) ms\)", det.detail(health))
    assert found, det.detail(health)
    held_ms, limit_ms = (float(g) for g in found.groups())
    assert limit_ms == 200.0
    assert 200.0 <= held_ms <= 202.0 and held_ms == round(held_ms), "held a whole number of 1 ms ticks"


# ------------------------------------------------------------------ lifecycle and supervisor
def test_a_trip_without_a_detail_latches_an_empty_one() -> None:
    lifecycle = Lifecycle()
    assert (lifecycle.state, lifecycle.trip_reason, lifecycle.trip_detail, lifecycle.entered_s) == (State.IDLE, "", "", 0.0)
    assert lifecycle.trip(1.0, "estop") is True
    assert (lifecycle.state, lifecycle.trip_reason, lifecycle.trip_detail) == (State.TRIPPED, "estop", "")


def _running(config: SafetyConfig | None = None) -> tuple[Supervisor, TickHealth]:
    supervisor = Supervisor(config or SafetyConfig())
    health = TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    return supervisor, health


def _trip_events(supervisor: Supervisor) -> list[tuple[float, str]]:
    events: list[tuple[float, str, str, str]] = []
    supervisor.events.drain(lambda *event: events.append(event))
    return [(t, name) for t, kind, name, _ in events if str(kind).lower().endswith("fault")]


def test_a_controller_output_trip_is_stamped_with_the_ticks_time() -> None:
    supervisor, health = _running()
    supervisor.update(0.25, 0.004, health, 0.0)
    command = supervisor.update(0.254, 0.004, health, math.nan)
    assert command.trip_reason == "controller_output"
    assert _trip_events(supervisor) == [(0.254, "controller_output")]
    assert supervisor.lifecycle.entered_s == 0.254


def test_a_hard_stroke_trip_is_stamped_with_the_ticks_time() -> None:
    supervisor, health = _running()
    health.meas.base_displacement_m = 1.01 * STROKE.hard_limit_m
    command = supervisor.update(0.5, 0.004, health, 0.0)
    assert command.trip_reason == "stroke_hard"
    assert _trip_events(supervisor) == [(0.5, "stroke_hard")]
    assert supervisor.lifecycle.entered_s == 0.5


def test_with_zero_demand_the_stopping_ramp_ends_within_the_clock_tolerance_of_its_length() -> None:
    supervisor, health = _running()
    supervisor.update(0.004, 0.004, health, 0.0)
    supervisor.stop(0.004)
    ramp_s = supervisor.config.run.stopping_ramp_s
    supervisor.update(0.004 + 0.5 * ramp_s, 0.5 * ramp_s, health, 0.0)
    assert supervisor.state is State.STOPPING, "zero force, but the ramp's time is not up"
    # a tick time that lands a rounding error short of the ramp's end: the ramp is done there
    command = supervisor.update(0.004 + ramp_s - 0.5 * TIME_EPS_S, 0.5 * ramp_s, health, 0.0)
    assert supervisor.state is State.DONE and command.force_N == 0.0 and not command.enable


# ------------------------------------------------------------------ the tick and its trip outputs
def test_a_safe_stop_after_a_trips_table_stop_counts_both() -> None:
    table = TableStop()
    outputs = TripOutputs(RecordingWriter(), BOTH, EVERY, table)
    outputs.update(State.TRIPPED, "stroke_hard", 0.0)  # the trip stops the table: one
    outputs.update(State.IDLE, "", 0.5)
    outputs.stop_the_table(1.0)  # a later safe stop (table_record_mismatch) stops it again: two
    assert outputs.table_stops == 2 and table.calls == [0.0, 1.0]


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def test_a_fresh_tick_has_shown_no_event(bench) -> None:
    assert bench.tick.last_event == ""


def test_an_exception_in_recording_trips_at_the_ticks_time_naming_the_exception(bench) -> None:
    bench.run_until_running()
    events: list[tuple[float, str, str, str]] = []

    class BrokenRecorder:
        def record_row(self, row) -> None:
            raise OSError("disk gone")

        def record_event(self, t: float, kind: str, name: str, detail: str) -> None:
            events.append((t, kind, name, detail))

    bench.tick.recorder = BrokenRecorder()
    bench.publish()
    t = bench.t
    command = bench.tick.run(t, PERIOD_S, t)
    assert command.trip_reason == "tick_exception"
    assert "disk gone" in bench.supervisor.lifecycle.trip_detail and "OSError" in bench.supervisor.lifecycle.trip_detail
    assert bench.supervisor.lifecycle.entered_s == t


def test_each_event_reaches_the_recorder_and_the_console_with_its_time(bench) -> None:
    recorded: list[tuple[float, str, str, str]] = []

    class Recorder:
        def record_row(self, row) -> None:
            pass

        def record_event(self, t: float, kind: str, name: str, detail: str) -> None:
            recorded.append((t, kind, name, detail))

    bench.tick = ControlTick(bench.link, bench.controller, bench.tick.estimator, bench.supervisor, Recorder(),
                             heartbeat_every=1)
    with LoopStatus() as status:
        bench.tick.attach_status(status)
        bench.run_until_running()
        shown = status.recent_events()
    assert recorded, "arming and starting are events"
    assert all(isinstance(t, float) and 0.0 <= t <= bench.t for t, *_ in recorded)
    armed = next(event for event in recorded if event[2] == "ARMED")
    assert armed[0] == pytest.approx(3 * PERIOD_S)
    assert shown and all(line.strip() for line in shown), "the console's event lines carry the text"
    assert bench.tick.last_event == shown[-1]


# ------------------------------------------------------------------ pre-arm: ages on their bounds, words, all failures
def test_ages_exactly_on_their_bounds_arm() -> None:
    config = SafetyConfig()
    health = _healthy()
    health.table_age_s = health.base_age_s = config.sensors.max_sensor_age_s
    health.actuator_status_age_s = config.actuator.max_status_age_s
    health.estop_panel_age_s = config.estop.max_panel_age_s
    assert pre_arm_failures(config, health) == ()
    lost = EStopLost(config.estop)
    assert lost.update(0.0, 0.0, health) is False, "a panel frame exactly max_panel_age_s old is not lost"


def test_the_refusals_give_large_ages_in_milliseconds() -> None:
    config = SafetyConfig()
    health = _healthy()
    health.base_age_s = 0.5
    health.estop_panel_age_s = 0.5
    failed = pre_arm_failures(config, health)
    assert failed[0].startswith("sensors_fresh: table age 1.00 ms, base age 500.00 ms,")
    assert failed[1].startswith("estop_panel_live: newest E-stop panel frame 500.0 ms old,")


def test_a_refusal_lists_a_configuration_problem_with_the_sensor_failures_after_it() -> None:
    config = dataclasses.replace(SafetyConfig(), stroke=BAND_PAST_HARD_LIMIT)
    assert check_config(config), "the fade band reaches past the hard limit"
    health = _healthy()
    health.e2e_ok = False
    names = [line.split(":")[0] for line in pre_arm_failures(config, health)]
    assert names[0] == "config" and names[-1] == "e2e_ok"


# ------------------------------------------------------------------ the supervisor's command outside a run
def test_a_new_supervisor_commands_nothing_until_its_first_tick() -> None:
    command = Supervisor(SafetyConfig()).command
    assert (command.t, command.force_N, command.enable, command.state, command.trip_reason) == (
        0.0, 0.0, False, State.IDLE, "")


def test_an_idle_tick_stamps_the_command_with_its_time() -> None:
    supervisor = Supervisor(SafetyConfig())
    command = supervisor.update(1.25, 0.004, TickHealth(), 0.0)
    assert (command.t, command.enable, command.state) == (1.25, False, State.IDLE)


def test_arming_stamps_the_state_and_leaves_no_trip_reason_or_stop_behind() -> None:
    supervisor, health = _running()
    supervisor.stop(0.1, "operator")
    supervisor.stop_reason, supervisor.stop_detail = "operator_stop", "the operator asked"
    supervisor.update(0.2 + supervisor.config.run.stopping_ramp_s, 0.004, health, 0.0)
    assert supervisor.state is State.DONE
    supervisor.reset(2.0, health)
    supervisor.arm(2.5, health)
    assert supervisor.lifecycle.entered_s == 2.5
    assert (supervisor.stop_reason, supervisor.stop_detail) == ("", "")
    assert supervisor.command.trip_reason == "" and supervisor.command.state is State.ARMED


# ------------------------------------------------------------------ actuator checks
def test_a_reset_force_tracker_expects_zero_force() -> None:
    tracker = ForceTracking(ForceConfig(actuator_time_constant_s=0.0))
    tracker.command_N = 2_000.0
    tracker.update(0.0, 0.004, TickHealth())
    assert tracker.expected_N() == 2_000.0
    tracker.reset()
    assert tracker.expected_N() == 0.0


def test_compensation_fault_is_still_present_only_while_the_state_is_not_finite() -> None:
    detector = CompensationFault(ForceConfig())
    health = TickHealth()
    health.compensation_pinned = True
    health.compensation_value = 5.0
    assert detector.present(health) == "", "a pinned parameter cannot be judged from one sample"
    health.compensation_diverged = True
    health.compensation_value = math.nan
    assert detector.present(health) == detector.detail(health)
    assert detector.present(health).startswith("compensator state not finite (parameter nan)")


def test_each_trip_action_field_documents_the_checks_of_its_class() -> None:
    docs = {field.name: field.metadata["doc"] for field in dataclasses.fields(TripActionsConfig)}
    assert set(docs) == set(TRIP_CLASSES)
    for check, trip_class in TRIP_CLASS_OF.items():
        doc = docs[trip_class]
        named = check in doc or (check.startswith(("sensor_", "bus_")) and check.split("_")[0] + "_*" in doc)
        assert named, f"{trip_class}'s doc {doc!r} does not name {check}"


# ------------------------------------------------------------------ construction: what a new object says
def test_new_interlocks_have_not_acted() -> None:
    force = ForceConfig()
    for interlock in (StrokeHardLimit(STROKE), StrokePredictiveLimit(STROKE), ForceClamp(force), ForceRateLimit(force),
                      StrokeSoftFade(STROKE)):
        assert interlock.acted is False, type(interlock).__name__


def test_a_new_supervisor_has_no_stop_reason() -> None:
    supervisor = Supervisor(SafetyConfig())
    assert (supervisor.stop_reason, supervisor.stop_detail) == ("", "")


def test_an_inconsistent_configuration_is_refused_naming_the_safety_section_and_every_problem() -> None:
    config = dataclasses.replace(SafetyConfig(), stroke=BAND_PAST_HARD_LIMIT,
                                 trip_actions=TripActionsConfig(stroke=("disable", "disable")))
    problems = check_config(config)
    assert len(problems) == 2
    with pytest.raises(ProfileError) as refused:
        Supervisor(config)
    assert refused.value.key_path == "safety"
    assert str(refused.value) == "safety: inconsistent safety configuration: " + "; ".join(problems)


def test_the_stopping_ramp_event_says_how_long_and_what_follows() -> None:
    supervisor, health = _running()
    supervisor.update(0.004, 0.004, health, 1_000.0)
    supervisor.stop(0.004)
    supervisor.update(0.008, 0.004, health, 1_000.0)
    events: list[tuple[float, str, str, str]] = []
    supervisor.events.drain(lambda *event: events.append(event))
    ramp = [detail for _, _, name, detail in events if name == "stop_ramp"]
    assert ramp == [f"force ramps to zero over {supervisor.config.run.stopping_ramp_s:g} s (safety.run.stopping_ramp_s), "
                    "then the drive is disabled"]


def test_an_event_ring_of_one_keeps_the_newest_event() -> None:
    ring = EventRing(1)
    ring.push(1.0, "state", "ARMED", "first")
    ring.push(2.0, "state", "RUNNING", "second")
    drained: list[tuple[float, str, str, str]] = []
    assert ring.drain(lambda *event: drained.append(event)) == 1
    assert drained == [(2.0, "state", "RUNNING", "second")] and ring.overwritten == 1
    with pytest.raises(ValueError, match="event ring capacity is 0, expected at least 1"):
        EventRing(0)


def test_an_unknown_check_name_lists_the_known_ones() -> None:
    with pytest.raises(KeyError) as unknown:
        bit("stroke_sideways")
    assert "unknown safety check 'stroke_sideways'; expected one of " + ", ".join(CHECK_NAMES) in str(unknown.value)


def test_a_check_without_a_record_reports_why_and_has_no_gate() -> None:
    check = TableRecordCheck(0.02)
    assert math.isnan(check.gate_s)
    assert check.summary() == {"verdict": "off", "signal": "table velocity xdot_0", "reason": NO_RECORD}


def test_the_table_channels_are_judged_by_the_tables_freshness() -> None:
    for det in (SensorJump(SENSORS), SensorStuck(SENSORS)):
        health = TickHealth()
        det.update(0.0, DT, health)
        health.table_fresh = False  # the table's value is not a new sample, whatever it reads
        health.meas.table_displacement_m = 2.0 * SENSORS.jump_limit_m
        for k in range(1, SENSORS.stuck_samples + 2):
            health.meas.base_displacement_m = 1e-6 * (k % 2)  # the base mat's noise: never stuck
            health.meas.base_velocity_m_s = 1e-5 * (k % 2)
            assert det.update(k * DT, DT, health) is False, type(det).__name__


def test_a_stuck_base_mat_is_caught_while_the_table_sends_nothing() -> None:
    det = SensorStuck(SENSORS)
    health = TickHealth()
    health.table_fresh = False
    fired_at = None
    for k in range(SENSORS.stuck_samples + 5):
        health.meas.base_velocity_m_s = 1e-5 * (k % 2)  # the base mat's velocity moves; its displacement is frozen at 0
        if det.update(k * DT, DT, health):
            fired_at = k
            break
    assert fired_at == SENSORS.stuck_samples, "the first sample primes; each later equal one is a repeat"
    assert det.detail(health).startswith("y_b = 0.0 repeated to the bit")


def test_the_force_tracking_check_takes_its_action_from_the_profile_and_starts_from_zero() -> None:
    tracker = ForceTracking(ForceConfig(actuator_time_constant_s=0.0, tracking_action="safe_stop"))
    assert tracker.action is Action.SAFE_STOP
    assert tracker.expected_N() == 0.0
    tracker.update(0.0, 0.004, TickHealth())
    assert tracker.expected_N() == 0.0, "nothing commanded yet"


def test_the_stall_budget_refusal_gives_each_time_in_milliseconds_and_the_remedy() -> None:
    base = SafetyConfig()
    config = dataclasses.replace(base, run=dataclasses.replace(base.run, max_stall_s=0.2),
                                 sensors=dataclasses.replace(base.sensors, max_sensor_age_s=0.1),
                                 stroke=dataclasses.replace(base.stroke, stop_time_s=0.25),
                                 force=dataclasses.replace(base.force, actuator_time_constant_s=0.05))
    assert check_config(config) == [
        "run.max_stall_s (200.0 ms) + sensors.max_sensor_age_s (100.0 ms) = 300.0 ms of blind time exceeds what the "
        "predictive stroke limit covers, stroke.stop_time_s - force.actuator_time_constant_s = 200.0 ms: "
        "lower the stall budget or the sensor age, or lengthen stop_time_s (docs/SAFETY.md, Stall budget)"
    ]


def test_the_fade_band_refusal_says_what_would_happen() -> None:
    config = dataclasses.replace(SafetyConfig(), stroke=BAND_PAST_HARD_LIMIT)
    assert check_config(config) == [
        "stroke.fade_band_m (0.01 m) is wider than the soft-to-hard gap (0.005 m): force would still push outward at "
        "the hard limit"
    ]


@pytest.mark.parametrize(("group", "field"), [("sensors", "max_sensor_age_s"), ("run", "max_stall_s"),
                                              ("estop", "max_panel_age_s")])
def test_a_zero_time_is_refused_under_its_groups_name(group: str, field: str) -> None:
    base = SafetyConfig()
    config = dataclasses.replace(base, **{group: dataclasses.replace(getattr(base, group), **{field: 0.0})})
    assert f"{group}.{field} is 0, expected > 0" in check_config(config)


def test_unknown_and_missing_trip_actions_are_refused_word_for_word() -> None:
    config = dataclasses.replace(SafetyConfig(), trip_actions=TripActionsConfig(stroke=("estop", "launch")))
    assert check_config(config) == [
        "trip_actions.stroke names ['launch'], expected disable, estop or stop_table",
        "trip_actions.stroke is ['estop', 'launch']: disable cannot be removed (a trip always commands zero force with "
        "the drive disabled first)",
    ]


def test_a_stopping_ramp_exactly_as_long_as_the_rate_limit_needs_is_accepted() -> None:
    base = SafetyConfig()
    ramp_needed = base.force.max_force_N / base.force.max_force_rate_N_per_s
    config = dataclasses.replace(base, run=dataclasses.replace(base.run, stopping_ramp_s=ramp_needed))
    assert check_config(config) == []


def test_a_reset_persistence_counts_from_the_conditions_return() -> None:
    timer = Persistence(0.1)
    assert timer.update(0.0, True) is False
    timer.reset()
    assert timer.active is False and timer.held_s(1.0) == 0.0
    assert timer.update(1.0, True) is False, "held 0 s since it came back"
    assert timer.update(1.05, True) is False
    assert timer.update(1.1, True) is True


def test_a_small_derivative_beside_a_fast_velocity_is_not_a_sign_flip() -> None:
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
    det = SensorSignFlip(config)
    health = TickHealth()
    for k in range(200):  # the base mat's displacement stands still while its velocity reads 10 floors forward
        health.meas.base_velocity_m_s = 10.0 * config.sign_flip_floor_m_s
        assert det.update(k * DT, DT, health) is False


@pytest.mark.parametrize(("derivative", "velocity"), [(1.0, -2.0), (2.0, -1.0), (-1.0, 2.0), (-2.0, 1.0)])
def test_a_value_exactly_on_the_sign_flip_floor_is_not_above_it(derivative: float, velocity: float) -> None:
    det = SensorSignFlip(SENSORS)
    floor = SENSORS.sign_flip_floor_m_s
    det._deriv[1].y, det._vel[1].y = derivative * floor, velocity * floor
    assert det._bad(1) is False
    det._deriv[1].y, det._vel[1].y = 2.0 * derivative * floor, 2.0 * velocity * floor
    assert det._bad(1) is True


def test_a_pair_starts_from_its_velocity_and_again_after_a_gap_exactly_as_long_as_the_persistence_time() -> None:
    # binary-exact times: two 0.25 s ticks without a sample make a span of exactly the 0.5 s persistence time
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9, disagree_time_s=0.5)
    det = SensorDisagree(config)
    health = TickHealth()
    health.meas.base_velocity_m_s = 0.1
    det.update(0.0, 0.25, health)
    assert (det._deriv[1].y, det._vel[1].y) == (0.1, 0.1), "the first sample primes both filters with the velocity"
    health.base_fresh = False
    det.update(0.25, 0.25, health)
    health.base_fresh = True
    health.meas.base_displacement_m = 1.0  # 2 m/s over the gap, were it differentiated
    health.meas.base_velocity_m_s = 0.3
    det.update(0.5, 0.25, health)
    assert (det._deriv[1].y, det._vel[1].y) == (0.3, 0.3), "a span of the persistence time is a gap: start again"


def test_a_missed_sample_widens_the_span_the_derivative_is_taken_over() -> None:
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
    det = SensorDisagree(config)
    health = TickHealth()
    speed = 0.2  # m/s, four times the tolerance
    for k in range(400):  # a sample every other tick, each 2 DT further
        health.base_fresh = k % 2 == 0
        health.meas.base_displacement_m = speed * DT * (k - k % 2)
        health.meas.base_velocity_m_s = speed
        assert det.update(k * DT, DT, health) is False, k
    assert det._deriv[1].y == pytest.approx(speed)


def test_after_priming_the_derivative_is_filtered_from_the_velocity() -> None:
    det = SensorDisagree(SENSORS)  # the shipped 20 ms filter
    health = TickHealth()
    health.meas.base_velocity_m_s = 0.1
    det.update(0.0, DT, health)
    health.meas.base_displacement_m = 0.001 * DT  # 1 mm/s over the next tick
    health.meas.base_velocity_m_s = 0.3  # the mean over the tick: 0.2 m/s
    det.update(DT, DT, health)
    gain = DT / (SENSORS.disagree_filter_s + DT)
    assert det._deriv[1].y == pytest.approx(0.1 + gain * (0.001 - 0.1)), "one filter step from the primed 0.1 m/s"
    assert det._vel[1].y == pytest.approx(0.1 + gain * (0.2 - 0.1)), "one filter step from the primed 0.1 m/s"


def test_a_reset_low_pass_is_primed_by_its_next_input_and_a_reset_tracker_expects_zero() -> None:
    lag = LowPass(0.01)
    lag.update(5.0, 0.001)
    lag.reset()
    assert (lag.y, lag.primed) == (0.0, False)
    assert lag.update(3.0, 0.001) == 3.0
    tracker = ForceTracking(ForceConfig(actuator_time_constant_s=0.01))
    tracker.command_N = 2_000.0
    tracker.update(0.0, 0.004, TickHealth())
    tracker.reset()
    assert tracker.expected_N() == 0.0


def test_a_disagreement_on_the_table_is_reported_on_the_table() -> None:
    config = dataclasses.replace(SENSORS, disagree_filter_s=1e-9)
    det = SensorDisagree(config)
    health = TickHealth()
    for k in range(1000):
        health.meas.table_velocity_m_s = 1.0  # the table's displacement stands still
        if det.update(k * DT, DT, health):
            break
    else:
        pytest.fail("the disagreement must be caught")
    assert "x_0" in det.detail(health) and "y_b" not in det.detail(health)


def test_pair_checks_start_quietly_at_an_offset_and_before_any_sample() -> None:
    for det in (SensorDisagree(SENSORS), SensorSignFlip(SENSORS)):
        health = TickHealth()
        health.table_fresh = health.base_fresh = False
        assert det.update(0.0, DT, health) is False, "nothing received yet"
        health.table_fresh = health.base_fresh = True
        health.meas.table_displacement_m = health.meas.base_displacement_m = 0.05  # at rest, off centre
        for k in range(1, 300):
            assert det.update(k * DT, DT, health) is False, (type(det).__name__, k)


def test_a_new_low_pass_is_primed_by_its_first_input_and_a_new_tracker_expects_zero() -> None:
    lag = LowPass(0.01)
    assert (lag.y, lag.primed) == (0.0, False)
    assert lag.update(3.0, 0.001) == 3.0
    assert ForceTracking(ForceConfig(actuator_time_constant_s=0.01)).expected_N() == 0.0


def test_a_new_persistence_counts_from_the_conditions_first_appearance() -> None:
    timer = Persistence(0.1)
    assert timer.active is False
    assert timer.update(5.0, True) is False, "held 0 s, however late it first appears"
    assert timer.update(5.1, True) is True


def test_the_table_checks_summary_keeps_its_measures_rounded_to_their_stated_digits() -> None:
    period_s = 1.0 / 300.0  # a period with many decimals: times are not whole microseconds
    t = np.arange(0.0, 7.995, period_s)  # 2399 samples: the time compared is not a whole number of ms either
    rng = np.random.default_rng(5)
    told = sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 6.28)) for f in rng.uniform(0.5, 4.0, 20))
    told = 0.1 * told / np.std(told)
    table = 0.93 * np.interp(t - 0.008, t, told, left=0.0) + 0.02 * np.sin(2 * np.pi * 7.3 * t)  # gain, lag, a hum
    check = TableRecordCheck(0.02)
    check.expect(told, period_s, (told.size - 1) * period_s, period_s)
    for n, value in enumerate(table):
        check.update(n * period_s, float(value))
    summary = check.summary()
    tracking = check.tracking
    assert tracking is not None and 0.9 < tracking.correlation < 0.9999, "an imperfect match, every digit in use"
    assert summary["gate_s"] == round(check.gate_s, 6) != round(check.gate_s, 7)
    assert summary["record_s_compared"] == round(tracking.count * period_s, 6) != round(tracking.count * period_s, 7)
    assert summary["judged_at_s"] == round(check.worst_at_s, 6)
    assert summary["final"] == {"correlation": round(tracking.correlation, 4), "delay_s": round(tracking.delay_s, 6),
                                "amplitude_ratio": round(tracking.amplitude_ratio, 4)}
    assert isinstance(summary["final"]["correlation"], float) and summary["final"]["correlation"] < 1.0
    assert summary["final"]["amplitude_ratio"] != round(tracking.amplitude_ratio, 5)


def test_a_disagreement_exactly_at_the_tolerance_is_within_it() -> None:
    det = SensorDisagree(SENSORS)
    det._deriv[1].y, det._vel[1].y = SENSORS.disagree_tolerance_m_s, 0.0
    assert det._bad(1) is False
    det._deriv[1].y = 1.5 * SENSORS.disagree_tolerance_m_s
    assert det._bad(1) is True


def test_an_event_ring_of_one_hands_on_a_single_event() -> None:
    ring = EventRing(1)
    ring.push(1.0, "state", "ARMED", "only")
    drained: list[tuple[float, str, str, str]] = []
    assert ring.drain(lambda *event: drained.append(event)) == 1
    assert drained == [(1.0, "state", "ARMED", "only")] and ring.overwritten == 0


def test_the_list_of_checks_is_put_in_bit_order_and_a_gap_or_a_repeat_is_refused() -> None:
    assert _in_bit_order(tuple(reversed(CHECKS_BY_BIT))) == CHECKS_BY_BIT
    gap = tuple(check for check in CHECKS_BY_BIT if check.bit_number != 3)
    n = len(gap)
    with pytest.raises(RuntimeError) as refused:
        _in_bit_order(gap)
    assert str(refused.value) == (f"safety check bits are {[c.bit_number for c in gap]}; expected each of "
                                  f"0..{n - 1} once")
    repeat = (*CHECKS_BY_BIT[:-1], CHECKS_BY_BIT[-1]._replace(kind=CHECKS_BY_BIT[0].kind))
    with pytest.raises(RuntimeError) as repeated:
        _in_bit_order(repeat)
    assert str(repeated.value) == f"safety check names repeat: {[c.name for c in repeat]}"


def test_a_name_the_safety_package_does_not_have_is_an_attribute_error_naming_it() -> None:
    """The package loads its names lazily (PEP 562): a wrong one says which, as a module's own attribute error does."""
    import harness.safety as safety

    with pytest.raises(AttributeError, match="module 'harness.safety' has no attribute 'no_such_check'"):
        safety.no_such_check  # noqa: B018 - the attribute access is the test
