"""CRC-8/2F and rolling-counter checks of drivers/protocol/e2e.py against independent references."""

from __future__ import annotations

import crccheck
import pytest
from cantools.autosar.end_to_end import compute_profile2_crc
from hypothesis import given
from hypothesis import strategies as st

from drivers.protocol.e2e import crc8_2f, parse_data_ids, profile2_crc, protect

DATA_IDS = tuple(range(0x40, 0x50))


def test_crc8_2f_check_value_from_autosar_catalogue() -> None:
    # AUTOSAR SWS CRC Library, Crc_CalculateCRC8H2F: check value 0xDF for "123456789"
    assert crc8_2f(b"123456789") == 0xDF


def test_crc8_2f_autosar_example_vectors() -> None:
    # Examples from the AUTOSAR SWS CRC Library table for CRC8H2F
    assert crc8_2f(bytes([0x00, 0x00, 0x00, 0x00])) == 0x12
    assert crc8_2f(bytes([0xF2, 0x01, 0x83])) == 0xC2
    assert crc8_2f(bytes([0xFF, 0xFF, 0xFF, 0xFF])) == 0x6C


@given(st.binary(min_size=0, max_size=16))
def test_crc8_2f_matches_crccheck(data: bytes) -> None:
    assert crc8_2f(data) == crccheck.crc.Crc8Autosar().calc(data)


@given(st.binary(min_size=2, max_size=8), st.integers(0, 15))
def test_profile2_crc_matches_cantools_helper(payload: bytes, counter: int) -> None:
    data = bytearray(payload)
    protect(data, counter, DATA_IDS)
    assert data[1] & 0x0F == counter
    assert data[0] == compute_profile2_crc(bytes(data), DATA_IDS[counter])


@given(st.binary(min_size=2, max_size=8), st.integers(0, 15))
def test_protect_keeps_high_nibble_and_rest(payload: bytes, counter: int) -> None:
    data = bytearray(payload)
    protect(data, counter, DATA_IDS)
    assert data[1] >> 4 == payload[1] >> 4
    assert data[2:] == payload[2:]
    assert profile2_crc(data, len(data), DATA_IDS) == data[0]


def test_data_id_changes_crc() -> None:
    data = bytearray(b"\x00\x05\x10\x20")
    protect(data, 5, DATA_IDS)
    other = tuple((d + 1) & 0xFF for d in DATA_IDS)
    assert profile2_crc(data, 4, other) != data[0]


def test_parse_data_ids() -> None:
    assert parse_data_ids("1, 2 3 4 5 6 7 8 9 10 11 12 13 14 15 0x10", "M") == tuple(range(1, 17))
    with pytest.raises(ValueError, match="15 values instead of 16"):
        parse_data_ids(" ".join(["1"] * 15), "M")
    with pytest.raises(ValueError, match="256 is outside 0..255"):
        parse_data_ids(" ".join(["256"] * 16), "M")
    with pytest.raises(ValueError, match="not a list of integers"):
        parse_data_ids("a " * 16, "M")


def test_parse_data_ids_accepts_0_and_255_and_refuses_just_outside() -> None:
    assert parse_data_ids(" ".join(["0"] * 8 + ["255"] * 8), "M") == (0,) * 8 + (255,) * 8
    with pytest.raises(ValueError, match="value -1 is outside 0..255"):
        parse_data_ids(" ".join(["0"] * 15 + ["-1"]), "M")


@given(st.binary(min_size=0, max_size=16), st.integers(0, 16), st.integers(0, 16))
def test_crc8_2f_of_a_range_equals_the_crc_of_the_slice(data: bytes, start: int, stop: int) -> None:
    assert crc8_2f(data, start, min(stop, len(data))) == crc8_2f(data[start:stop])
