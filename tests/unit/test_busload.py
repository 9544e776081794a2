"""drivers/protocol/busload.py: frame length formula, load from DBC and rates, refusal above the allowed share.

Also the profile's side: harness/canbus/config.py (rates of every message) and harness/canbus/link.py
(refusal before the bus is opened).
"""

from __future__ import annotations

import dataclasses

import pytest

from drivers.errors import BusLoadError, ProtocolError
from drivers.protocol.busload import BusLoad, bus_load, check_bus_load, frame_bits
from drivers.protocol.codec import load_protocol
from harness.canbus.config import RATE_FIELDS, CanConfig
from harness.config.schema import build
from harness.errors import ProfileError

PROTOCOL = load_protocol()


def check(config: CanConfig) -> BusLoad:
    """:func:`check_bus_load` with the rates, bitrate and allowed share of ``config``."""
    return check_bus_load(PROTOCOL, config.rates_hz(), config.bitrate_bps, config.max_bus_load)


def test_eight_byte_standard_frame_is_about_130_us_at_1_mbit() -> None:
    # 34 stuffable header/CRC bits + 64 data + 13 fixed + floor(97/4) = 24 stuff bits
    assert frame_bits(8) == 135
    assert 125e-6 <= frame_bits(8) / 1e6 <= 140e-6


def test_frame_bits_by_hand_and_monotonic() -> None:
    assert frame_bits(0) == 34 + 13 + 33 // 4
    assert frame_bits(2) == 34 + 16 + 13 + 49 // 4
    assert frame_bits(8, extended_id=True) == 54 + 64 + 13 + 117 // 4
    lengths = [frame_bits(n) for n in range(9)]
    assert lengths == sorted(lengths) and len(set(lengths)) == 9
    with pytest.raises(ValueError, match="DLC 9 is outside 0..8"):
        frame_bits(9)


def test_every_dbc_message_has_a_configured_rate() -> None:
    assert set(RATE_FIELDS) == set(PROTOCOL.messages)
    assert set(CanConfig().rates_hz()) == set(PROTOCOL.messages)


def test_load_is_sum_of_rate_times_frame_bits() -> None:
    rates = {name: 0.0 for name in PROTOCOL.messages}
    rates["TABLE_SENSORS"] = 1000.0  # 8 bytes
    rates["HEARTBEAT"] = 100.0  # 2 bytes
    load = bus_load(PROTOCOL, rates, 500_000)
    expected = 1000.0 * frame_bits(8) + 100.0 * frame_bits(2)
    assert load.total_bits_per_s == pytest.approx(expected)
    assert load.share == pytest.approx(expected / 500_000)


def test_default_config_fits_500_hz_control_at_1_mbit() -> None:
    config = CanConfig()
    assert config.command_rate_hz >= 500 and config.sensor_frame_rate_hz >= 500
    load = check(config)
    assert 0.0 < load.share <= config.max_bus_load


def test_overload_is_refused_with_the_figure() -> None:
    config = dataclasses.replace(CanConfig(), loop_rate_hz=2000.0)
    share = bus_load(PROTOCOL, config.rates_hz(), config.bitrate_bps).share
    assert share > 0.5
    with pytest.raises(BusLoadError) as info:
        check(config)
    assert f"{share:.1%}" in str(info.value)
    assert "allowed 50.0%" in str(info.value)
    assert "TABLE_SENSORS" in str(info.value)


def test_lower_bitrate_or_tighter_share_refuses_the_default_rates() -> None:
    with pytest.raises(BusLoadError):
        check(dataclasses.replace(CanConfig(), bitrate_bps=250_000))
    with pytest.raises(BusLoadError):
        check(dataclasses.replace(CanConfig(), max_bus_load=0.1))


def test_share_exactly_at_the_limit_is_accepted() -> None:
    config = CanConfig()
    share = bus_load(PROTOCOL, config.rates_hz(), config.bitrate_bps).share
    check(dataclasses.replace(config, max_bus_load=share))


def test_rates_and_dbc_must_agree() -> None:
    rates = CanConfig().rates_hz()
    del rates["HEARTBEAT"]
    with pytest.raises(ProtocolError, match="no rate configured for message HEARTBEAT"):
        bus_load(PROTOCOL, rates, 1_000_000)
    rates = {**CanConfig().rates_hz(), "NOT_A_MESSAGE": 1.0}
    with pytest.raises(ProtocolError, match="NOT_A_MESSAGE"):
        bus_load(PROTOCOL, rates, 1_000_000)


def test_config_from_yaml_mapping_with_units() -> None:
    data = {"sensor_rate_hz": "1 kHz", "bitrate_bps": 500_000, "max_bus_load": 0.6}
    config = build(CanConfig, data, source="p.yaml", path="can")
    assert config.sensor_rate_hz == 1000.0
    assert config.rates_hz()["BASE_SENSORS"] == 1000.0
    with pytest.raises(ProfileError, match="can.max_bus_load"):
        build(CanConfig, {"max_bus_load": 1.5}, source="p.yaml", path="can")
    with pytest.raises(ProfileError, match="unknown key"):
        build(CanConfig, {"bitrate": 500_000}, source="p.yaml", path="can")


def test_overloaded_link_is_refused_before_the_bus_is_opened(monkeypatch: pytest.MonkeyPatch) -> None:
    import drivers.link
    from harness.canbus import link as can_link

    def must_not_open(*args: object, **kwargs: object) -> None:
        raise AssertionError("the bus was opened for a refused configuration")

    monkeypatch.setattr(drivers.link, "open_bus", must_not_open)
    overloaded = dataclasses.replace(CanConfig(), loop_rate_hz=2000.0)
    with pytest.raises(BusLoadError, match="exceeds the allowed 50.0%"):
        can_link.open_harness(overloaded)
    with pytest.raises(BusLoadError):
        can_link.open_rig(overloaded)
    with pytest.raises(ProtocolError, match="names CAN protocol version 9"):
        can_link.open_harness(dataclasses.replace(CanConfig(), protocol_version=9))
    with pytest.raises(BusLoadError):
        drivers.link.open_harness("virtual", "x", 1_000_000, overloaded.rates_hz())


def test_prepare_accepts_the_defaults() -> None:
    from harness.canbus.link import prepare

    protocol, load = prepare(CanConfig())
    assert protocol.version == CanConfig().protocol_version
    assert load.share == pytest.approx(bus_load(PROTOCOL, CanConfig().rates_hz(), 1_000_000).share)
