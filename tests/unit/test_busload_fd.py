"""CAN FD in the bus-load check (drivers/protocol/busload.py), the profile's ``can.fd`` keys and the FD links.

The frame lengths are counted here field by field from the FD base frame format of
ISO 11898-1:2015, independently of the module's formula, so a wrong term in either shows.
"""

from __future__ import annotations

import dataclasses
import uuid
from pathlib import Path

import can
import pytest

from drivers.errors import BusError, BusLoadError
from drivers.link import open_harness, open_rig
from drivers.protocol.busload import bus_load, check_bus_load, fd_frame_bits, frame_bits, frame_time_s
from drivers.protocol.codec import load_protocol
from drivers.transports.bus import open_bus, socketcan_preflight
from harness.canbus.config import CanConfig
from harness.canbus.link import prepare
from harness.errors import ProfileError
from harness.profile import load_profile
from tests.conftest import PROFILES, edited_dbc

CLASSIC = load_protocol()
FD = load_protocol(fd=True)


def by_hand(length: int) -> tuple[int, int]:
    """(nominal, data) worst-case bits of an FD base frame with ``length`` data bytes, field by field."""
    sof, base_id, rrs, ide, fdf, res, brs = 1, 11, 1, 1, 1, 1, 1
    arbitration = sof + base_id + rrs + ide + fdf + res + brs  # 17, at the nominal rate
    esi, dlc = 1, 4
    stuffed = arbitration + esi + dlc + 8 * length  # SOF to the end of the data field: dynamic stuffing
    stuff_total = (stuffed - 1) // 4  # one per 4 bits after the first 5
    stuff_arbitration = (arbitration - 1) // 4  # 4: as many as the arbitration phase can hold
    crc = 17 if length <= 16 else 21
    stuff_count = 3 + 1  # Gray-coded count and parity
    crc_field = stuff_count + crc
    fixed = 1 + (crc_field - 1) // 4  # one before the field, one after every 4 bits of it
    crc_delimiter, ack, ack_delimiter, eof, ifs = 1, 1, 1, 7, 3
    nominal = arbitration + stuff_arbitration + crc_delimiter + ack + ack_delimiter + eof + ifs
    data = esi + dlc + 8 * length + (stuff_total - stuff_arbitration) + crc_field + fixed
    return nominal, data


@pytest.mark.parametrize("length", [0, 3, 8, 12, 16, 20, 32, 48, 64])
def test_fd_frame_bits_field_by_field(length: int) -> None:
    bits = fd_frame_bits(length)
    assert (bits.nominal, bits.data) == by_hand(length)


def test_the_sensor_set_frame_is_105_6_us_at_1_and_5_mbit() -> None:
    bits = fd_frame_bits(32)
    assert (bits.nominal, bits.data) == (34, 358)
    assert frame_time_s(FD["SENSOR_SET"], 1_000_000, 5_000_000) == pytest.approx(105.6e-6)
    four_classic = sum(frame_bits(8) for _ in range(4)) / 1e6
    assert four_classic == pytest.approx(540e-6)


def test_fd_lengths_grow_with_the_payload_and_crc_21_starts_above_16_bytes() -> None:
    lengths = [0, 1, 2, 3, 4, 5, 6, 7, 8, 12, 16, 20, 24, 32, 48, 64]
    data = [fd_frame_bits(n).data for n in lengths]
    assert data == sorted(data) and len(set(data)) == len(data)
    # 16 -> 20 bytes: 32 data bits, 8 more dynamic stuff bits, 4 more CRC bits, 1 more fixed stuff bit
    assert fd_frame_bits(20).data - fd_frame_bits(16).data == 32 + 8 + 4 + 1
    with pytest.raises(ValueError, match="10 data bytes is not a CAN FD frame length"):
        fd_frame_bits(10)


def test_without_bit_rate_switching_an_fd_frame_costs_more_than_a_classic_one() -> None:
    eight = fd_frame_bits(8)
    assert eight.time_s(1e6, 1e6) > frame_bits(8) / 1e6, "FD overhead (stuff count, CRC-17, fixed stuff bits)"
    assert eight.time_s(1e6, 5e6) < frame_bits(8) / 1e6, "with BRS at 5 Mbit/s it is shorter"


def test_a_message_without_brs_runs_its_data_phase_at_the_nominal_rate(tmp_path: Path) -> None:
    path = edited_dbc(tmp_path, Path(FD.path), ('BA_ "CANFD_BRS" BO_ 50 1;', 'BA_ "CANFD_BRS" BO_ 50 0;'))
    codec = load_protocol(path, fd=True)["SENSOR_SET"]
    assert frame_time_s(codec, 1_000_000, 5_000_000) == pytest.approx((34 + 358) / 1e6)


def test_fd_rates_replace_the_four_sensor_messages_by_the_set() -> None:
    rates = CanConfig(fd=True, loop_rate_hz=2000.0).rates_hz()
    assert set(rates) == set(FD.messages)
    assert rates["SENSOR_SET"] == 2000.0
    assert rates["TABLE_SENSORS"] == rates["BASE_SENSORS"] == rates["STORY_DRIFTS"] == rates["FLOOR_ACCELS"] == 0.0
    assert "SENSOR_SET" not in CanConfig().rates_hz()


def test_2_khz_needs_fd_and_fits_it_with_the_default_data_rate() -> None:
    classic = CanConfig(loop_rate_hz=2000.0)
    with pytest.raises(BusLoadError, match="85.3%"):
        prepare(classic)
    fd = dataclasses.replace(classic, fd=True)
    protocol, load = prepare(fd)
    assert protocol.fd and load.data_bitrate_bps == 5_000_000
    expected = sum(rate * frame_time_s(FD[name], 1e6, 5e6) for name, rate in fd.rates_hz().items())
    assert load.share == pytest.approx(expected)
    assert 0.3 < load.share < 0.35
    assert "CAN FD at 1000000 bit/s nominal, 5000000 bit/s data" in load.describe()
    assert "TABLE_SENSORS" not in load.describe(), "a message sent at 0 Hz is not listed"
    with pytest.raises(BusLoadError, match="60.7%"):
        prepare(dataclasses.replace(fd, data_bitrate_bps=2_000_000))


def test_the_classic_load_is_unchanged_by_the_fd_arguments() -> None:
    rates = CanConfig().rates_hz()
    assert bus_load(CLASSIC, rates, 1_000_000, 5_000_000).share == pytest.approx(bus_load(CLASSIC, rates, 1_000_000).share)
    assert check_bus_load(CLASSIC, rates, 1_000_000).data_bitrate_bps == 0


@pytest.mark.parametrize("value", ["maybe", "1", "yes please"])
def test_a_bad_can_fd_value_is_refused_naming_true_or_false(value: str) -> None:
    with pytest.raises(ProfileError, match=r"can\.fd.*expected true or false"):
        load_profile(PROFILES / "nceer_4dof.yaml", overrides=[f"can.fd={value}"])


def test_the_default_profile_is_classic_and_can_fd_true_selects_fd() -> None:
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    assert profile.can.fd is False and profile.can.data_bitrate_bps == 5_000_000
    fd = load_profile(PROFILES / "nceer_4dof.yaml", overrides=["can.fd=true"])
    assert fd.can.fd is True


def test_a_data_rate_below_the_nominal_rate_is_refused() -> None:
    with pytest.raises(ProfileError, match="data_bitrate_bps .* is below bitrate_bps"):
        load_profile(PROFILES / "nceer_4dof.yaml", overrides=["can.fd=true", "can.data_bitrate_bps=500000"])


def test_socketcan_preflight_asks_for_mtu_72_for_fd(tmp_path: Path) -> None:
    (tmp_path / "vcan0").mkdir()
    (tmp_path / "vcan0" / "flags").write_text("0xc1\n")
    (tmp_path / "vcan0" / "mtu").write_text("16\n")
    socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=True)  # classic: fine
    with pytest.raises(BusError, match=r"MTU 16, too small for CAN FD.*expected MTU 72.*ip link set vcan0 mtu 72"):
        socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=True, fd=True)
    (tmp_path / "vcan0" / "mtu").write_text("72\n")
    socketcan_preflight("vcan0", sys_net=tmp_path, kernel_ok=True, fd=True)


def test_the_seqpacket_transport_carries_the_fd_protocol_between_two_nodes() -> None:
    channel = f"fd-{uuid.uuid4().hex[:10]}"
    rates = CanConfig(fd=True, loop_rate_hz=2000.0).rates_hz()
    with open_rig("seqpacket", channel, 1_000_000, rates, fd=True, data_bitrate_bps=5_000_000) as rig, \
            open_harness("seqpacket", channel, 1_000_000, rates, fd=True, data_bitrate_bps=5_000_000) as harness:
        assert rig.bus.protocol == can.CanProtocol.CAN_FD and harness.bus.protocol == can.CanProtocol.CAN_FD
        values = [0.012345, -0.5, 3.0, 0.0101, 0.25, -1.0, 0.001, -0.002, 0.003, 9.0, -8.0, 7.0]
        assert rig.writer.sensor_set(values, 0.0)
        assert harness.writer.command(1234.0, True, 0.0)
        for _ in range(200):
            if harness.reader.poll(0.0, keep_fresh=True) and harness.reader.table.count:
                break
        assert harness.reader.sample("SENSOR_SET").values == pytest.approx(values, abs=1e-5)
        assert harness.reader.sample("FLOOR_ACCELS").values == pytest.approx(values[9:], abs=2e-3)
        msg = None
        for _ in range(200):
            msg = rig.bus.recv(timeout=0.01)
            if msg is not None:
                break
        assert msg is not None and msg.is_fd and msg.bitrate_switch and msg.arbitration_id == 0x20


def test_open_bus_asks_python_can_for_fd_only_when_fd() -> None:
    channel = f"fd-{uuid.uuid4().hex[:10]}"
    with open_bus("seqpacket", channel, 1_000_000, fd=True, data_bitrate_bps=5_000_000) as fd_bus, \
            open_bus("seqpacket", channel + "c", 1_000_000) as classic_bus:
        assert fd_bus.protocol == can.CanProtocol.CAN_FD
        assert classic_bus.protocol == can.CanProtocol.CAN_20
