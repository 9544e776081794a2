"""ControlTick on a real bus: what each tick SENDS, decoded from the actuator's side of the bus.

The safety review found that the same-tick promises were proven only up to the
supervisor's return value: moving the write before supervision, or sending the last
command on the exception path, passed every test. These tests put a rig-side node on
python-can's in-process bus that publishes sensor and status frames and decodes the
ACTUATOR_CMD frames the tick sends, and assert on those frames.
"""

from __future__ import annotations

import math
import uuid

import pytest

from drivers.protocol.codec import load_protocol
from drivers.protocol.e2e import protect
from drivers.protocol.protocol_values import DriveState, EstopSource, FaultCode
from drivers.reader import RIG_RX, FrameReader
from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness, open_rig
from harness.control.estimator import FrictionEstimator
from harness.loop.tick import ControlTick
from harness.profile import load_profile
from harness.safety.config import CommsConfig, SafetyConfig
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor

PERIOD_S = 0.002


class FixedForce:
    """A controller that asks for a set force, or raises, with the visible internals the row records."""

    needs_full_state = False

    def __init__(self, force_N: float = 2_000.0) -> None:
        self.force_N = force_N
        self.raise_next = False
        self.sliding_variable = 0.0
        self.equivalent_force_N = 0.0

    def update(self, t, dt, meas, friction, state):
        if self.raise_next:
            raise RuntimeError("controller bug")
        return self.force_N


class Bench:
    """The harness tick on one side of a bus, a rig-side node on the other."""

    def __init__(self, safety: SafetyConfig | None = None) -> None:
        # The rig-side node here echoes the command as the measured force: a force source,
        # so the tracking check expects no velocity feedback from it.
        profile = load_profile(None, overrides=["safety.force.velocity_feedback_Ns_per_m=0"])
        can = CanConfig(interface="virtual", channel=f"tick-{uuid.uuid4().hex[:8]}")
        self.rig = open_rig(can)
        #: The rig side's view of what the harness sent: the latest frame of each message, and a tap for each frame.
        self.rig_side = FrameReader(self.rig.bus, self.rig.protocol, RIG_RX, health=self.rig.health)
        self.link = open_harness(can)
        self.controller = FixedForce()
        self.supervisor = Supervisor(safety or profile.safety, period_s=PERIOD_S)
        estimator = FrictionEstimator(profile.bearing, profile.structure.total_weight_N)
        self.tick = ControlTick(self.link, self.controller, estimator, self.supervisor, None, heartbeat_every=1)
        self.t = 0.0
        self.x_b = 0.0
        self.v_b = 0.0
        self.publish_sensors = True
        self.publish_panel = True  # the E-stop panel's heartbeat (ESTOP, source 3, active=0)
        self.publish_status = True  # ACTUATOR_STATUS (the load cell): slower than the loop on a real bus

    def close(self) -> None:
        self.link.close()
        self.rig.close()

    def publish(self) -> None:
        """One set of rig frames at the current time: the base-mat at stroke x_b (table at 0)."""
        w = self.rig.writer
        if self.publish_sensors:
            noise_m = 1e-6 * (self.tick.ticks % 3 - 1)  # a real transducer is never bit-for-bit constant
            w.table(noise_m, 10.0 * noise_m, 0.0, self.t)  # velocity moves by 1 LSB too (sensor_stuck)
            w.base(self.x_b + noise_m, self.v_b + 10.0 * noise_m, 0.0, self.t)  # 1 LSB of ydot_b
        if self.publish_panel:
            w.estop(False, self.t, source=EstopSource.PANEL)
        if self.publish_status:
            command = self.supervisor.command
            drive_state = DriveState.ENABLED if command.enable else DriveState.READY
            w.actuator_status(command.force_N, drive_state, True, FaultCode.NONE, self.t)

    def step(self):
        """Publish, run one tick, and return the ACTUATOR_CMD (enable, force_N) the rig received for it."""
        self.publish()
        command = self.tick.run(self.t, PERIOD_S, self.t)
        self.t += PERIOD_S
        sample = self.rig_side.sample("ACTUATOR_CMD")
        before = sample.count
        self.rig_side.poll(self.t)
        assert sample.count == before + 1, "exactly one actuator command per tick"
        enable, force = sample.values[sample.index("enable")], sample.values[sample.index("force")]
        return command, (bool(enable), force)

    def run_until_running(self):
        for _ in range(3):
            self.step()
        self.supervisor.arm(self.t, self.tick.health)
        self.supervisor.start(self.t)
        for _ in range(20):
            _, sent = self.step()
        assert sent[0] and sent[1] > 0.0, "the drive is enabled and force flows before the fault"


@pytest.fixture
def bench():
    benches = []

    def make(safety: SafetyConfig | None = None) -> Bench:
        b = Bench(safety)
        benches.append(b)
        return b

    yield make
    for b in benches:
        b.close()


def test_the_frame_sent_on_the_stroke_trip_tick_is_zero_and_disabled(bench):
    b = bench()
    b.run_until_running()
    b.controller.force_N = -2_000.0  # pulls the base back: the stroke fade leaves it alone
    for _ in range(200):  # the base speeds up to slide outward at 0.5 m/s, 1 mm per tick
        b.v_b = min(0.5, b.v_b + 0.1)
        b.x_b += b.v_b * PERIOD_S
        command, sent = b.step()
        if command.state is State.TRIPPED:
            break
        assert sent[0] and sent[1] != 0.0  # force flowed up to the trip
    assert command.trip_reason in ("stroke_predictive", "stroke_hard")
    assert sent == (False, 0.0)  # the bus carried the trip in the same tick, not the previous command


def test_the_frame_sent_on_an_exception_tick_is_zero_and_disabled(bench):
    b = bench()
    b.run_until_running()
    b.controller.raise_next = True
    command, sent = b.step()
    assert command.trip_reason == "tick_exception"
    assert sent == (False, 0.0)


def test_an_exception_in_recording_trips_and_sends_zero_at_once(bench):
    b = bench()
    b.run_until_running()

    class BrokenRecorder:
        def record_row(self, row):
            raise OSError("disk gone")

        def record_event(self, *args):
            pass

    b.tick.recorder = BrokenRecorder()
    b.publish()
    command = b.tick.run(b.t, PERIOD_S, b.t)
    sample = b.rig_side.sample("ACTUATOR_CMD")
    b.rig_side.poll(b.t)
    assert command.trip_reason == "tick_exception"
    assert (bool(sample.values[sample.index("enable")]), sample.values[sample.index("force")]) == (False, 0.0)


def test_an_exception_while_reading_trips(bench, monkeypatch):
    b = bench()
    b.run_until_running()
    monkeypatch.setattr(b.tick.reader, "fill", lambda meas: (_ for _ in ()).throw(ValueError("decoder bug")))
    command, sent = b.step()
    assert command.trip_reason == "tick_exception" and sent == (False, 0.0)
    assert b.supervisor.trip_detail == "ValueError: decoder bug"  # the trip names what failed


class AddedForce:
    """A compensator that adds a set force to the controller's (the tick must use the one it is given)."""

    def __init__(self, added_N: float) -> None:
        self.added_N, self.command_N = added_N, 0.0
        self.pinned = self.diverged = False
        self.bound_value = 0.0

    def reset(self) -> None:
        self.command_N = 0.0

    def update(self, t, dt, force_N, meas, applied_N):
        self.command_N = force_N + self.added_N
        return self.command_N


def test_the_tick_commands_through_the_compensator_it_is_given(bench):
    b = bench()
    b.tick = ControlTick(b.link, b.controller, b.tick.estimator, b.supervisor, None, heartbeat_every=1,
                         compensator=AddedForce(150.0))
    b.run_until_running()
    _, sent = b.step()
    assert sent == (True, pytest.approx(b.controller.force_N + 150.0, abs=1.0))


def test_rejected_frames_do_not_keep_a_sensor_fresh(bench):
    # E2E rejections tolerated far beyond what arrives, so only staleness can trip
    b = bench(SafetyConfig(comms=CommsConfig(max_e2e_rejects=10_000)))
    b.run_until_running()
    protocol = load_protocol()
    codec = protocol["BASE_SENSORS"]
    corrupt = bytearray(codec.encode([b.x_b, 0.0, 0.0], 3))
    corrupt[0] ^= 0xFF  # a wrong CRC: rejected
    import can

    b.publish_sensors = False
    max_age_s = load_profile(None).safety.sensors.max_sensor_age_s
    tripped_at = None
    for k in range(40):
        b.rig.writer.table(0.0, 0.0, 0.0, b.t)
        b.rig.bus.send(can.Message(arbitration_id=codec.frame_id, data=corrupt, is_extended_id=False))
        command, sent = b.step()
        if command.state is State.TRIPPED:
            tripped_at = k
            break
    assert tripped_at is not None and command.trip_reason == "sensor_stale"
    assert (tripped_at + 1) * PERIOD_S == pytest.approx(max_age_s + PERIOD_S, abs=PERIOD_S)
    assert sent == (False, 0.0)


def test_an_intact_frame_with_a_value_out_of_range_trips_sensor_invalid_in_the_same_tick(bench):
    b = bench()
    b.run_until_running()
    import can

    codec = load_protocol()["BASE_SENSORS"]
    data = bytearray(codec.encode([0.0, 0.0, 0.0], 0))
    raw = 0x7FFFF  # y_b = 0.524287 m: on the wire, outside the DBC's +/-0.5 m
    bits = int.from_bytes(data, "little") & ~(((1 << 20) - 1) << 12) | (raw << 12)
    data = bytearray(bits.to_bytes(8, "little"))
    b.publish_sensors = False
    b.rig.writer.table(0.0, 0.0, 0.0, b.t)
    counter = (b.rig.writer.frame("BASE_SENSORS").counter) % 16
    protect(data, counter, codec.data_ids)
    b.rig.bus.send(can.Message(arbitration_id=codec.frame_id, data=data, is_extended_id=False))
    command, sent = b.step()
    assert command.trip_reason == "sensor_invalid", command.trip_reason
    assert math.isnan(b.tick.meas.base_displacement_m)
    assert sent == (False, 0.0)


def test_commands_follow_the_supervisor_not_the_controller_on_every_tick(bench):
    b = bench()
    b.run_until_running()
    b.controller.force_N = 50_000.0  # far beyond the clamp: what is sent is the supervised force
    for _ in range(30):
        command, sent = b.step()
        assert sent == (command.enable, pytest.approx(command.force_N, abs=1.0))
        assert abs(sent[1]) <= load_profile(None).safety.force.max_force_N


def test_a_bus_that_cannot_be_polled_trips_bus_gone_in_the_same_tick(bench, monkeypatch):
    from drivers.errors import BusError

    b = bench()
    b.run_until_running()

    def gone(now):
        raise BusError("interface vanished")

    monkeypatch.setattr(b.tick.reader, "poll", gone)
    b.publish()
    command = b.tick.run(b.t, PERIOD_S, b.t)
    assert b.tick.health.bus_gone is True
    assert command.trip_reason == "bus_gone" and command.force_N == 0.0 and not command.enable


def test_a_recorder_gets_one_row_per_tick_and_every_event(bench):
    b = bench()
    rows, events = [], []

    class Recorder:
        def record_row(self, row):
            rows.append(row.copy())

        def record_event(self, t, kind, name, detail):
            events.append((t, kind, name, detail))

    b.tick = ControlTick(b.link, b.controller, b.tick.estimator, b.supervisor, Recorder(), heartbeat_every=1)
    b.run_until_running()
    b.controller.raise_next = True
    b.step()
    assert len(rows) == b.tick.ticks == 24
    assert [r[0] for r in rows] == pytest.approx([k * PERIOD_S for k in range(24)])  # the row starts with t
    assert ("fault", "tick_exception") in [(kind, name) for _, kind, name, _ in events]
    assert b.tick.last_event.endswith(events[-1][3]) and events[-1][2] in b.tick.last_event


def test_each_failed_disable_send_is_counted(bench, monkeypatch):
    b = bench()

    def refused(*args):
        raise OSError("ENOBUFS")

    monkeypatch.setattr(b.tick.writer, "command", refused)
    for k in range(3):
        b.tick.send_disable(k * PERIOD_S)  # never raises
    assert b.tick.disable_failures == 3


class _Flags:
    """Stands in for the bus health the link reports: every flag the tick copies, set by the test."""

    def __init__(self, **flags) -> None:
        self.error_frames, self.send_failures, self.error_passive, self.bus_off = 0, 0, False, False
        self.__dict__.update(flags)


@pytest.mark.parametrize(("fault", "reason", "state"), [
    ("estop", "estop", State.TRIPPED),
    ("drive_fault", "drive_fault", State.TRIPPED),
    ("foreign_command", "foreign_command", State.TRIPPED),
    ("bus_off", "bus_off", State.TRIPPED),
    ("error_passive", "bus_error_passive", State.STOPPING),  # safe_stop by default
])
def test_each_flag_the_drivers_report_reaches_the_supervisor_through_the_tick(bench, monkeypatch, fault, reason, state):
    from harness.safety.checks import bit

    b = bench()
    b.run_until_running()
    reader_type = type(b.tick.reader)
    if fault == "estop":
        b.tick.reader.estop_requested = True  # what a valid ESTOP frame with active=1 latches
    elif fault == "drive_fault":
        monkeypatch.setattr(reader_type, "drive_fault", property(lambda self: True))
    elif fault == "foreign_command":
        monkeypatch.setattr(reader_type, "foreign_command_seen", property(lambda self: True))
    else:
        b.tick.bus_health = _Flags(**{fault: True})
    command, _ = b.step()
    assert command.state is state and command.acted & bit(reason)
    assert (command.trip_reason == reason) if state is State.TRIPPED else not command.trip_reason


def test_a_jump_between_two_fresh_samples_trips_through_the_tick(bench):
    b = bench()
    b.run_until_running()
    b.x_b += 0.02  # 20 mm between two base-mat frames, four times jump_limit_m
    command, sent = b.step()
    assert command.trip_reason == "sensor_jump" and sent == (False, 0.0)


@pytest.mark.parametrize(("every", "ticks_with_a_heartbeat"), [(1, list(range(12))), (5, [0, 5, 10])])
def test_the_heartbeat_goes_out_on_every_nth_tick_from_the_first(every: int, ticks_with_a_heartbeat: list[int]):
    b = Bench()
    try:
        b.tick = ControlTick(b.link, b.controller, b.tick.estimator, b.supervisor, None, heartbeat_every=every)
        heartbeat = b.rig_side.sample("HEARTBEAT")
        seen = []
        for k in range(12):
            before = heartbeat.count
            b.step()
            if heartbeat.count > before:
                seen.append(k)
        assert seen == ticks_with_a_heartbeat
    finally:
        b.close()


def test_a_stall_the_loop_reports_reaches_the_supervisor_through_the_tick(bench):
    b = bench()
    b.run_until_running()
    b.publish()
    command = b.tick.run(b.t, PERIOD_S, b.t, 0.0, 0.045, 21)  # 45 ms since the previous command
    assert (b.tick.health.stall_s, b.tick.health.missed_periods) == (0.045, 21)
    assert command.trip_reason == "loop_stall" and "21 missed periods" in b.supervisor.trip_detail
