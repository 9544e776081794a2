"""drivers/reader.py, drivers/rig_reader.py, drivers/writer.py, drivers/transports/bus.py's BusHealth: samples, ages, counts."""

from __future__ import annotations

import errno
import math
import time
import uuid
from collections import deque
from collections.abc import Iterable

import can
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers import rig_reader
from drivers.errors import BusError, ProtocolError
from drivers.link import open_harness, open_rig
from drivers.measurements import Measurements
from drivers.protocol.codec import load_protocol
from drivers.protocol.decoder import RxStatus
from drivers.protocol.protocol_values import DriveState, FaultCode, RigCommand
from drivers.reader import FrameReader, HarnessReader, damaged_estop
from drivers.rig_reader import RigReader
from drivers.transports import bus as busmod
from drivers.transports.bus import BusHealth, open_bus
from drivers.writer import HarnessWriter, RigWriter

PROTOCOL = load_protocol()
#: A modest rate for every message (Hz), for the links opened here.
RATES_HZ = {name: 50.0 for name in PROTOCOL.messages}


class FakeBus:
    """Just enough of can.BusABC: a receive queue, a sent list, an optional send error."""

    def __init__(self, frames: Iterable[can.Message] = (), send_error: BaseException | None = None):
        self.rx: deque[can.Message] = deque(frames)
        self.sent: list[tuple[can.Message, bytes]] = []
        self.send_error = send_error
        self.recv_error: BaseException | None = None

    def recv(self, timeout: float | None = None) -> can.Message | None:
        if self.recv_error is not None:
            raise self.recv_error
        return self.rx.popleft() if self.rx else None

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        if self.send_error is not None:
            raise self.send_error
        self.sent.append((msg, bytes(msg.data)))


def frame(name: str, values: list[float], counter: int = 0, *, timestamp: float = 0.0, is_rx: bool = True) -> can.Message:
    codec = PROTOCOL[name]
    return can.Message(
        arbitration_id=codec.frame_id, is_extended_id=False, data=codec.encode(values, counter),
        timestamp=timestamp, is_rx=is_rx,
    )


def error_frame(error_class: int, ctrl: int = 0) -> can.Message:
    data = bytearray(8)
    data[1] = ctrl
    return can.Message(arbitration_id=error_class, is_error_frame=True, dlc=8, data=data)


def harness_reader(bus: FakeBus, **kwargs: object) -> HarnessReader:
    return HarnessReader(bus, PROTOCOL, **kwargs)  # type: ignore[arg-type]


# --- reader: latest sample and age ----------------------------------------------------


def test_reader_keeps_latest_sample_with_receive_time_and_age() -> None:
    bus = FakeBus([frame("TABLE_SENSORS", [0.01, 0.1, 1.0], 0), frame("TABLE_SENSORS", [0.02, 0.2, 2.0], 1)])
    reader = harness_reader(bus)
    assert reader.age("TABLE_SENSORS", 0.0) == math.inf
    assert reader.poll(now=1.0) == 2
    table = reader.sample("TABLE_SENSORS")
    assert table.values == pytest.approx([0.02, 0.2, 2.0])
    assert table["x_0"] == pytest.approx(0.02)
    assert table.count == 2 and table.rx_time == 1.0 and table.fresh
    assert reader.age("TABLE_SENSORS", 1.25) == pytest.approx(0.25)
    assert reader.poll(now=2.0) == 0
    assert not table.fresh
    assert table.rx_time == 1.0 and reader.age("TABLE_SENSORS", 2.0) == pytest.approx(1.0)
    assert reader.age("BASE_SENSORS", 2.0) == math.inf


def test_reader_can_take_receive_time_from_the_frame() -> None:
    # the frame's wall-clock stamp, 0.25 s before the poll, moved onto the loop's clock
    bus = FakeBus([frame("BASE_SENSORS", [0.0, 0.0, 0.0], timestamp=time.time() - 0.25)])
    reader = harness_reader(bus, use_msg_timestamp=True)
    reader.poll(now=999.0)
    assert reader.sample("BASE_SENSORS").rx_time == pytest.approx(999.0 - 0.25, abs=0.05)
    assert reader.sample("BASE_SENSORS").age(999.0) == pytest.approx(0.25, abs=0.05)


def test_rejected_frames_do_not_touch_the_sample_and_are_counted() -> None:
    good = frame("TABLE_SENSORS", [0.01, 0.0, 0.0], 0)
    corrupt = frame("TABLE_SENSORS", [0.05, 0.0, 0.0], 1)
    corrupt.data[3] ^= 0x01
    repeated = frame("TABLE_SENSORS", [0.06, 0.0, 0.0], 0)
    short = can.Message(arbitration_id=0x30, is_extended_id=False, data=bytes(6))
    reader = harness_reader(FakeBus([good, corrupt, repeated, short]))
    assert reader.poll(now=1.0) == 4
    table = reader.sample("TABLE_SENSORS")
    assert table.values[0] == pytest.approx(0.01) and table.count == 1
    assert reader.decoder.counts[RxStatus.BAD_CRC] == 1
    assert reader.decoder.counts[RxStatus.REPEATED_COUNTER] == 1
    assert reader.decoder.counts[RxStatus.WRONG_LENGTH] == 1
    assert reader.e2e_rejects == 3
    assert table.last_status == RxStatus.WRONG_LENGTH and not reader.e2e_ok()
    assert reader.counters.frames == 4


def test_extended_id_with_a_protocol_number_is_not_that_message() -> None:
    good = frame("TABLE_SENSORS", [0.01, 0.0, 0.0], 0)
    alien = can.Message(arbitration_id=0x30, is_extended_id=True, data=bytes(8))
    reader = harness_reader(FakeBus([good, alien]))
    reader.poll(1.0)
    assert reader.e2e_ok() and reader.sample("TABLE_SENSORS").count == 1
    assert reader.decoder.counts[RxStatus.UNKNOWN_ID] == 1


def test_e2e_ok_recovers_with_the_next_good_frame() -> None:
    bus = FakeBus([frame("TABLE_SENSORS", [0.0] * 3, 0), frame("TABLE_SENSORS", [0.0] * 3, 2)])
    reader = harness_reader(bus)
    reader.poll(1.0)
    assert not reader.e2e_ok()
    bus.rx.append(frame("TABLE_SENSORS", [0.0] * 3, 3))
    reader.poll(2.0)
    assert reader.e2e_ok()


def test_fill_measurements_and_sensor_age() -> None:
    bus = FakeBus([frame("TABLE_SENSORS", [0.011, 0.12, 0.0]), frame("BASE_SENSORS", [-0.002, 0.034, 0.0])])
    reader = harness_reader(bus)
    assert reader.sensor_age(0.0) == math.inf
    assert (reader.drive_state, reader.pressure_ok) == (DriveState.OFF, False)  # safe before any status frame
    assert not reader.drive_ready and not reader.drive_fault
    reader.poll(now=5.0)
    meas = Measurements()
    reader.fill(meas)
    assert (meas.table_displacement_m, meas.table_velocity_m_s) == pytest.approx((0.011, 0.12))
    assert (meas.base_displacement_m, meas.base_velocity_m_s) == pytest.approx((-0.002, 0.034))
    assert reader.sensor_age(5.5) == pytest.approx(0.5)


def test_poll_is_bounded_by_max_frames() -> None:
    frames = [frame("HEARTBEAT", [1.0], c) for c in range(5)]
    reader = FrameReader(FakeBus(frames), PROTOCOL, ["HEARTBEAT"], max_frames=2)  # type: ignore[arg-type]
    assert [reader.poll(0.0), reader.poll(0.0), reader.poll(0.0)] == [2, 2, 1]
    assert reader.counters.polls_capped == 2
    assert reader.sample("HEARTBEAT").count == 5


def test_receive_failure_is_a_bus_error() -> None:
    bus = FakeBus()
    bus.recv_error = can.CanOperationError("interface went away")
    with pytest.raises(BusError, match="interface went away"):
        harness_reader(bus).poll(0.0)


# --- reader: foreign commands and E-stop ----------------------------------------------


def test_any_actuator_command_frame_is_foreign_even_from_this_host() -> None:
    # socketcan marks frames from any process on this host is_rx=False; they are still foreign
    bus = FakeBus([frame("ACTUATOR_CMD", [1.0, 100.0], is_rx=False)])
    reader = harness_reader(bus)
    assert not reader.foreign_command_seen
    reader.poll(1.0)
    assert reader.foreign_command_seen
    bus.rx.append(frame("ACTUATOR_CMD", [1.0, 100.0], is_rx=True))
    reader.poll(2.0)
    assert reader.counters.foreign_commands == 2 and reader.counters.last_foreign_time == 2.0
    assert reader.decoder.counts[RxStatus.UNKNOWN_ID] == 0


def test_own_commands_are_not_foreign_over_a_bus() -> None:
    channel = f"own-{uuid.uuid4().hex}"
    with open_bus("virtual", channel) as harness_bus, open_bus("virtual", channel) as other_bus:
        writer, reader = HarnessWriter(harness_bus, PROTOCOL), HarnessReader(harness_bus, PROTOCOL)
        assert writer.command(100.0, True, now=0.0)
        reader.poll(0.0)
        assert not reader.foreign_command_seen
        assert HarnessWriter(other_bus, PROTOCOL).command(100.0, True, now=0.0)
        assert _drain(reader, 1) == 1
        assert reader.foreign_command_seen


def test_estop_valid_active_latches_until_cleared() -> None:
    bus = FakeBus([frame("ESTOP", [0.0, 3.0, 0.0], 0)])
    reader = harness_reader(bus)
    reader.poll(1.0)
    assert not reader.estop_requested and reader.counters.estop_frames == 1
    bus.rx.append(frame("ESTOP", [1.0, 3.0, 7.0], 1))
    reader.poll(2.0)
    assert reader.estop_requested and reader.counters.last_estop_time == 2.0
    bus.rx.append(frame("ESTOP", [0.0, 3.0, 0.0], 2))
    reader.poll(3.0)
    assert reader.estop_requested  # a release frame does not clear the latch
    reader.clear_estop()
    assert not reader.estop_requested


@pytest.mark.parametrize("damage", ["crc", "length", "skipped"])
def test_damaged_estop_frames_fail_safe(damage: str) -> None:
    bus = FakeBus([frame("ESTOP", [0.0, 0.0, 0.0], 0)])
    reader = harness_reader(bus)
    reader.poll(1.0)
    if damage == "crc":
        bad = frame("ESTOP", [0.0, 0.0, 0.0], 1)
        bad.data[2] ^= 0x80
    elif damage == "length":
        bad = can.Message(arbitration_id=0x10, is_extended_id=False, data=bytes(2))
    else:
        bad = frame("ESTOP", [1.0, 1.0, 0.0], 5)  # valid CRC, counter jumped, active
    bus.rx.append(bad)
    reader.poll(2.0)
    assert reader.estop_requested


def _unreadable_estop(damage: str) -> can.Message:
    estop_id = PROTOCOL["ESTOP"].frame_id
    if damage == "crc":
        bad = frame("ESTOP", [0.0, 0.0, 0.0], 1)
        bad.data[2] ^= 0x80
        return bad
    if damage == "length":
        return can.Message(arbitration_id=estop_id, is_extended_id=False, data=bytes(2))
    return can.Message(arbitration_id=estop_id, is_extended_id=False, is_remote_frame=True, dlc=8)


@pytest.mark.parametrize("damage", ["crc", "length", "remote"])
def test_both_sides_take_an_unreadable_estop_frame_for_a_stop_request(damage: str) -> None:
    release = frame("ESTOP", [0.0, 0.0, 0.0], 0)
    harness = harness_reader(FakeBus([release, _unreadable_estop(damage)]))
    harness.poll(1.0)
    assert harness.estop_requested
    rig = RigReader(FakeBus([release, _unreadable_estop(damage)]), PROTOCOL)  # type: ignore[arg-type]
    assert rig.receive() == rig_reader.OTHER  # an intact release is no stop
    assert rig.receive() == rig_reader.ESTOP


@pytest.mark.parametrize("counter", [0, 5])  # repeated, skipped
def test_both_sides_take_an_active_estop_out_of_sequence_for_a_stop_request(counter: int) -> None:
    release = frame("ESTOP", [0.0, 0.0, 0.0], 0)
    late_stop = frame("ESTOP", [1.0, 1.0, 0.0], counter)  # intact, active, its counter refused
    late_release = frame("ESTOP", [0.0, 0.0, 0.0], counter)
    harness = harness_reader(FakeBus([release, late_stop]))
    harness.poll(1.0)
    assert harness.estop_requested
    rig = RigReader(FakeBus([release, late_stop, release, late_release]), PROTOCOL)  # type: ignore[arg-type]
    assert rig.receive() == rig_reader.OTHER
    assert rig.receive() == rig_reader.ESTOP, "an active stop out of sequence is still a stop on the rig too"
    rig.receive()
    assert rig.receive() == rig_reader.REJECTED, "a release out of sequence is refused, and no stop"


def test_only_a_frame_that_cannot_be_read_is_a_damaged_estop() -> None:
    unreadable = {status for status in RxStatus if damaged_estop(status)}
    assert unreadable == {RxStatus.NOT_DATA, RxStatus.WRONG_LENGTH, RxStatus.BAD_CRC}


def test_skipped_counter_release_frame_does_not_latch() -> None:
    bus = FakeBus([frame("ESTOP", [0.0, 0.0, 0.0], 0), frame("ESTOP", [0.0, 0.0, 0.0], 9)])
    reader = harness_reader(bus)
    reader.poll(1.0)
    assert not reader.estop_requested
    assert reader.decoder.counts[RxStatus.SKIPPED_COUNTER] == 1


# --- bus health: error frames -----------------------------------------------------------


def test_error_frames_are_classified_and_not_decoded() -> None:
    frames = [
        error_frame(busmod.CAN_ERR_CRTL, busmod.CAN_ERR_CRTL_TX_WARNING),
        error_frame(busmod.CAN_ERR_CRTL, busmod.CAN_ERR_CRTL_TX_PASSIVE),
        error_frame(busmod.CAN_ERR_PROT | busmod.CAN_ERR_BUSERROR),
        error_frame(busmod.CAN_ERR_ACK),
    ]
    reader = harness_reader(FakeBus(frames))
    assert reader.poll(1.0) == 4
    health = reader.health
    assert health.error_frames == 4
    assert health.error_warning_events == 1 and health.error_passive_events == 1
    assert health.state == can.BusState.PASSIVE and health.error_passive and not health.bus_off
    assert health.protocol_errors == 1 and health.ack_errors == 1
    assert sum(reader.decoder.counts) == 0


def test_bus_off_latches_until_restarted() -> None:
    bus = FakeBus([error_frame(busmod.CAN_ERR_BUSOFF)])
    reader = harness_reader(bus)
    reader.poll(1.0)
    assert reader.health.bus_off and reader.health.bus_off_events == 1
    assert reader.health.last_error_time == 1.0
    bus.rx.append(error_frame(busmod.CAN_ERR_CRTL, busmod.CAN_ERR_CRTL_RX_PASSIVE))
    reader.poll(2.0)
    assert reader.health.bus_off and not reader.health.error_passive  # error-passive does not undo bus-off
    bus.rx.append(error_frame(busmod.CAN_ERR_RESTARTED))
    reader.poll(3.0)
    assert not reader.health.bus_off and not reader.health.error_passive and reader.health.restarts == 1


# --- writer: counters, reuse, send failures -------------------------------------------


def test_writer_counter_sequence_wraps_and_frames_decode_in_order() -> None:
    bus = FakeBus()
    writer = HarnessWriter(bus, PROTOCOL)  # type: ignore[arg-type]
    for k in range(20):
        assert writer.command(float(k), True, now=k * 0.002)
    counters = [data[1] & 0x0F for _, data in bus.sent]
    assert counters == [k % 16 for k in range(20)]
    rig = RigReader(FakeBus(), PROTOCOL)  # type: ignore[arg-type]
    statuses = [rig.decoder.decode(0x20, data) for _, data in bus.sent]
    assert statuses == [RxStatus.OK] * 20
    assert rig.decoder.values("ACTUATOR_CMD") == [1.0, 19.0]
    assert writer.frame("ACTUATOR_CMD").sent == 20


def test_writer_reuses_one_message_object_and_buffer() -> None:
    bus = FakeBus()
    writer = HarnessWriter(bus, PROTOCOL)  # type: ignore[arg-type]
    buffer = writer.frame("HEARTBEAT").msg.data
    for state in (1, 2, 3):
        writer.heartbeat(state, now=float(state))
    msgs = [msg for msg, _ in bus.sent]
    assert all(m is msgs[0] for m in msgs) and msgs[0].data is buffer
    assert [data for _, data in bus.sent] != [bus.sent[0][1]] * 3  # contents did change
    assert msgs[0].timestamp == 3.0


def test_enobufs_is_counted_and_does_not_advance_the_counter() -> None:
    full = can.CanOperationError("Failed to transmit: No buffer space available", errno.ENOBUFS)
    bus = FakeBus(send_error=full)
    health = BusHealth()
    writer = HarnessWriter(bus, PROTOCOL, health)  # type: ignore[arg-type]
    assert writer.command(10.0, True, now=1.0) is False
    assert writer.command(10.0, True, now=1.002) is False
    assert health.send_failures == 2 and health.tx_queue_full == 2
    assert health.last_error_time == 1.002 and "No buffer space" in health.last_send_error
    bus.send_error = None
    assert writer.command(10.0, True, now=1.004) is True
    assert bus.sent[0][1][1] & 0x0F == 0


@pytest.mark.parametrize(
    "err",
    [can.CanOperationError("Failed to transmit: Network is down", errno.ENETDOWN), OSError(errno.EBADF, "Bad file descriptor")],
)
def test_other_send_errors_are_failures_but_not_queue_full(err: BaseException) -> None:
    writer = HarnessWriter(FakeBus(send_error=err), PROTOCOL)  # type: ignore[arg-type]
    assert not writer.heartbeat(1, now=0.0)
    assert writer.health.send_failures == 1 and writer.health.tx_queue_full == 0
    assert writer.send_failures == 1


def test_out_of_range_command_is_a_caller_error_not_a_send() -> None:
    bus = FakeBus()
    writer = HarnessWriter(bus, PROTOCOL)  # type: ignore[arg-type]
    with pytest.raises(ProtocolError, match="ACTUATOR_CMD.force"):
        writer.command(40_000.0, True, now=0.0)
    assert bus.sent == [] and writer.frame("ACTUATOR_CMD").counter == 0


# --- both sides over a virtual bus ---------------------------------------------------------


def test_harness_and_rig_talk_over_a_virtual_bus() -> None:
    channel = f"io-{uuid.uuid4().hex}"
    with open_bus("virtual", channel) as harness_bus, open_bus("virtual", channel) as rig_bus:
        hw, hr = HarnessWriter(harness_bus, PROTOCOL), HarnessReader(harness_bus, PROTOCOL)
        rw, rr = RigWriter(rig_bus, PROTOCOL), RigReader(rig_bus, PROTOCOL)
        assert rw.table(0.1, -0.2, 3.0, 0.0) and rw.base(0.05, 0.01, -1.0, 0.0)
        assert rw.drifts(0.001, -0.002, 0.003, 0.0) and rw.accels(1.5, -2.5, 3.5, 0.0)
        assert rw.actuator_status(-1234.0, DriveState.ENABLED, True, FaultCode.NONE, 0.0)
        assert rw.rig_status(True, True, False, 12.3456, (1 << 24) + 7, 0.0)
        assert hw.command(2500.0, True, 0.0) and hw.heartbeat(3, 0.0)
        assert hw.rig_control(RigCommand.START_TABLE, True, 0.0, fault_id=2, fault_param=0.004)
        assert _drain(hr, 6) == 6
        assert [rr.receive(0.0) for _ in range(4)] == [rig_reader.COMMAND, rig_reader.HEARTBEAT, rig_reader.CONTROL,
                                                       rig_reader.NOTHING]
        assert hr.sample("STORY_DRIFTS").values == pytest.approx([0.001, -0.002, 0.003])
        assert hr.sample("FLOOR_ACCELS").values == pytest.approx([1.5, -2.5, 3.5])
        assert hr.status.values == pytest.approx([2.0, 1.0, 0.0, -1234.0])
        assert (hr.drive_state, hr.pressure_ok, hr.fault_code, hr.measured_force_n) == (2, True, 0, -1234.0)
        assert hr.drive_ready and not hr.drive_fault
        assert hr.sample("RIG_STATUS").values == pytest.approx([1.0, 1.0, 0.0, 0.0, 12.3456, 7.0])  # start_refused 0
        assert rr.command == [1.0, 2500.0] and rr.heartbeat == [3.0]
        assert rr.control == pytest.approx([1.0, 1.0, 2.0, 0.004], rel=1e-6)
        assert hr.e2e_ok() and rr.decoder.counts[RxStatus.OK] == 3 and not hr.foreign_command_seen


def test_links_open_both_sides_and_close_idempotently() -> None:
    channel = f"link-{uuid.uuid4().hex}"
    with open_harness("virtual", channel, 1_000_000, RATES_HZ) as harness, \
            open_rig("virtual", channel, 1_000_000, RATES_HZ) as rig:
        assert harness.reader.health is harness.health and harness.writer.health is harness.health
        assert 0 < harness.load.share <= 0.5
        assert rig.writer.table(0.003, 0.0, 0.0, now=0.0)
        assert harness.writer.command(-50.0, False, now=0.0)
        rig_side = RigReader(rig.bus, rig.protocol)
        assert _drain(harness.reader, 1) == 1 and rig_side.receive(1.0) == rig_reader.COMMAND
        assert harness.reader.table.values[0] == pytest.approx(0.003)
        assert rig_side.command == [0.0, -50.0]
    harness.close()  # again, after the with block: no error
    assert harness.writer.heartbeat(1, now=0.0) is False


def _drain(reader: FrameReader, expected: int) -> int:
    """Poll until ``expected`` frames arrived (the virtual bus delivers synchronously; bounded)."""
    total = 0
    for _ in range(100):
        total += reader.poll(0.0)
        if total >= expected:
            break
    return total


@st.composite
def any_frame(draw: st.DrawFn) -> can.Message:
    extended = draw(st.booleans())
    frame_id = draw(st.integers(0, 0x1FFFFFFF if extended else 0x7FF) | st.sampled_from(sorted(PROTOCOL.by_id)))
    kind = draw(st.sampled_from(["data", "data", "data", "remote", "error"]))
    data = draw(st.binary(min_size=0, max_size=8)) if kind != "remote" else b""
    return can.Message(
        arbitration_id=frame_id & (0x1FFFFFFF if extended else 0x7FF), is_extended_id=extended, data=data,
        dlc=len(data) if kind != "remote" else draw(st.integers(0, 8)),
        is_remote_frame=kind == "remote", is_error_frame=kind == "error", is_rx=draw(st.booleans()),
    )


@settings(max_examples=200, deadline=None)
@given(st.lists(any_frame(), max_size=40))
def test_reader_fed_arbitrary_frames_never_raises_and_accounts_for_each(frames: list[can.Message]) -> None:
    reader = harness_reader(FakeBus(frames))
    assert reader.poll(now=1.0) == len(frames)
    accounted = sum(reader.decoder.counts) + reader.health.error_frames + reader.counters.foreign_commands
    assert accounted == len(frames)
    assert reader.health.error_frames == sum(1 for f in frames if f.is_error_frame)
