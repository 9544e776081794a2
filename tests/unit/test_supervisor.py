"""Tests of the supervisor: order of checks, actions, pre-arm, reset, events and counters."""

from __future__ import annotations

import dataclasses
import math
import tracemalloc

import pytest

from harness.safety.checks import CHECK_NAMES, CHECKS, bit, index, names_of
from harness.safety.config import (
    CommsConfig,
    ForceConfig,
    SafetyConfig,
    SensorConfig,
    StrokeConfig,
)
from harness.safety.events import EventRing
from harness.safety.health import TickHealth
from harness.safety.lifecycle import ArmRefused, ResetRefused, State
from harness.safety.prearm import PRE_ARM_CHECKS
from harness.safety.supervisor import Supervisor

DT = 0.004


class Rig:
    """A supervisor in RUNNING with a health struct and a perfectly tracking actuator."""

    def __init__(self, config: SafetyConfig | None = None) -> None:
        self.sup = Supervisor(config or SafetyConfig())
        self.health = TickHealth()
        self.k = 0
        self.events: list[tuple[float, str, str, str]] = []
        self.sup.arm(0.0, self.health)
        self.sup.start(0.0)

    def tick(self, force: float = 0.0):
        self.k += 1
        self.health.measured_force_N = self.sup.command.force_N
        command = self.sup.update(self.k * DT, DT, self.health, force)
        self.sup.events.drain(lambda *e: self.events.append(e))
        return command


def test_detectors_run_in_the_order_of_the_list_of_checks() -> None:
    sup = Supervisor(SafetyConfig())
    order = [d.NAME for d in sup.detectors]
    assert order == [
        "estop", "estop_lost", "operator_trip", "operator_stop", "loop_stall",
        "sensor_invalid", "sensor_stale", "sensor_jump", "sensor_stuck", "sensor_sign_flip", "sensor_polarity",
        "sensor_disagree", "bus_gone", "bus_off", "bus_error_passive", "bus_error_frames", "e2e_rejects", "bus_send_failures",
        "foreign_command", "drive_fault", "hydraulic_pressure", "actuator_status_stale", "load_cell_limit", "force_tracking",
        "compensation_fault", "force_oscillation", "table_record_mismatch", "table_record_marginal",
    ]
    assert order == [check.name for check in CHECKS if check.build is not None]


def test_update_returns_the_same_preallocated_command() -> None:
    rig = Rig()
    first = rig.tick(100.0)
    assert rig.tick(200.0) is first is rig.sup.command


def test_first_trip_in_the_documented_order_is_latched() -> None:
    rig = Rig()
    rig.health.estop = True
    rig.health.table_age_s = 1.0  # also stale; estop comes first
    command = rig.tick(100.0)
    assert command.trip_reason == "estop"
    assert command.acted & bit("estop") and not command.acted & bit("sensor_stale")


@pytest.mark.parametrize(("setup", "reason"), [
    (lambda h: setattr(h.meas, "base_displacement_m", math.nan), "sensor_invalid"),
    (lambda h: setattr(h, "base_age_s", 1.0), "sensor_stale"),
    (lambda h: setattr(h, "bus_off", True), "bus_off"),
    (lambda h: setattr(h, "bus_gone", True), "bus_gone"),
    (lambda h: setattr(h, "foreign_command", True), "foreign_command"),
    (lambda h: setattr(h, "drive_fault", True), "drive_fault"),
    (lambda h: setattr(h, "pressure_ok", False), "hydraulic_pressure"),
    (lambda h: setattr(h, "actuator_status_age_s", 1.0), "actuator_status_stale"),
    (lambda h: setattr(h, "operator_trip", True), "operator_trip"),
])
def test_each_trip_zeroes_and_disables_on_its_tick_and_reset_waits_for_it(setup, reason: str) -> None:
    rig = Rig()
    for _ in range(5):
        rig.tick(3000.0)
    assert rig.sup.command.enable and rig.sup.command.force_N != 0.0
    clean = dataclasses.replace(rig.health, meas=dataclasses.replace(rig.health.meas))
    setup(rig.health)
    command = rig.tick(3000.0)
    assert (command.force_N, command.enable, command.state, command.trip_reason) == (0.0, False, State.TRIPPED, reason)
    assert rig.sup.act_ticks[index(reason)] == 1
    assert ("fault", reason) in [(e[1], e[2]) for e in rig.events]
    with pytest.raises(ResetRefused, match=reason):
        rig.sup.reset(1.0, rig.health)
    rig.sup.reset(1.0, clean)
    assert rig.sup.state is State.IDLE


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_controller_output_trips(bad: float) -> None:
    rig = Rig()
    rig.tick(1000.0)
    command = rig.tick(bad)
    assert (command.force_N, command.enable, command.trip_reason) == (0.0, False, "controller_output")
    assert "controller output not finite" in rig.sup.lifecycle.trip_detail


@pytest.mark.parametrize("dt", [0.0, -DT, math.nan, math.inf])
def test_bad_dt_trips_loop_timing(dt: float) -> None:
    rig = Rig()
    command = rig.sup.update(1.0, dt, rig.health, 0.0)
    assert command.trip_reason == "loop_timing" and not command.enable


def test_reported_tick_exception_trips_with_its_name() -> None:
    rig = Rig()
    rig.tick(1000.0)
    command = rig.sup.report_exception(0.5, ZeroDivisionError("division by zero"))
    assert (command.force_N, command.enable, command.trip_reason) == (0.0, False, "tick_exception")
    assert "ZeroDivisionError" in rig.sup.trip_detail
    assert rig.sup.act_counts() == {"tick_exception": 1}
    rig.sup.reset(1.0, rig.health)  # not knowable: the reset is allowed
    assert rig.sup.state is State.IDLE


def test_hard_stroke_trips_and_reset_is_refused_until_centred() -> None:
    rig = Rig()
    rig.health.meas.base_displacement_m = 0.004
    rig.tick()
    for x in (0.02, 0.045, 0.07):  # walk outward without triggering jump (limit 5 mm/sample? use fresh=False)
        rig.health.base_fresh = False
        rig.health.meas.base_displacement_m = x
        assert rig.tick().state is State.RUNNING
    rig.health.meas.base_displacement_m = 0.075
    command = rig.tick()
    assert command.trip_reason == "stroke_hard"
    with pytest.raises(ResetRefused, match="stroke_hard"):
        rig.sup.reset(1.0, rig.health)
    rig.health.meas.base_displacement_m = 0.0
    rig.sup.reset(1.0, rig.health)


def test_predictive_stroke_trips_before_the_hard_limit() -> None:
    rig = Rig()
    rig.health.base_fresh = False  # keep the jump and disagreement checks out of this test
    rig.health.meas.base_displacement_m = 0.05
    rig.health.meas.base_velocity_m_s = 0.3  # projection 0.08 m > 0.075 m
    command = rig.tick()
    assert command.trip_reason == "stroke_predictive"


def test_soft_fade_clamp_and_rate_flags_and_counters() -> None:
    rig = Rig()
    for _ in range(20):
        rig.tick(50_000.0)  # clamped to 10 kN, rate-limited on the way
    assert rig.sup.command.force_N == pytest.approx(10_000.0)
    assert rig.sup.act_ticks[index("force_clamp")] == 20
    assert 5 <= rig.sup.act_ticks[index("force_rate")] < 20
    rig.health.base_fresh = False
    rig.health.meas.base_displacement_m = 0.055  # half the fade band
    command = rig.tick(50_000.0)
    assert command.force_N == pytest.approx(5_000.0)
    assert command.acted & bit("stroke_soft") and command.acted & bit("force_clamp")
    assert set(names_of(command.acted)) == {"force_clamp", "stroke_soft"}
    step = 400_000.0 * DT
    command = rig.tick(-50_000.0)  # rate-limited on the way down, still outward: still faded
    assert command.force_N == pytest.approx((5_000.0 - step) * 0.5)
    assert command.acted & bit("stroke_soft")
    previous = command.force_N
    command = rig.tick(-50_000.0)
    assert command.force_N == pytest.approx((previous - step) * 0.5)
    previous = command.force_N
    command = rig.tick(-50_000.0)  # now pulling back towards the centre: passes, only rate-limited
    assert command.force_N == pytest.approx(previous - step) and command.force_N < 0.0
    assert not command.acted & bit("stroke_soft")


def test_events_on_rising_edges_only() -> None:
    rig = Rig()
    for _ in range(10):
        rig.tick(50_000.0)
    names = [e[2] for e in rig.events if e[1] == "interlock"]
    assert names.count("force_clamp") == 1 and names.count("force_rate") == 1
    rig.tick(0.0)
    rig.tick(0.0)  # clamp released
    rig.tick(50_000.0)
    assert [e[2] for e in rig.events if e[1] == "interlock"].count("force_clamp") == 2


def test_safe_stop_detector_enters_stopping_and_finishes() -> None:
    # the measurements here are noise-free, so every channel repeats to the bit: a real sensor's never
    # does, and sensor_stuck would (rightly) trip after stuck_samples ticks; this test is about the stop
    rig = Rig(dataclasses.replace(SafetyConfig(), sensors=SensorConfig(stuck_samples=10**6)))
    for _ in range(10):
        rig.tick(2000.0)
    rig.health.error_passive = True
    command = rig.tick(2000.0)
    assert command.state is State.STOPPING and command.enable
    assert command.acted & bit("bus_error_passive")
    while rig.sup.state is State.STOPPING:
        rig.tick(2000.0)
        assert rig.k < 1000
    assert rig.sup.state is State.DONE and rig.sup.command.trip_reason == ""
    rig.sup.reset(rig.k * DT, rig.health)
    assert rig.sup.state is State.IDLE


def test_indicate_action_flags_without_changing_force_or_state() -> None:
    config = dataclasses.replace(SafetyConfig(), comms=CommsConfig(error_passive_action="indicate"))
    rig = Rig(config)
    for _ in range(10):
        rig.tick(1000.0)
    rig.health.error_passive = True
    command = rig.tick(1000.0)
    assert (command.state, command.force_N) == (State.RUNNING, 1000.0)
    assert command.acted == bit("bus_error_passive")
    assert [e[2] for e in rig.events if e[1] == "fault"] == ["bus_error_passive"]


def test_operator_stop_ramps_and_operator_trip_overrides() -> None:
    rig = Rig()
    for _ in range(10):
        rig.tick(2000.0)
    rig.health.operator_stop = True
    assert rig.tick(2000.0).state is State.STOPPING
    rig.health.operator_trip = True
    command = rig.tick(2000.0)
    assert (command.state, command.trip_reason, command.force_N) == (State.TRIPPED, "operator_trip", 0.0)


@pytest.mark.parametrize(("field", "value", "check"), [
    ("table_age_s", 1.0, "sensors_fresh"),
    ("e2e_ok", False, "e2e_ok"),
    ("drive_ready", False, "actuator_ready"),
    ("drive_fault", True, "actuator_ready"),
    ("pressure_ok", False, "hydraulic_pressure"),
    ("actuator_status_age_s", 1.0, "actuator_status_fresh"),
    ("foreign_command", True, "no_foreign_command"),
    ("bus_off", True, "bus_ok"),
    ("error_passive", True, "bus_ok"),
    ("bus_gone", True, "bus_ok"),
    ("estop", True, "estop_clear"),
    ("operator_stop", True, "no_operator_request"),
    ("operator_trip", True, "no_operator_request"),
    ("estop_panel_age_s", 1.0, "estop_panel_live"),
])
def test_arm_refused_names_the_failed_check(field: str, value: object, check: str) -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth()
    setattr(health, field, value)
    with pytest.raises(ArmRefused) as info:
        sup.arm(0.0, health)
    assert [f.split(":")[0] for f in info.value.failed] == [check]
    assert check in PRE_ARM_CHECKS
    assert sup.state is State.IDLE


def test_arm_refused_says_what_was_expected_and_lists_every_failure() -> None:
    health = TickHealth(estop=True, operator_trip=True)
    with pytest.raises(ArmRefused) as info:
        Supervisor(SafetyConfig()).arm(0.0, health)
    assert str(info.value) == (
        "arm refused: expected every pre-arm check to pass, failed: estop_clear: E-stop asserted, expected released; "
        "no_operator_request: stop=False, trip=True pending, expected none"
    )


@pytest.mark.parametrize(("offset_m", "ok"), [(0.005, True), (-0.005, True), (0.0051, False), (math.nan, False)])
def test_arm_needs_the_stroke_near_centre(offset_m: float, ok: bool) -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth()
    health.meas.table_displacement_m = 0.01
    health.meas.base_displacement_m = 0.01 + offset_m
    if ok:
        sup.arm(0.0, health)
        assert sup.state is State.ARMED
    else:
        with pytest.raises(ArmRefused, match="stroke_centred"):
            sup.arm(0.0, health)


def test_arm_clears_detector_history() -> None:
    sup = Supervisor(SafetyConfig())
    health = TickHealth(e2e_rejects=1000)  # rejections counted before arming are not a rate
    sup.arm(0.0, health)
    sup.start(0.0)
    assert sup.update(DT, DT, health, 0.0).state is State.RUNNING
    health.e2e_rejects += CommsConfig().max_e2e_rejects + 1
    assert sup.update(2 * DT, DT, health, 0.0).trip_reason == "e2e_rejects"


def test_done_reset_and_rearm() -> None:
    rig = Rig()
    rig.sup.stop(rig.k * DT)
    while rig.sup.state is State.STOPPING:
        rig.tick()
    rig.sup.reset(1.0, rig.health)
    rig.sup.arm(1.0, rig.health)
    assert rig.sup.state is State.ARMED


def test_event_ring_overwrites_oldest_and_counts() -> None:
    ring = EventRing(3)
    for k in range(5):
        ring.push(float(k), "fault", "estop", str(k))
    seen: list[tuple] = []
    assert ring.drain(lambda *e: seen.append(e)) == 3
    assert [e[0] for e in seen] == [2.0, 3.0, 4.0] and ring.overwritten == 2 and len(ring) == 0


def test_bits_are_stable_and_unique() -> None:
    assert len(set(CHECK_NAMES)) == len(CHECK_NAMES)
    assert bit("force_clamp") == 1 and bit("force_rate") == 2 and bit("stroke_soft") == 4
    with pytest.raises(KeyError, match="unknown safety check"):
        bit("nope")


def test_steady_ticks_do_not_allocate() -> None:
    config = dataclasses.replace(SafetyConfig(), force=ForceConfig(), stroke=StrokeConfig())
    rig = Rig(config)
    for _ in range(200):
        rig.tick(50_000.0)  # warm up with clamp acting; events drained
    health, sup = rig.health, rig.sup
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for k in range(2000):
            health.measured_force_N = sup.command.force_N
            sup.update((300 + k) * DT, DT, health, 50_000.0 if k % 50 < 40 else 0.0)
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    grown = [s for s in after.compare_to(before, "filename") if "harness/safety" in str(s.traceback) and s.size_diff > 0]
    assert sum(s.size_diff for s in grown) < 2048, grown


def test_every_interlock_event_says_its_limit_and_the_demanded_value() -> None:
    rig = Rig()
    rig.tick(50_000.0)  # clamped to 10 kN and rate-limited to 400 kN/s x 4 ms = 1.6 kN
    details = {e[2]: e[3] for e in rig.events if e[1] == "interlock"}
    assert details["force_clamp"] == "demanded 50000 N, clamped to +/-10000 N (safety.force.max_force_N)"
    assert details["force_rate"] == ("demanded 2.5e+06 N/s (0 N to 10000 N in 4 ms), limited to +/-400000 N/s "
                                     "(safety.force.max_force_rate_N_per_s)")
    for _ in range(10):
        rig.tick(50_000.0)
    rig.health.base_fresh = False
    rig.health.meas.base_displacement_m = 0.055  # half the fade band beyond the 0.05 m soft limit
    rig.tick(50_000.0)
    details = {e[2]: e[3] for e in rig.events if e[1] == "interlock"}
    assert details["stroke_soft"] == ("x_b = 0.055 m beyond the soft limit +/-0.05 m (safety.stroke.soft_limit_m): "
                                      "outward force 10000 N faded to 5000 N")
    rig.sup.stop(rig.k * DT)
    rig.tick(0.0)
    details = {e[2]: e[3] for e in rig.events if e[1] == "interlock"}
    assert details["stop_ramp"].startswith("force ramps to zero over 0.5 s (safety.run.stopping_ramp_s)")
    assert all(e[3] for e in rig.events if e[1] == "interlock")  # no interlock event has an empty detail
