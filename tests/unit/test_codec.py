"""drivers/protocol/codec.py and drivers/protocol/rig.dbc: round trips, cantools agreement, and every kind of rejection."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from drivers.protocol.codec import (
    DEFAULT_DBC,
    MessageCodec,
    Protocol,
    check_protocol_version,
    load_protocol,
)
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.protocol.e2e import protect
from harness.errors import ProtocolError

PROTOCOL = load_protocol()
FD_PROTOCOL = load_protocol(fd=True)
NAMES = sorted(PROTOCOL.messages)


def raw_values(codec: MessageCodec) -> st.SearchStrategy[list[float]]:
    """SI values exactly on the DBC grid, anywhere in each signal's [min, max]."""
    parts = []
    for sig in codec.signals:
        if sig.is_float:
            parts.append(st.floats(sig.minimum, sig.maximum, width=32))
        else:
            parts.append(st.integers(sig.raw_min, sig.raw_max).map(lambda r, s=sig: r * s.scale + s.offset))
    return st.tuples(*parts).map(list)


def protected(codec: MessageCodec, values: list[float], counter: int = 0) -> bytearray:
    data = bytearray(codec.length)
    codec.encode_into(data, values, counter)
    return data


def test_protocol_has_the_required_messages_and_version() -> None:
    assert set(NAMES) == {
        "ESTOP", "ACTUATOR_CMD", "TABLE_SENSORS", "BASE_SENSORS", "ACTUATOR_STATUS",
        "HEARTBEAT", "STORY_DRIFTS", "FLOOR_ACCELS", "RIG_CONTROL", "RIG_STATUS", "DRIVE_RESET",
    }
    assert PROTOCOL.version == 1
    assert len(PROTOCOL.by_id) == len(NAMES)
    assert all(2 <= c.length <= 8 and c.frame_id < 0x800 for c in PROTOCOL.messages.values())
    assert len({c.data_ids for c in PROTOCOL.messages.values()}) == len(NAMES)


def test_ranges_fit_the_quarter_scale_rig_with_margin() -> None:
    table = PROTOCOL["TABLE_SENSORS"]
    x0, xd0, xdd0 = (table.signals[table.index(n)] for n in ("x_0", "xdot_0", "xddot_0"))
    assert x0.scale <= 1e-6 and x0.maximum >= 0.3 and x0.minimum <= -0.3
    assert xd0.scale <= 1e-3 and xd0.maximum >= 1.5
    assert xdd0.maximum >= 3 * 9.81
    force = PROTOCOL["ACTUATOR_CMD"].signals[PROTOCOL["ACTUATOR_CMD"].index("force")]
    assert force.scale <= 1.0 and force.maximum >= 25_000 and force.minimum <= -25_000
    assert x0.signed and xd0.signed and force.signed


@pytest.mark.parametrize("name", NAMES)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_round_trip_every_message_full_range(name: str, data: st.DataObject) -> None:
    codec = PROTOCOL[name]
    values = data.draw(raw_values(codec))
    counter = data.draw(st.integers(0, 15))
    frame = protected(codec, values, counter)
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(codec.frame_id, frame) == RxStatus.OK
    assert decoder.values(name) == pytest.approx(values, rel=1e-12, abs=1e-12)


@pytest.mark.parametrize(
    ("protocol", "name"),
    [(PROTOCOL, name) for name in NAMES] + [(FD_PROTOCOL, name) for name in sorted(FD_PROTOCOL.messages)],
    ids=[name for name in NAMES] + [f"fd-{name}" for name in sorted(FD_PROTOCOL.messages)],
)
@settings(max_examples=40, deadline=None)
@given(data=st.data())
def test_encoding_agrees_with_cantools(protocol: Protocol, name: str, data: st.DataObject) -> None:
    """Classic and CAN FD alike: our frame is cantools' frame, and our decoder gives the values back."""
    codec = protocol[name]
    values = data.draw(raw_values(codec))
    counter = data.draw(st.integers(0, 15))
    ours = protected(codec, values, counter)
    message = protocol.database.get_message_by_name(name)
    assert bool(message.is_fd) == protocol.fd
    decoded = message.decode(bytes(ours), decode_choices=False, scaling=True)
    assert decoded["counter"] == counter
    for sig, value in zip(codec.signals, values, strict=True):
        assert decoded[sig.name] == pytest.approx(value, rel=1e-9, abs=1e-12)
    theirs = bytearray(message.encode({"crc": 0, "counter": counter, **dict(zip(codec.signal_names, values, strict=True))}))
    protect(theirs, counter, codec.data_ids)
    assert theirs == ours
    decoder = Decoder(protocol)
    assert decoder.decode(codec.frame_id, ours, fd=protocol.fd) == RxStatus.OK
    assert decoder.values(name) == pytest.approx(values, rel=1e-12, abs=1e-12)


def test_encode_rounds_to_the_grid() -> None:
    codec = PROTOCOL["TABLE_SENSORS"]
    frame = protected(codec, [0.0123454, -0.0000004, 9.81])
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(codec.frame_id, frame) == RxStatus.OK
    assert decoder.values("TABLE_SENSORS") == pytest.approx([0.012345, 0.0, 9.81], abs=1e-12)


@pytest.mark.parametrize(
    ("name", "values", "bad"),
    [
        ("TABLE_SENSORS", [0.51, 0.0, 0.0], "x_0"),
        ("TABLE_SENSORS", [0.0, -2.6, 0.0], "xdot_0"),
        ("ACTUATOR_CMD", [1.0, 30_001.0], "force"),
        ("ACTUATOR_CMD", [1.0, math.nan], "force"),
        ("ACTUATOR_STATUS", [5.0, 1.0, 0.0, 0.0], "drive_state"),
        ("RIG_CONTROL", [4.0, 0.0, 0.0, 0.0], "command"),
        ("RIG_CONTROL", [1.0, 0.0, 0.0, math.inf], "fault_param"),
        ("DRIVE_RESET", [256.0], "fault_code"),
    ],
)
def test_encode_refuses_out_of_range(name: str, values: list[float], bad: str) -> None:
    with pytest.raises(ProtocolError, match=rf"{name}\.{bad}: .* is outside"):
        protected(PROTOCOL[name], values)


def test_encode_refuses_wrong_count_and_unknown_names() -> None:
    with pytest.raises(ProtocolError, match="2 values instead of 3"):
        protected(PROTOCOL["TABLE_SENSORS"], [0.0, 0.0])
    with pytest.raises(ProtocolError, match="has no signal 'x0'"):
        PROTOCOL["TABLE_SENSORS"].encode({"x0": 0.0}, 0)
    with pytest.raises(ProtocolError, match="no value for signal 'xdot_0'"):
        PROTOCOL["TABLE_SENSORS"].encode({"x_0": 0.0}, 0)
    with pytest.raises(ProtocolError, match="no message 'TABLE'"):
        PROTOCOL["TABLE"]
    assert PROTOCOL["TABLE_SENSORS"].encode({"x_0": 0.1, "xdot_0": 0.0, "xddot_0": 0.0}, 0)[1] & 0x0F == 0


def good_table_frame(counter: int = 0) -> bytearray:
    return protected(PROTOCOL["TABLE_SENSORS"], [0.01, 0.02, 0.03], counter)


def test_rejects_wrong_length() -> None:
    decoder = Decoder(PROTOCOL)
    frame = good_table_frame()
    assert decoder.decode(0x30, frame[:6]) == RxStatus.WRONG_LENGTH
    assert decoder.decode(0x30, frame + b"\x00") == RxStatus.WRONG_LENGTH
    assert decoder.counts[RxStatus.WRONG_LENGTH] == 2
    assert decoder.rejected("TABLE_SENSORS", RxStatus.WRONG_LENGTH) == 2


#: Every message of drivers/protocol/rig.dbc that carries the E2E CRC (byte 0, signal ``crc``): all of them today.
CRC_MESSAGES = sorted(m.name for m in PROTOCOL.database.messages if any(s.name == "crc" for s in m.signals))


def test_every_message_of_the_dbc_carries_the_crc() -> None:
    assert CRC_MESSAGES == NAMES


@pytest.mark.parametrize("name", CRC_MESSAGES)
@pytest.mark.parametrize("counter", [0, 7])
def test_rejects_every_single_bit_flip_of_every_message_as_bad_crc(name: str, counter: int) -> None:
    codec = PROTOCOL[name]
    values = [sig.maximum if k % 2 else sig.minimum for k, sig in enumerate(codec.signals)]  # valid, bits set and clear
    good = protected(codec, values, counter)
    decoder = Decoder(PROTOCOL)
    for bit in range(8 * codec.length):
        frame = bytearray(good)
        frame[bit // 8] ^= 1 << (bit % 8)
        assert decoder.decode(codec.frame_id, frame) == RxStatus.BAD_CRC, f"{name}: bit {bit} flipped was not caught"
    assert decoder.rejected(name, RxStatus.BAD_CRC) == 8 * codec.length
    assert decoder.decode(codec.frame_id, good) == RxStatus.OK  # the unflipped frame is a good one


def test_rejects_a_frame_of_one_message_on_another_id_via_data_id() -> None:
    # TABLE_SENSORS and BASE_SENSORS share a layout; only the Data-ID tells them apart
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(PROTOCOL["BASE_SENSORS"].frame_id, good_table_frame()) == RxStatus.BAD_CRC


def test_rejects_repeated_and_skipped_counters_and_keeps_last_values() -> None:
    decoder = Decoder(PROTOCOL)
    codec = PROTOCOL["TABLE_SENSORS"]
    assert decoder.decode(0x30, protected(codec, [0.1, 0.0, 0.0], 4)) == RxStatus.OK
    assert decoder.decode(0x30, protected(codec, [0.2, 0.0, 0.0], 4)) == RxStatus.REPEATED_COUNTER
    assert decoder.values("TABLE_SENSORS")[0] == pytest.approx(0.1)
    assert decoder.decode(0x30, protected(codec, [0.3, 0.0, 0.0], 6)) == RxStatus.SKIPPED_COUNTER
    assert decoder.values("TABLE_SENSORS")[0] == pytest.approx(0.1)
    assert decoder.decode(0x30, protected(codec, [0.4, 0.0, 0.0], 7)) == RxStatus.OK
    assert decoder.values("TABLE_SENSORS")[0] == pytest.approx(0.4)
    assert decoder.counts[RxStatus.REPEATED_COUNTER] == 1
    assert decoder.counts[RxStatus.SKIPPED_COUNTER] == 1
    assert decoder.accepted("TABLE_SENSORS") == 2
    decoder.reset_counters()
    assert decoder.decode(0x30, protected(codec, [0.5, 0.0, 0.0], 1)) == RxStatus.OK


def test_counters_are_per_message() -> None:
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(0x30, protected(PROTOCOL["TABLE_SENSORS"], [0.0] * 3, 3)) == RxStatus.OK
    assert decoder.decode(0x31, protected(PROTOCOL["BASE_SENSORS"], [0.0] * 3, 9)) == RxStatus.OK


def test_rejects_out_of_range_value_with_valid_crc() -> None:
    codec = PROTOCOL["TABLE_SENSORS"]
    frame = bytearray(8)
    raw = codec.signals[0].raw_max + 1  # x_0 one step above +0.5 m, still fits the 20-bit field
    word = (raw & codec.signals[0].mask) << codec.signals[0].start
    frame[:] = word.to_bytes(8, "little")
    protect(frame, 0, codec.data_ids)
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(0x30, frame) == RxStatus.OUT_OF_RANGE
    assert decoder.values("TABLE_SENSORS") == [0.0, 0.0, 0.0]


def test_rejects_out_of_range_enum() -> None:
    codec = PROTOCOL["ACTUATOR_STATUS"]
    frame = bytearray(codec.length)
    frame[1] = 0xF0  # drive_state 15, defined 0..4
    protect(frame, 0, codec.data_ids)
    assert Decoder(PROTOCOL).decode(codec.frame_id, frame) == RxStatus.OUT_OF_RANGE


def test_rejects_unknown_id_and_ids_this_node_does_not_receive() -> None:
    decoder = Decoder(PROTOCOL, ["TABLE_SENSORS"])
    assert decoder.decode(0x7FF, bytes(8)) == RxStatus.UNKNOWN_ID
    assert decoder.decode(0x31, protected(PROTOCOL["BASE_SENSORS"], [0.0] * 3)) == RxStatus.UNKNOWN_ID
    assert decoder.counts[RxStatus.UNKNOWN_ID] == 2
    assert decoder.rejected_total == 2
    with pytest.raises(ProtocolError, match="does not receive 'BASE_SENSORS'"):
        decoder.values("BASE_SENSORS")


def test_rejects_non_data_frames_and_extended_ids() -> None:
    decoder = Decoder(PROTOCOL)
    assert decoder.decode(0x30, good_table_frame(), is_data_frame=False) == RxStatus.NOT_DATA
    assert decoder.decode(0x30, good_table_frame(), extended=True) == RxStatus.UNKNOWN_ID
    assert decoder.accepted("TABLE_SENSORS") == 0


@settings(max_examples=400, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 0x7FF), st.binary(min_size=0, max_size=8)), max_size=30))
def test_random_frames_never_raise_and_each_is_counted_once(frames: list[tuple[int, bytes]]) -> None:
    decoder = Decoder(PROTOCOL)
    known = sorted(PROTOCOL.by_id)
    for frame_id, data in frames:
        status = decoder.decode(frame_id, data)
        assert isinstance(status, RxStatus)
        if frame_id not in PROTOCOL.by_id:
            assert status == RxStatus.UNKNOWN_ID
    assert sum(decoder.counts) == len(frames)
    assert decoder.counts[RxStatus.OK] == sum(decoder.accepted(PROTOCOL.by_id[i].name) for i in known)


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(sorted(PROTOCOL.by_id)), st.binary(min_size=0, max_size=8))
def test_random_payloads_on_known_ids_never_raise(frame_id: int, data: bytes) -> None:
    decoder = Decoder(PROTOCOL)
    status = decoder.decode(frame_id, data)
    codec = PROTOCOL.by_id[frame_id]
    if len(data) != codec.length:
        assert status == RxStatus.WRONG_LENGTH
    elif not codec.crc_ok(data):
        assert status == RxStatus.BAD_CRC
    assert decoder.rejected_total + decoder.counts[RxStatus.OK] == 1


def test_version_check_names_both_versions() -> None:
    check_protocol_version(PROTOCOL, 1)
    with pytest.raises(ProtocolError, match=r"version 2 but .*rig.dbc is version 1"):
        check_protocol_version(PROTOCOL, 2)


def _edited_dbc(tmp_path: Path, old: str, new: str) -> Path:
    text = DEFAULT_DBC.read_text()
    assert old in text
    path = tmp_path / "edited.dbc"
    path.write_text(text.replace(old, new))
    return path


def test_bad_dbc_files_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ProtocolError, match="not found"):
        load_protocol(tmp_path / "missing.dbc")
    with pytest.raises(ProtocolError, match="no ProtocolVersion attribute"):
        load_protocol(_edited_dbc(tmp_path, 'BA_ "ProtocolVersion" 1;', ""))
    with pytest.raises(ProtocolError, match="ESTOP has no E2EDataIDs"):
        load_protocol(_edited_dbc(tmp_path, 'BA_ "E2EDataIDs" BO_ 16 "16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31";', ""))
    with pytest.raises(ProtocolError, match="expected signal 'counter' at bit 8"):
        load_protocol(_edited_dbc(
            tmp_path,
            'SG_ counter : 8|4@1+ (1,0) [0|15] "" HARNESS,RIG,SERVO',
            'SG_ counter : 9|3@1+ (1,0) [0|7] "" HARNESS,RIG,SERVO',
        ))
    bumped = load_protocol(_edited_dbc(tmp_path, 'BA_ "ProtocolVersion" 1;', 'BA_ "ProtocolVersion" 7;'))
    assert bumped.version == 7


def test_named_choices_come_from_the_dbc() -> None:
    assert PROTOCOL.choice("ACTUATOR_STATUS", "drive_state", "ENABLED") == 2
    assert PROTOCOL.choice("RIG_CONTROL", "command", "START_TABLE") == 1
    assert PROTOCOL.choice("ESTOP", "source", "PANEL") == 3
    with pytest.raises(ProtocolError, match="no choice 'RUNNING'; expected one of: OFF, READY"):
        PROTOCOL.choice("ACTUATOR_STATUS", "drive_state", "RUNNING")
    with pytest.raises(ProtocolError, match="has no signal 'mode'"):
        PROTOCOL.choice("ACTUATOR_STATUS", "mode", "OFF")


def test_out_of_range_error_names_the_right_signal_among_equal_ranges() -> None:
    with pytest.raises(ProtocolError, match=r"STORY_DRIFTS\.drift_3: 0\.07 m is outside -0\.065\.\.0\.065 m"):
        protected(PROTOCOL["STORY_DRIFTS"], [0.0, 0.01, 0.07])


def test_each_rejection_is_counted_for_its_message_and_in_total() -> None:
    codec = PROTOCOL["TABLE_SENSORS"]
    decoder = Decoder(PROTOCOL)
    out_of_range = bytearray(codec.length)
    out_of_range[:] = ((codec.signals[0].raw_max + 1) << codec.signals[0].start).to_bytes(8, "little")
    protect(out_of_range, 2, codec.data_ids)
    frames = [
        (good_table_frame(0), {}, RxStatus.OK),
        (good_table_frame(1), {"is_data_frame": False}, RxStatus.NOT_DATA),
        (good_table_frame(0), {}, RxStatus.REPEATED_COUNTER),
        (good_table_frame(5), {}, RxStatus.SKIPPED_COUNTER),
        (good_table_frame(7), {}, RxStatus.SKIPPED_COUNTER),
        (out_of_range, {}, RxStatus.SKIPPED_COUNTER),  # counter 2 after 7
        (good_table_frame(3), {}, RxStatus.OK),
    ]
    for frame, flags, expected in frames:
        assert decoder.decode(codec.frame_id, frame, **flags) == expected
        assert decoder.last is codec
    protect(out_of_range, 4, codec.data_ids)
    assert decoder.decode(codec.frame_id, out_of_range) == RxStatus.OUT_OF_RANGE
    for status, n in ((RxStatus.NOT_DATA, 1), (RxStatus.REPEATED_COUNTER, 1), (RxStatus.SKIPPED_COUNTER, 3),
                      (RxStatus.OUT_OF_RANGE, 1)):
        assert (decoder.rejected("TABLE_SENSORS", status), decoder.counts[status]) == (n, n), status
    assert decoder.accepted("TABLE_SENSORS") == 2 and decoder.rejected_total == 6
    assert decoder.decode(0x7FF, bytes(8)) == RxStatus.UNKNOWN_ID and decoder.last is None


def test_asking_for_a_message_the_decoder_does_not_receive_names_the_ones_it_does() -> None:
    with pytest.raises(ProtocolError, match=r"does not receive 'ESTOP'; it receives: TABLE_SENSORS, BASE_SENSORS$"):
        Decoder(PROTOCOL, ["TABLE_SENSORS", "BASE_SENSORS"]).values("ESTOP")
