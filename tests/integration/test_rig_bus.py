"""The virtual rig on the python-can virtual bus, read with the harness-side drivers.

Most tests drive the rig in-process with ``service(now)`` and a made-up clock, so
they are deterministic and never sleep; the thread and ``run_rig_command`` tests
poll with generous timeouts.
"""

from __future__ import annotations

import dataclasses
import signal
import subprocess
import sys
import threading
import time
import uuid

import can
import numpy as np
import pytest

from drivers.protocol.decoder import RxStatus
from drivers.protocol.protocol_values import DriveState, FaultCode, RigCommand
from harness import exit_codes
from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness, open_rig
from harness.errors import BusError
from harness.profile import load_profile
from harness.rig.config import (
    ActuatorConfig,
    DisplacementSensorConfig,
    DriveConfig,
    FaultSpec,
    RigConfig,
    SensorsConfig,
)
from harness.rig.faults import fault_id_for
from harness.rig.virtual_rig import RigParts, VirtualRig
from harness.runs import rig_service
from harness.runs.dry_run import RigCoordinator
from harness.runs.options import StudyOptions, prepare_motion
from harness.runs.rig_service import run_rig_command
from harness.safety.lifecycle import State
from tests.conftest import PROFILES

PERIOD = 0.002
IDS = {"TABLE_SENSORS": 0x30, "BASE_SENSORS": 0x31, "ACTUATOR_STATUS": 0x40, "STORY_DRIFTS": 0x200,
       "FLOOR_ACCELS": 0x201, "RIG_STATUS": 0x301, "ESTOP": 0x10}


@pytest.fixture(scope="module")
def profile():
    return load_profile(PROFILES / "nceer_4dof.yaml")


@pytest.fixture(scope="module")
def motion(profile):
    return prepare_motion(profile, StudyOptions(record="synthetic", duration_s=4.0))


def quiet_config(**changes) -> RigConfig:
    """No noise, no delays, ideal actuator, a watchdog that does not trip unless a test wants it."""
    base = RigConfig(
        actuator=ActuatorConfig(model="ideal", force_rate_limit_N_per_s=1e9), drive=DriveConfig(watchdog_timeout_s=10.0)
    )
    return dataclasses.replace(base, **changes)


class Bench:
    """A rig, a harness link and a raw listener on one fresh virtual channel, with a made-up clock."""

    def __init__(self, profile, motion, config: RigConfig, *, lockstep: bool = True, seed: int = 0,
                 can_config: CanConfig | None = None, period_s: float = PERIOD):
        can_config = can_config or CanConfig(channel=f"rig-{uuid.uuid4().hex[:10]}")
        self.period_s = period_s
        self.rig_link = open_rig(can_config)
        self.link = open_harness(can_config)
        self.listener = can.Bus(interface="virtual", channel=can_config.channel)
        parts = RigParts(profile.structure, profile.bearing, config, profile.simulation.rtol)
        self.rig = VirtualRig(parts, motion, self.rig_link, step_period_s=period_s, lockstep=lockstep, seed=seed,
                              can_config=can_config)
        self.now = 0.0
        self.reader, self.writer = self.link.reader, self.link.writer

    def close(self) -> None:
        self.listener.shutdown()
        self.link.close()
        self.rig_link.close()

    def service(self, dt: float = 0.0) -> None:
        self.now += dt
        self.rig.service(self.now)
        self.reader.poll(self.now)

    def start(self) -> None:
        """Heartbeat, lockstep on and table start (the harness's opening)."""
        self.writer.heartbeat(1, self.now)
        self.writer.rig_control(RigCommand.START_TABLE, self.rig.lockstep, self.now)
        self.service()

    def control(self, command: int = RigCommand.NONE, fault_id: int = 0, param: float = 0.0) -> None:
        self.writer.rig_control(command, self.rig.lockstep, self.now, fault_id, param)
        self.service()

    def step(self, force: float = 0.0, enable: bool = True, n: int = 1) -> None:
        for _ in range(n):
            self.writer.heartbeat(1, self.now)
            self.writer.command(force, enable, self.now)
            self.service(self.period_s)

    def frames(self, every_id: bool = False) -> list[can.Message]:
        """The frames on the bus since the last call: the rig's sensor and status frames, or ``every_id``."""
        out = []
        while (msg := self.listener.recv(timeout=0)) is not None:
            if every_id or msg.arbitration_id in IDS.values():
                out.append(msg)
        return out

    def value(self, message: str, signal: str) -> float:
        return self.reader.sample(message)[signal]


@pytest.fixture
def bench(profile, motion):
    benches = []

    def make(config: RigConfig | None = None, **kwargs) -> Bench:
        b = Bench(profile, motion, config or quiet_config(), **kwargs)
        benches.append(b)
        return b

    yield make
    for b in benches:
        b.close()


# ------------------------------------------------------------------ lockstep contract
def test_lockstep_publishes_in_contract_order_one_step_per_command(bench):
    b = bench()
    b.start()
    opening = [m.arbitration_id for m in b.frames()]
    # the E-stop panel's heartbeat (0x10, source 3) rides with the set every 25 steps, step 0 included
    assert opening == [0x30, 0x31, 0x200, 0x201, 0x40, 0x10, 0x301], "entering lockstep publishes the set, RIG_STATUS last"
    assert b.value("RIG_STATUS", "step_index") == 0 and b.value("RIG_STATUS", "lockstep") == 1
    b.writer.heartbeat(1, b.now)
    b.service(PERIOD)
    assert b.frames() == [] and b.rig.state.step_index == 0, "a heartbeat does not step the rig"
    for k in range(1, 5):
        b.step(100.0)
        ids = [m.arbitration_id for m in b.frames()]
        stories = [0x200, 0x201] if k % 2 == 0 else []  # story rate 250 Hz = every 2nd step at 500 Hz
        assert ids == [0x30, 0x31, *stories, 0x40, 0x301]
        assert b.value("RIG_STATUS", "step_index") == k
        assert b.rig.state.rig_time_s == pytest.approx(k * PERIOD)
    assert b.value("RIG_STATUS", "table_running") == 1
    assert b.value("RIG_STATUS", "record_time") == pytest.approx(4 * PERIOD, abs=1e-4), "the record started at step 1"


def test_a_start_while_the_table_runs_is_answered_with_start_refused(bench):
    b = bench()
    b.start()
    b.step(n=3)
    assert b.value("RIG_STATUS", "table_running") == 1 and b.value("RIG_STATUS", "start_refused") == 0
    record_time = b.value("RIG_STATUS", "record_time")
    b.control(RigCommand.START_TABLE)
    assert b.value("RIG_STATUS", "start_refused") == 1, "the rig answers a start it cannot obey, at once in lockstep"
    assert b.value("RIG_STATUS", "record_time") == pytest.approx(record_time, abs=1e-4), "the record was not restarted"
    assert any("start table refused" in line for _, line in b.rig.journal.drain())
    coordinator = RigCoordinator(True, PERIOD)
    coordinator.link = b.link
    assert coordinator.start_refused(), "the dry run reads the rig's answer"
    b.control(RigCommand.STOP_TABLE)
    assert b.value("RIG_STATUS", "start_refused") == 0 and b.value("RIG_STATUS", "table_running") == 0
    assert not coordinator.start_refused()
    b.control(RigCommand.START_TABLE)
    b.step()
    assert b.value("RIG_STATUS", "start_refused") == 0 and b.value("RIG_STATUS", "table_running") == 1


def test_the_table_is_held_when_the_harness_run_ends(bench):
    b = bench()
    b.start()
    b.step(n=3)
    assert b.rig.table.running
    b.writer.heartbeat(int(State.DONE), b.now)
    b.service()
    assert not b.rig.table.running, "a table left running would play on while the next harness waits idle"
    assert any(line == "table stopped: the harness's run ended" for _, line in b.rig.journal.drain())
    b.writer.command(0.0, False, b.now)
    b.service(PERIOD)
    assert b.value("RIG_STATUS", "table_running") == 0


def test_two_commands_in_one_poll_are_two_steps(bench):
    b = bench()
    b.start()
    b.writer.command(0.0, True, b.now)
    b.writer.command(0.0, True, b.now)
    b.service()
    assert b.rig.state.step_index == 2


def test_lockstep_runs_are_deterministic_per_seed(bench, profile):
    def run(seed: int) -> list[bytes]:
        b = bench(profile.rig, seed=seed)  # the profile's noise, delays and first-order actuator
        b.start()
        for k in range(150):
            b.step(800.0 * np.sin(0.05 * k))
        return [(m.arbitration_id, bytes(m.data)) for m in b.frames()]

    first, again, other = run(5), run(5), run(6)
    assert len(first) > 600
    assert first == again
    assert first != other


# --------------------------------------------------------------------- sensors, delay
def test_sensor_delay_in_lockstep_is_whole_steps(bench):
    def base_displacements(delay_s: float) -> np.ndarray:
        config = quiet_config(sensors=SensorsConfig(displacement=DisplacementSensorConfig(delay_s=delay_s)))
        b = bench(config)
        b.start()
        values = []
        for _ in range(60):
            b.step(2000.0)
            values.append(b.value("BASE_SENSORS", "y_b"))
        return np.array(values)

    direct, delayed = base_displacements(0.0), base_displacements(0.0041)  # 2.05 steps -> 2 steps
    assert np.ptp(direct) > 1e-4, "the base mat moves"
    np.testing.assert_allclose(delayed[2:], direct[:-2], atol=1e-9)


def test_published_values_match_the_plant_history(bench):
    b = bench()
    b.start()
    for _ in range(30):
        b.step(1500.0)
    state = b.rig.table.y
    assert b.value("BASE_SENSORS", "y_b") == pytest.approx(state[3], abs=1e-6)  # 1 um resolution
    assert b.value("STORY_DRIFTS", "drift_1") == pytest.approx(state[0], abs=2e-6)
    x0, v0, _ = b.rig.table.table_truth()
    assert b.value("TABLE_SENSORS", "x_0") == pytest.approx(x0, abs=1e-6)
    assert b.value("TABLE_SENSORS", "xdot_0") == pytest.approx(v0, abs=1e-5)


def test_real_time_delay_measured_against_plant_time(bench):
    config = quiet_config(sensors=SensorsConfig(displacement=DisplacementSensorConfig(delay_s=0.003)))
    b = bench(config, lockstep=False)
    b.writer.rig_control(RigCommand.START_TABLE, False, 0.0)
    b.service(0.0)
    for _ in range(100):
        b.service(PERIOD)
    rows = b.rig.history.rows()
    x0_published = b.value("TABLE_SENSORS", "x_0")
    now_sub = b.rig.n
    assert now_sub == 400, "real time: 100 services of 2 ms = 400 sub-steps"
    motion = b.rig.table.motion
    record_start = rows[np.isfinite(rows[:, 1])][0, 0]
    expected_time = (now_sub - 6) * b.rig.h - record_start  # 3 ms = 6 sub-steps back
    assert x0_published == pytest.approx(motion.sample(expected_time)[0], abs=1e-6)
    assert abs(motion.sample(expected_time + 0.003)[0] - x0_published) > 5e-6, "the delay is visible"


# --------------------------------------------------------------------------- watchdog
def test_watchdog_trips_when_commands_stop(bench):
    b = bench(quiet_config(drive=DriveConfig(watchdog_timeout_s=0.05)), lockstep=False)
    b.writer.heartbeat(1, b.now)
    b.writer.command(3000.0, True, b.now)
    b.service(0.0)
    b.service(0.004)  # ACTUATOR_STATUS every 4 ms
    assert b.reader.drive_state == DriveState.ENABLED
    for _ in range(19):  # heartbeats continue, commands stopped at t = 0
        b.writer.heartbeat(1, b.now)
        b.service(0.002)
    assert b.rig.state.drive_state == DriveState.ENABLED, "42 ms < 50 ms timeout"
    b.writer.heartbeat(1, b.now)
    b.service(0.01)
    assert b.reader.drive_state == DriveState.FAULT and b.reader.fault_code == FaultCode.COMMAND_WATCHDOG
    force_at_trip = b.rig.state.actuator_force_N
    for _ in range(50):
        b.service(0.002)
    assert abs(b.rig.state.actuator_force_N) < 0.02 * abs(force_at_trip), "force decays to zero"
    b.writer.command(3000.0, True, b.now)
    b.service(0.002)
    assert b.rig.state.drive_state == DriveState.FAULT, "latched"
    b.control(command=RigCommand.RESET)
    b.writer.heartbeat(1, b.now)
    b.service(0.002)
    assert b.rig.state.drive_state == DriveState.READY, "reset clears the latch"


def _ready_in_real_time(bench) -> Bench:
    """A real-time rig whose drive is READY on the harness's heartbeats (0.5 s watchdog)."""
    b = bench(quiet_config(drive=DriveConfig(watchdog_timeout_s=0.5)), lockstep=False)
    for _ in range(5):
        b.writer.heartbeat(1, b.now)
        b.service(b.rig.schedule.sensor_period_s)
    assert b.rig.state.drive_state == DriveState.READY and b.rig.own_stalls == 0
    return b


def test_a_stall_of_the_rig_itself_is_not_a_silent_harness(bench):
    """CI in User-Mode Linux: the rig's process stopped 0.6 s while the harness's heartbeats queued up.

    The drive it emulates never stalls: the heartbeats that waited unread keep it READY.
    """
    b = _ready_in_real_time(bench)
    for _ in range(12):  # the harness goes on at 20 Hz, a command and a heartbeat a tick; the rig is not serviced for 0.6 s
        b.now += 0.05
        b.writer.command(0.0, False, b.now)  # read first: judged as it is read, the watchdog would latch already
        b.writer.heartbeat(1, b.now)
    b.service(0.0)
    assert b.rig.state.drive_state == DriveState.READY and b.rig.own_stalls == 1
    b.service(b.rig.schedule.sensor_period_s)
    assert b.rig.state.drive_state == DriveState.READY and b.rig.own_stalls == 1, "on schedule again"


def test_a_harness_silent_through_the_rigs_stall_still_trips_the_watchdog_in_that_service(bench):
    b = _ready_in_real_time(bench)
    b.service(0.6)  # nothing arrived while the rig stalled: the harness really stopped
    assert b.rig.state.drive_state == DriveState.FAULT and b.rig.state.fault_code == FaultCode.HEARTBEAT_WATCHDOG
    assert b.rig.own_stalls == 1
    assert b.reader.drive_state == DriveState.FAULT, "announced in the same service"


def test_lockstep_watchdog_runs_on_the_wall_clock(bench):
    b = bench(quiet_config(drive=DriveConfig(watchdog_timeout_s=0.05, lockstep_watchdog_timeout_s=1.0)))
    b.start()
    b.step(100.0)
    assert b.rig.state.drive_state == DriveState.ENABLED
    b.service(0.2)  # a slow host: 0.2 s without a step is far past the real-time 50 ms, not past the lockstep bound
    assert b.rig.state.drive_state == DriveState.ENABLED
    b.service(1.3)  # no frames: the lockstep loop's poll timeout calls service with the time
    assert b.rig.state.drive_state == DriveState.FAULT
    assert b.reader.drive_state == DriveState.FAULT, "announced between steps"


# ----------------------------------------------------------------------------- faults
def _rejects(b: Bench, message: str, status: RxStatus) -> int:
    return b.reader.decoder.rejected(message, status)


def test_dropout_stops_one_message_only(bench):
    b = bench()
    b.start()
    b.control(fault_id=fault_id_for("dropout", "BASE_SENSORS"))
    base, table = b.reader.base.count, b.reader.table.count
    b.step(n=10)
    assert b.reader.base.count == base and b.reader.table.count == table + 10
    b.control(fault_id=0)
    b.step()
    assert b.reader.base.count > base, "fault 0 clears"


def test_status_frames_stop(bench):
    b = bench()
    b.start()
    b.control(fault_id=fault_id_for("dropout", "ACTUATOR_STATUS"))
    count = b.reader.status.count
    b.step(n=10)
    assert b.reader.status.count == count and b.value("RIG_STATUS", "fault_active") == 1


@pytest.mark.parametrize(
    "kind, status", [("corrupt_crc", RxStatus.BAD_CRC), ("repeat_counter", RxStatus.REPEATED_COUNTER),
                     ("skip_counter", RxStatus.SKIPPED_COUNTER)]
)
def test_frame_faults_are_rejected_and_counted_by_the_reader(bench, kind, status):
    b = bench()
    b.start()
    b.step(n=3)
    b.control(fault_id=fault_id_for(kind, "TABLE_SENSORS"))
    count = b.reader.table.count
    b.step(n=10)
    assert _rejects(b, "TABLE_SENSORS", status) >= 9
    assert b.reader.table.count <= count + 1, "damaged frames are not accepted"
    assert _rejects(b, "BASE_SENSORS", status) == 0


def test_stuck_values_repeat_while_the_plant_moves(bench):
    b = bench()
    b.start()
    b.step(2000.0, n=5)
    b.control(fault_id=fault_id_for("stuck", "BASE_SENSORS"))
    seen = set()
    for _ in range(20):
        b.step(2000.0)
        seen.add((b.value("BASE_SENSORS", "y_b"), b.value("BASE_SENSORS", "ydot_b")))
    assert len(seen) == 1 and b.reader.base.fresh
    assert abs(b.rig.table.y[3] - next(iter(seen))[0]) > 1e-5, "the plant moved on"


def test_spike_is_one_sample(bench):
    b = bench()
    b.start()
    b.step(n=3)
    b.control(fault_id=fault_id_for("spike", "TABLE_SENSORS"), param=0.02)  # republished at once, with the spike
    values, truth = [b.value("TABLE_SENSORS", "x_0")], [b.rig.table.table_truth()[0]]
    for _ in range(5):
        b.step()
        values.append(b.value("TABLE_SENSORS", "x_0"))
        truth.append(b.rig.table.table_truth()[0])
    errors = np.array(values) - np.array(truth)
    assert abs(errors[0] - 0.02) < 2e-6
    assert np.all(np.abs(errors[1:]) < 2e-6)


def test_noise_burst_adds_noise(bench):
    b = bench()
    b.start()
    b.control(fault_id=fault_id_for("noise_burst", "STORY_DRIFTS"), param=0.001)
    errors = []
    for _ in range(200):
        b.step()
        errors.append(b.value("STORY_DRIFTS", "drift_2") - b.rig.table.y[1])
    assert np.std(errors) == pytest.approx(0.001, rel=0.25)  # 100 story frames


def test_extra_delay_fault_delays_the_sensors(bench):
    b = bench()
    b.start()
    b.control(fault_id=fault_id_for("extra_delay"), param=0.01)  # 5 steps
    values, truth = [], []
    for _ in range(40):
        b.step(3000.0)
        values.append(b.value("BASE_SENSORS", "y_b"))
        truth.append(b.rig.table.y[3])
    np.testing.assert_allclose(values[10:], truth[5:-5], atol=1e-6)


def test_bus_silence_sends_nothing(bench):
    b = bench()
    b.start()
    b.frames()
    b.control(fault_id=fault_id_for("bus_silence"))
    b.step(n=10)
    assert b.frames() == [] and b.rig.state.step_index == 10, "the rig still steps"


def test_drive_fault_pressure_loss_and_rig_estop(bench):
    b = bench()
    b.start()
    b.step(n=2)
    b.control(fault_id=fault_id_for("drive_fault"), param=42)
    assert b.reader.drive_state == DriveState.FAULT and b.reader.fault_code == 42
    b.control(fault_id=0, command=3)
    b.step(n=2)
    assert b.reader.drive_state == DriveState.ENABLED, "reset and fault clear bring the drive back"
    b.control(fault_id=fault_id_for("pressure_lost"))
    assert not b.reader.pressure_ok
    assert b.reader.drive_state == DriveState.FAULT and b.reader.fault_code == FaultCode.PRESSURE_LOST
    b.control(fault_id=fault_id_for("estop"))
    assert b.reader.estop_requested and b.reader.drive_state == DriveState.ESTOP


def test_estop_frame_from_the_harness_latches_estop(bench):
    b = bench()
    b.start()
    b.step(n=2)
    b.link.writer.estop(True, b.now)
    b.step()
    assert b.reader.drive_state == DriveState.ESTOP and b.rig.state.actuator_force_N < 1.0


def test_scheduled_fault_follows_record_time(bench):
    config = quiet_config(faults=(FaultSpec(kind="dropout", target="TABLE_SENSORS", start_s=0.01, duration_s=0.01),))
    b = bench(config)
    b.start()
    counts = []
    for _ in range(15):
        b.step()
        counts.append(b.reader.table.count)
    increments = np.diff([1, *counts])
    # the record starts with step 1, so step k publishes record time 2k ms: steps 5..9 fall in [10 ms, 20 ms)
    assert list(increments) == [1] * 4 + [0] * 5 + [1] * 6


def test_reset_puts_the_plant_at_rest(bench):
    b = bench()
    b.start()
    b.step(3000.0, n=20)
    assert np.any(b.rig.table.y != 0.0)
    b.control(command=RigCommand.RESET)
    state = b.rig.state
    assert np.all(b.rig.table.y == 0.0) and not state.table_running and state.step_index == 0
    assert b.value("RIG_STATUS", "step_index") == 0


# ------------------------------------------------------------------- threads, command
def _poll_until(reader, condition, timeout_s: float = 10.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < deadline, "timed out waiting on the bus"
        reader.poll(time.monotonic())
        time.sleep(0.005)


def test_real_time_thread_plays_the_record(bench, profile):
    b = bench(profile.rig, lockstep=False)
    b.rig.start_thread()
    try:
        b.writer.rig_control(RigCommand.START_TABLE, False, time.monotonic())
        _poll_until(b.reader, lambda: b.reader.sample("RIG_STATUS").count and b.value("RIG_STATUS", "record_time") > 0.2)
        assert b.reader.table.count > 20 and b.reader.sample("STORY_DRIFTS").count > 10
        assert b.value("RIG_STATUS", "lockstep") == 0
    finally:
        b.rig.stop()


def test_run_rig_command_serves_and_stops_cleanly(monkeypatch):
    channel = f"cmd-{uuid.uuid4().hex[:10]}"
    link = open_harness(CanConfig(channel=channel))
    stop = threading.Event()
    result = {}
    ready = threading.Event()
    frozen_before_serving = []
    monkeypatch.setattr(rig_service, "freeze_garbage", lambda: frozen_before_serving.append(not ready.is_set()))

    def target() -> None:
        result["status"] = run_rig_command(
            PROFILES / "nceer_4dof.yaml", interface="virtual", channel=channel,
            options=StudyOptions(record="synthetic", duration_s=3.0), stop_event=stop, on_ready=lambda rig: ready.set(),
        )

    thread = threading.Thread(target=target)
    thread.start()
    try:
        assert ready.wait(30.0)
        _poll_until(link.reader, lambda: link.reader.status.count > 5)
        time.sleep(0.3)
        stop.set()
        thread.join(10.0)
        assert not thread.is_alive() and result["status"] == exit_codes.OK
        assert frozen_before_serving == [True], "the garbage collector frozen once, before the rig served"
        link.reader.poll(time.monotonic())
        assert link.reader.drive_state == DriveState.OFF, "the last status says the drive is off"
    finally:
        stop.set()
        link.close()


def test_a_failed_bus_ends_the_service_thread_with_the_error(bench):
    b = bench(lockstep=False)
    b.rig.start_thread()
    b.rig_link.close()
    deadline = time.monotonic() + 10.0
    while b.rig.serving:
        assert time.monotonic() < deadline, "the thread must end when the bus is gone"
        time.sleep(0.01)
    assert isinstance(b.rig.error, BusError)
    b.rig.stop()  # still safe: drive off, the failed send is only counted


def test_ctrl_c_stops_a_rig_process_cleanly():
    code = (
        "import sys\n"
        "from harness.runs.rig_service import run_rig_command\n"
        "from harness.runs.options import StudyOptions\n"
        f"sys.exit(run_rig_command({str(PROFILES / 'nceer_4dof.yaml')!r}, interface='virtual', channel='sigint', "
        "options=StudyOptions(record='synthetic', duration_s=3.0), on_ready=lambda rig: print('ready', flush=True)))\n"
    )
    # an operator's terminal delivers Ctrl-C; a suite started as a background job would hand the rig SIGINT ignored
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=PROFILES.parent,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        assert process.stdout.readline().strip() == b"ready", process.stderr.read().decode()[-2000:]
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20) == exit_codes.STOPPED, process.stderr.read().decode()[-2000:]
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()


def test_step_lockstep_in_process_equals_command_frames(bench):
    over_bus, in_process = bench(), bench()
    over_bus.start()
    in_process.start()
    forces = [500.0 * k for k in range(12)]
    for force in forces:
        over_bus.step(force)
        in_process.rig.step_lockstep(force, True, in_process.now)
    np.testing.assert_array_equal(over_bus.rig.history.rows(), in_process.rig.history.rows())
    assert in_process.rig.state.step_index == 12 and in_process.rig.state.command_N == forces[-1]
