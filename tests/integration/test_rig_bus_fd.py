"""The virtual rig on the CAN FD protocol (``can.fd: true``), read with the harness-side drivers.

In-process on the python-can virtual bus with a made-up clock, as tests/integration/test_rig_bus.py:
the rig sends the whole sensor set as one SENSOR_SET FD frame with bit-rate switching, the
harness's reader hands its parts to the four sensor messages' samples, frame-level faults of
any sensor message act on the one frame, and the harness's own frames are FD frames too.
"""

from __future__ import annotations

import dataclasses
import math
import uuid

import can
import pytest

from drivers.protocol.decoder import RxStatus
from drivers.protocol.e2e import protect
from drivers.protocol.protocol_values import RigCommand
from harness.canbus.config import CanConfig
from harness.canbus.link import open_rig
from harness.profile import load_profile
from harness.rig.config import ActuatorConfig, DriveConfig, RigConfig
from harness.rig.faults import fault_id_for
from harness.rig.virtual_rig import RigParts, VirtualRig
from harness.runs.options import StudyOptions, prepare_motion
from tests.conftest import PROFILES
from tests.integration.test_rig_bus import Bench

PERIOD = 0.0005  # 2 kHz, one physics sub-step
SENSOR_SET_ID, TABLE_ID, BASE_ID, DRIFTS_ID, ACCELS_ID = 0x32, 0x30, 0x31, 0x200, 0x201


@pytest.fixture(scope="module")
def profile():
    return load_profile(PROFILES / "nceer_4dof.yaml")


@pytest.fixture(scope="module")
def motion(profile):
    return prepare_motion(profile, StudyOptions(record="synthetic", duration_s=2.0))


class FdBench(Bench):
    """The bench of tests/integration/test_rig_bus.py on a fresh virtual channel with the FD protocol at 2 kHz."""

    def __init__(self, profile, motion):
        can_config = CanConfig(channel=f"fd-{uuid.uuid4().hex[:10]}", fd=True, loop_rate_hz=2000.0)
        config = RigConfig(actuator=ActuatorConfig(model="ideal", force_rate_limit_N_per_s=1e9),
                           drive=DriveConfig(watchdog_timeout_s=10.0))
        super().__init__(profile, motion, config, can_config=can_config, period_s=PERIOD)
        self.can = can_config

    def frames(self, every_id: bool = True) -> list[can.Message]:
        """Every frame on the bus since the last call."""
        return super().frames(every_id)


@pytest.fixture
def bench(profile, motion):
    made = []

    def make() -> FdBench:
        b = FdBench(profile, motion)
        made.append(b)
        return b

    yield make
    for b in made:
        b.close()


def test_every_frame_on_the_fd_bus_is_an_fd_frame_and_the_sensors_travel_as_one_set(bench):
    b = bench()
    b.start()
    b.frames()
    b.step(200.0, n=20)
    frames = b.frames()
    ids = [m.arbitration_id for m in frames]
    assert all(m.is_fd and m.bitrate_switch for m in frames), "every frame, the harness's and the rig's, is FD with BRS"
    assert ids.count(SENSOR_SET_ID) == 20, "one sensor set per lockstep step"
    assert not {TABLE_ID, BASE_ID, DRIFTS_ID, ACCELS_ID} & set(ids), "the four classic sensor messages are not sent"
    assert all(len(m.data) == 32 for m in frames if m.arbitration_id == SENSOR_SET_ID)
    assert {0x20, 0x50} <= set(ids), "the harness's command and heartbeat went out (as FD frames)"


def test_the_harness_reads_the_set_into_the_four_sensor_samples(bench):
    b = bench()
    b.start()
    b.step(500.0, n=200)
    reader = b.reader
    sensor_set = reader.sample("SENSOR_SET")
    assert sensor_set.count >= 200
    for name in ("TABLE_SENSORS", "BASE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS"):
        sample = reader.sample(name)
        assert sample.count == sensor_set.count and sample.fresh and sample.rx_time == b.now
        assert sample.last_status == RxStatus.OK
    table, base = reader.sample("TABLE_SENSORS"), reader.sample("BASE_SENSORS")
    assert table["x_0"] == sensor_set["x_0"] and base["ydot_b"] == sensor_set["ydot_b"]
    assert reader.sample("FLOOR_ACCELS")["accel_3"] == sensor_set["accel_3"]
    assert reader.sample("STORY_DRIFTS")["drift_2"] == sensor_set["drift_2"]
    assert any(v != 0.0 for v in table.values), "the table moves: real values, not zeros"
    assert reader.decoder.rejected_total == 0


@pytest.mark.parametrize("target", ["TABLE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS"])
def test_a_frame_fault_of_any_sensor_message_acts_on_the_one_frame(bench, target):
    b = bench()
    b.start()
    b.step(n=5)
    b.writer.rig_control(RigCommand.NONE, True, b.now, fault_id_for("corrupt_crc", target), 0.0)
    b.service()
    before = b.reader.decoder.rejected("SENSOR_SET", RxStatus.BAD_CRC)
    b.step(n=10)
    assert b.reader.decoder.rejected("SENSOR_SET", RxStatus.BAD_CRC) >= before + 10
    assert b.reader.sample("TABLE_SENSORS").last_status == RxStatus.BAD_CRC
    assert not b.reader.e2e_ok()


def test_a_value_fault_stays_in_its_own_block(bench):
    b = bench()
    b.start()
    b.step(n=5)
    b.writer.rig_control(RigCommand.NONE, True, b.now, fault_id_for("stuck", "FLOOR_ACCELS"), 0.0)
    b.service()
    b.step(500.0, n=2)
    stuck = list(b.reader.sample("FLOOR_ACCELS").values)
    table = list(b.reader.sample("TABLE_SENSORS").values)
    b.step(500.0, n=40)
    assert b.reader.sample("FLOOR_ACCELS").values == stuck
    assert b.reader.sample("TABLE_SENSORS").values != table
    assert b.reader.decoder.rejected_total == 0


def test_an_out_of_range_value_in_the_set_poisons_the_control_measurements(bench):
    b = bench()
    b.start()
    b.step(n=3)
    codec = b.link.protocol["SENSOR_SET"]
    accels_before = list(b.reader.sample("FLOOR_ACCELS").values)
    data = bytearray(codec.length)
    codec.pack(data, [0.0] * len(codec.signals))
    word = int.from_bytes(data, "little") | (0x7FFFF << 12)  # x_0 raw 524287: inside the field, beyond 0.5 m
    data[:] = word.to_bytes(codec.length, "little")
    protect(data, b.rig_link.writer.frame("SENSOR_SET").counter, codec.data_ids)
    b.listener.send(can.Message(arbitration_id=codec.frame_id, data=data, is_fd=True, bitrate_switch=True,
                                is_extended_id=False))
    b.reader.poll(b.now)
    assert all(math.isnan(v) for v in b.reader.sample("TABLE_SENSORS").values)
    assert all(math.isnan(v) for v in b.reader.sample("BASE_SENSORS").values)
    assert b.reader.sample("FLOOR_ACCELS").values == accels_before, "a logging block is not poisoned"
    assert b.reader.sample("TABLE_SENSORS").last_status == RxStatus.OUT_OF_RANGE


def test_classic_frames_on_the_fd_bus_are_rejected_not_read(bench):
    b = bench()
    b.start()
    b.step(n=3)
    table = b.link.protocol["TABLE_SENSORS"]
    data = bytearray(table.length)
    table.encode_into(data, [0.1, 0.0, 0.0], 0)
    b.listener.send(can.Message(arbitration_id=table.frame_id, data=data, is_fd=False, is_extended_id=False))
    b.reader.poll(b.now)
    assert b.reader.decoder.rejected("TABLE_SENSORS", RxStatus.NOT_DATA) == 1
    assert b.reader.sample("TABLE_SENSORS")["x_0"] != pytest.approx(0.1)


def test_the_fd_rig_in_real_time_sends_the_set_at_the_sensor_rate(profile, motion):
    can_config = CanConfig(channel=f"fd-{uuid.uuid4().hex[:10]}", fd=True, loop_rate_hz=2000.0)
    with open_rig(can_config) as rig_link, can.Bus(interface="virtual", channel=can_config.channel) as listener:
        config = dataclasses.replace(RigConfig(), drive=DriveConfig(watchdog_timeout_s=10.0))
        parts = RigParts(profile.structure, profile.bearing, config, profile.simulation.rtol)
        rig = VirtualRig(parts, motion, rig_link, step_period_s=PERIOD, lockstep=False, can_config=can_config)
        for k in range(1, 201):  # 0.1 s of rig time, serviced every period
            rig.service(k * PERIOD)
        ids = []
        while (msg := listener.recv(timeout=0)) is not None:
            ids.append(msg.arbitration_id)
        assert 199 <= ids.count(SENSOR_SET_ID) <= 201, "2000 Hz for 0.1 s"
        assert not {TABLE_ID, BASE_ID, DRIFTS_ID, ACCELS_ID} & set(ids)
