"""The CAN FD variant of the protocol: drivers/protocol/rig_fd.dbc against rig.dbc and cantools, FD frame checks and E2E.

The FD DBC is hand-written beside the classic one; these tests hold the two together (same
messages, signals, Data-IDs and value tables) and check the FD-only SENSOR_SET bit for bit against
cantools, as tests/unit/test_codec.py checks the classic messages.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from drivers.errors import ProtocolError
from drivers.protocol.codec import DEFAULT_DBC, DEFAULT_FD_DBC, load_protocol
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.reader import SENSOR_SET_PARTS
from tests.conftest import edited_dbc
from tests.unit.test_codec import protected

CLASSIC = load_protocol()
FD = load_protocol(fd=True)


def test_the_fd_dbc_is_every_classic_message_as_an_fd_frame_plus_the_sensor_set() -> None:
    assert set(FD.messages) == set(CLASSIC.messages) | {"SENSOR_SET"}
    assert FD.fd and not CLASSIC.fd
    assert FD.version == CLASSIC.version
    for name, classic in CLASSIC.messages.items():
        fd = FD[name]
        assert (fd.frame_id, fd.length, fd.data_ids, fd.signals) == (
            classic.frame_id, classic.length, classic.data_ids, classic.signals
        ), name
        assert fd.is_fd and fd.bitrate_switch and not classic.is_fd and not classic.bitrate_switch
    for name in CLASSIC.messages:
        for signal in CLASSIC[name].signal_names:
            assert FD.value_table(name, signal) == CLASSIC.value_table(name, signal)
    sensor_set = FD["SENSOR_SET"]
    assert sensor_set.is_fd and sensor_set.bitrate_switch and sensor_set.length == 32
    assert sensor_set.frame_id not in CLASSIC.by_id
    assert sensor_set.data_ids not in {c.data_ids for c in CLASSIC.messages.values()}


def test_sensor_set_block_k_is_classic_message_k_shifted_by_64_k_bits() -> None:
    sensor_set = FD["SENSOR_SET"]
    by_name = {s.name: s for s in sensor_set.signals}
    order = []
    for k, name in enumerate(SENSOR_SET_PARTS):
        for sig in CLASSIC[name].signals:
            ours = by_name[sig.name]
            assert ours.start == sig.start + 64 * k, sig.name
            assert (ours.length, ours.signed, ours.scale, ours.raw_min, ours.raw_max, ours.unit) == (
                sig.length, sig.signed, sig.scale, sig.raw_min, sig.raw_max, sig.unit
            ), sig.name
            order.append(sig.name)
    assert list(sensor_set.signal_names) == order


@pytest.mark.parametrize("counter", [0, 9])
def test_every_single_bit_flip_of_a_sensor_set_is_a_bad_crc(counter: int) -> None:
    codec = FD["SENSOR_SET"]
    values = [sig.maximum if k % 2 else sig.minimum for k, sig in enumerate(codec.signals)]
    good = protected(codec, values, counter)
    decoder = Decoder(FD)
    for bit in range(8 * codec.length):
        frame = bytearray(good)
        frame[bit // 8] ^= 1 << (bit % 8)
        assert decoder.decode(codec.frame_id, frame, fd=True) == RxStatus.BAD_CRC, f"bit {bit} flipped was not caught"
    assert decoder.decode(codec.frame_id, good, fd=True) == RxStatus.OK


def test_the_sensor_set_counter_and_length_are_checked_as_the_classic_ones() -> None:
    codec = FD["SENSOR_SET"]
    values = [0.0] * len(codec.signals)
    decoder = Decoder(FD)
    assert decoder.decode(codec.frame_id, protected(codec, values, 3), fd=True) == RxStatus.OK
    assert decoder.decode(codec.frame_id, protected(codec, values, 3), fd=True) == RxStatus.REPEATED_COUNTER
    assert decoder.decode(codec.frame_id, protected(codec, values, 5), fd=True) == RxStatus.SKIPPED_COUNTER
    assert decoder.decode(codec.frame_id, protected(codec, values, 6)[:24], fd=True) == RxStatus.WRONG_LENGTH
    other = FD["TABLE_SENSORS"]  # a classic-sized payload under the set's ID: wrong length, never decoded
    assert decoder.decode(codec.frame_id, protected(other, [0.0, 0.0, 0.0]), fd=True) == RxStatus.WRONG_LENGTH


def test_a_frame_in_the_other_format_is_not_data() -> None:
    table = CLASSIC["TABLE_SENSORS"]
    frame = protected(table, [0.01, 0.1, 1.0])
    classic, fd = Decoder(CLASSIC), Decoder(FD)
    assert classic.decode(table.frame_id, frame, fd=True) == RxStatus.NOT_DATA
    assert fd.decode(table.frame_id, frame, fd=False) == RxStatus.NOT_DATA
    assert classic.decode(table.frame_id, frame) == RxStatus.OK
    assert fd.decode(table.frame_id, frame, fd=True) == RxStatus.OK


def test_the_packaged_dbc_is_chosen_by_the_frame_format_and_a_mismatch_refused() -> None:
    assert load_protocol(fd=True).path == DEFAULT_FD_DBC
    assert load_protocol(fd=False).path == DEFAULT_DBC
    with pytest.raises(ProtocolError, match=r"describes classic CAN frames but can.fd is true.*rig_fd.dbc"):
        load_protocol(DEFAULT_DBC, fd=True)
    with pytest.raises(ProtocolError, match=r"describes CAN FD frames but can.fd is false.*rig.dbc"):
        load_protocol(DEFAULT_FD_DBC, fd=False)


def test_a_dbc_that_mixes_frame_formats_is_refused(tmp_path: Path) -> None:
    mixed = edited_dbc(tmp_path, DEFAULT_FD_DBC, ('BA_ "VFrameFormat" BO_ 32 14;\n', ""))
    with pytest.raises(ProtocolError, match="is a CAN FD frame but ACTUATOR_CMD a classic one"):
        load_protocol(mixed)


def test_a_length_no_fd_frame_has_is_refused(tmp_path: Path) -> None:
    bad = edited_dbc(tmp_path, DEFAULT_FD_DBC, ("BO_ 769 RIG_STATUS: 8 RIG", "BO_ 769 RIG_STATUS: 10 RIG"))
    with pytest.raises(ProtocolError, match="RIG_STATUS: 10 data bytes is not a length a CAN FD frame has"):
        load_protocol(bad)


def test_without_the_brs_attribute_the_dbc_default_decides(tmp_path: Path) -> None:
    path = edited_dbc(tmp_path, DEFAULT_FD_DBC, ('BA_ "CANFD_BRS" BO_ 50 1;\n', 'BA_ "CANFD_BRS" BO_ 50 0;\n'),
                      ('BA_ "CANFD_BRS" BO_ 32 1;\n', ""), ('BA_DEF_DEF_  "CANFD_BRS" "1";', 'BA_DEF_DEF_  "CANFD_BRS" "0";'))
    protocol = load_protocol(path, fd=True)
    assert not protocol["SENSOR_SET"].bitrate_switch  # set to 0
    assert not protocol["ACTUATOR_CMD"].bitrate_switch  # the default, 0
    assert protocol["TABLE_SENSORS"].bitrate_switch  # set to 1
