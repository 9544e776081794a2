"""The compiled receive side (drivers/protocol/frame_kernel.py): the same judgement on every path.

The reader takes a ``seqpacket`` bus's datagrams straight off its socket and checks and decodes
them in one compiled call (:meth:`drivers.protocol.decoder.Decoder.receive_datagrams`); on any other bus
it decodes each :class:`can.Message` through :meth:`~drivers.protocol.decoder.Decoder.decode`. These
tests feed the same frames, good and bad of every kind, to a reader on each path and require
the same outcome to the last count; and they pin the counter rules the E2E profile sets.
"""

from __future__ import annotations

import math
import re
import socket
import time
import uuid
from collections.abc import Iterator

import can
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drivers.protocol import frame_kernel as kernel
from drivers.protocol.codec import DEFAULT_DBC as REPO_DBC
from drivers.protocol.codec import Protocol, load_protocol
from drivers.protocol.datagram import encode_frame
from drivers.protocol.decoder import Decoder, RxStatus
from drivers.protocol.e2e import profile2_crc, protect
from drivers.protocol.protocol_values import EstopSource
from drivers.reader import HARNESS_RX, HarnessReader
from drivers.transports.bus import CAN_ERR_BUSOFF
from drivers.transports.seqpacket.bus import SeqPacketBus
from drivers.transports.seqpacket.channel import parse_channel

CLASSIC = load_protocol()
FD = load_protocol(fd=True)
NOW_S = 12.5

# kinds of frame the strategy makes
VALID, BAD_CRC, SHORT, REPEAT, UNKNOWN, EXTENDED, REMOTE, OTHER_FORMAT, ERROR, OUT_OF_RANGE, PANEL_ESTOP = range(11)


class ListBus(can.BusABC):
    """A python-can bus that hands out a list of frames (the reader's Message path)."""

    def __init__(self) -> None:
        self.pending: list[can.Message] = []
        super().__init__(channel="list")

    def send(self, msg: can.Message, timeout: float | None = None) -> None:
        raise AssertionError("the reader never sends")

    def _recv_internal(self, timeout: float | None) -> tuple[can.Message | None, bool]:
        return (self.pending.pop(0) if self.pending else None), False


def _frame(protocol: Protocol, kind: int, name: str, counter: int, fill: int) -> can.Message:
    """One frame of ``kind`` on message ``name`` with rolling ``counter``."""
    codec = protocol[name]
    data = bytearray(codec.length)
    values = [max(s.minimum, min(s.maximum, 0.0)) for s in codec.signals]
    if name == "ESTOP":
        values[codec.index("source")] = EstopSource.PANEL if kind == PANEL_ESTOP else EstopSource.RIG
        values[codec.index("active")] = float(fill & 1)
    codec.encode_into(data, values, counter)
    frame_id, extended, remote, fd, error = codec.frame_id, False, False, codec.is_fd, False
    if kind == BAD_CRC:
        data[0] ^= 1 + fill % 255
    elif kind == SHORT:
        data = data[:-1]
    elif kind == UNKNOWN:
        frame_id = 0x7F0 - fill % 8
    elif kind == EXTENDED:
        extended = True
    elif kind == REMOTE:
        remote, data = True, bytearray()
    elif kind == OTHER_FORMAT:
        fd = not fd
    elif kind == ERROR:
        frame_id, error, data = CAN_ERR_BUSOFF, True, bytearray(8)
    elif kind == OUT_OF_RANGE:
        for k in range(2, len(data)):
            data[k] = 0xFF
        protect(data, counter, codec.data_ids)
    return can.Message(
        arbitration_id=frame_id, is_extended_id=extended, is_remote_frame=remote, is_error_frame=error, is_fd=fd,
        data=data, dlc=len(data) if not remote else codec.length,
    )


def _frames(protocol: Protocol, plan: list[tuple[int, int, int]]) -> list[can.Message]:
    """Frames from ``(kind, message index, fill)`` triples, each message's counter advancing as a sender's would."""
    names = list(HARNESS_RX) + (["SENSOR_SET"] if protocol.fd else [])
    counters = dict.fromkeys(names, 0)
    frames = []
    for kind, which, fill in plan:
        name = "ESTOP" if kind == PANEL_ESTOP else names[which % len(names)]
        if kind == REPEAT:
            counters[name] = (counters[name] - 1) % 16
        frames.append(_frame(protocol, kind, name, counters[name], fill))
        counters[name] = (counters[name] + 1) % 16
    return frames


def _outcome(reader: HarnessReader) -> dict:
    """Everything a poll leaves behind that the tick or a report reads."""
    samples = {}
    for sample in reader._sample_list:
        samples[sample.name] = (
            [repr(v) if math.isnan(v) else v for v in sample.values], sample.count, sample.fresh, int(sample.last_status),
            sample.rx_time if sample.count else None,
        )
    decoder = reader.decoder
    return {
        "samples": samples,
        "counts": list(decoder.counts),
        "accepted": {name: decoder.accepted(name) for name in decoder._slot},
        "rejected": {name: [decoder.rejected(name, s) for s in RxStatus] for name in decoder._slot},
        "last": decoder.last.name if decoder.last is not None else None,
        "foreign": reader.counters.foreign_commands,
        "estop": (reader.estop_requested, reader.counters.estop_frames, reader.counters.panel_frames),
        "errors": (reader.health.error_frames, reader.health.bus_off_events),
        "frames": reader.counters.frames,
    }


@pytest.fixture
def pair() -> Iterator[tuple[SeqPacketBus, SeqPacketBus]]:
    """A receiving node and a sending node on a fresh ``seqpacket`` channel."""
    channel = f"kernel-{uuid.uuid4().hex}"
    receiver = can.Bus(interface="seqpacket", channel=channel)
    sender = can.Bus(interface="seqpacket", channel=channel)
    assert isinstance(receiver, SeqPacketBus) and isinstance(sender, SeqPacketBus)
    receiver.recv(timeout=0)  # the hub accepts the sender
    yield receiver, sender
    sender.shutdown()
    receiver.shutdown()


_PLAN = st.lists(st.tuples(st.integers(0, PANEL_ESTOP), st.integers(0, 20), st.integers(0, 255)), min_size=1, max_size=40)


@pytest.mark.parametrize("protocol", [CLASSIC, FD], ids=["classic", "fd"])
@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(plan=_PLAN, split=st.integers(1, 40))
def test_the_compiled_datagram_path_judges_every_frame_as_the_message_path(
    pair: tuple[SeqPacketBus, SeqPacketBus], protocol: Protocol, plan: list[tuple[int, int, int]], split: int,
) -> None:
    receiver, sender = pair
    frames = _frames(protocol, plan)
    direct = HarnessReader(receiver, protocol, max_frames=split)  # polls of at most `split` frames: capped polls too
    reference = HarnessReader(ListBus(), protocol)
    assert receiver.direct_fd >= 0, "one peer: the compiled receive is the path under test"
    for msg in frames:
        sender.send(msg)
    while direct.poll(NOW_S, keep_fresh=True):
        pass
    reference.bus.pending = list(frames)  # type: ignore[attr-defined]
    reference.poll(NOW_S, keep_fresh=True)
    assert _outcome(direct) == _outcome(reference)
    assert direct.counters.polls_capped == len(frames) // split


def test_a_poll_compiles_nothing_the_reader_did_not_compile_when_it_was_made(pair: tuple[SeqPacketBus, SeqPacketBus]) -> None:
    receiver, sender = pair
    reader = HarnessReader(receiver, CLASSIC)
    kernels = (kernel.decode_frame, kernel.decode_datagrams, kernel.receive_datagrams, kernel.unpack_signals)
    before = [len(k.signatures) for k in kernels]
    # unpack_signals runs inside the other three; its own dispatcher has a signature only once the codec's
    # unpack ran in this process, or the kernels were compiled here rather than loaded from numba's cache
    assert all(before[:3]), "the decoder compiles (or loads) every kernel a poll calls when it is made"
    for msg in _frames(CLASSIC, [(VALID, k, k) for k in range(8)] + [(BAD_CRC, 1, 3), (ERROR, 0, 0)]):
        sender.send(msg)
    assert reader.poll(NOW_S) == 10
    assert [len(k.signatures) for k in kernels] == before


def test_a_malformed_datagram_is_counted_by_the_bus_and_skipped(pair: tuple[SeqPacketBus, SeqPacketBus]) -> None:
    receiver, _ = pair
    reader = HarnessReader(receiver, CLASSIC)
    raw = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    try:
        raw.connect(parse_channel(receiver.channel).address)
        deadline = time.monotonic() + 5.0
        while receiver.peer_count < 2 and time.monotonic() < deadline:  # the hub accepts it within its check interval
            receiver.recv(timeout=0.01)
        assert receiver.peer_count == 2 and receiver.direct_fd == -1, "two peers: the bus's own path (it relays)"
        valid = _frames(CLASSIC, [(VALID, 0, 0)])[0]
        raw.send(b"\x01\x02")  # shorter than the header
        raw.send(encode_frame(valid))
        assert reader.poll(NOW_S) == 1
        assert receiver.malformed_frames == 1
    finally:
        raw.close()


def test_the_compiled_receive_counts_a_malformed_datagram_as_the_bus_does() -> None:
    channel = f"@kernel-{uuid.uuid4().hex}"
    raw_hub = socket.socket(socket.AF_UNIX, socket.SOCK_SEQPACKET)
    raw_hub.bind(parse_channel(channel).address)
    raw_hub.listen(1)
    node = can.Bus(interface="seqpacket", channel=channel)
    assert isinstance(node, SeqPacketBus)
    peer, _ = raw_hub.accept()
    try:
        reader = HarnessReader(node, CLASSIC)
        assert node.direct_fd >= 0
        peer.send(b"\x01\x02")
        peer.send(b"\x00" * 80)  # longer than any frame (the receiver reads one byte more than the largest)
        peer.send(encode_frame(_frames(CLASSIC, [(VALID, 1, 0)])[0]))
        assert reader.poll(NOW_S) == 1
        assert node.malformed_frames == 2
        assert reader.base.count == 1
    finally:
        node.shutdown()
        peer.close()
        raw_hub.close()


def test_the_end_of_the_peer_is_left_to_the_bus_which_drops_it(pair: tuple[SeqPacketBus, SeqPacketBus]) -> None:
    receiver, sender = pair
    reader = HarnessReader(receiver, CLASSIC)
    sender.send(_frames(CLASSIC, [(VALID, 0, 0)])[0])
    sender.shutdown()
    assert reader.poll(NOW_S) == 1, "the frame sent before the end is still read"
    assert reader.poll(NOW_S) == 0
    assert receiver.peer_count == 0 and receiver.direct_fd == -1


# --- the compiled checks against the sender's CRC and cantools' decoding ------------------------------


@given(data=st.binary(min_size=2, max_size=64), data_ids=st.lists(st.integers(0, 255), min_size=16, max_size=16))
def test_the_compiled_crc_is_the_one_the_sender_writes(data: bytes, data_ids: list[int]) -> None:
    compiled = kernel.crc_profile2(np.frombuffer(data, dtype=np.uint8), 0, len(data), np.array(data_ids), kernel.CRC_TABLE)
    assert compiled == profile2_crc(data, len(data), data_ids)


_DECODER = Decoder(CLASSIC)
_FD_DECODER = Decoder(FD)


@pytest.mark.parametrize(("protocol", "decoder"), [(CLASSIC, _DECODER), (FD, _FD_DECODER)], ids=["classic", "fd"])
@settings(max_examples=300, deadline=None)
@given(which=st.integers(0, 30), payload=st.binary(min_size=64, max_size=64), counter=st.integers(0, 15))
def test_any_payload_with_a_good_crc_decodes_to_cantools_values_or_is_out_of_range(
    protocol: Protocol, decoder: Decoder, which: int, payload: bytes, counter: int,
) -> None:
    codec = list(protocol.messages.values())[which % len(protocol.messages)]
    data = bytearray(payload[: codec.length])
    protect(data, counter, codec.data_ids)
    decoder.reset_counters()
    status = decoder.decode(codec.frame_id, data, fd=codec.is_fd)
    physical = protocol.database.decode_message(codec.frame_id, bytes(data), decode_choices=False, scaling=True)
    expected = [float(physical[name]) for name in codec.signal_names]
    if status == RxStatus.OK:
        assert decoder.values(codec.name) == pytest.approx(expected, rel=1e-12, abs=1e-12)
    else:
        assert status == RxStatus.OUT_OF_RANGE
        assert any(not s.minimum <= v <= s.maximum for s, v in zip(codec.signals, expected, strict=True))


# --- the rolling counter (AUTOSAR E2E profile 2), judged by the compiled checks -------------------------


def _counters(decoder: Decoder, counters: list[int], name: str = "HEARTBEAT") -> list[RxStatus]:
    codec = CLASSIC[name]
    statuses = []
    for counter in counters:
        data = bytearray(codec.length)
        codec.encode_into(data, [1.0] * len(codec.signals), counter)
        statuses.append(decoder.decode(codec.frame_id, data))
    return statuses


def test_the_first_frame_is_accepted_whatever_its_counter_then_each_must_advance_by_one() -> None:
    decoder = Decoder(CLASSIC)
    assert _counters(decoder, [9, 10, 11, 12, 13, 14, 15, 0, 1]) == [RxStatus.OK] * 9


def test_a_repeated_counter_is_rejected_and_the_state_kept() -> None:
    decoder = Decoder(CLASSIC)
    assert _counters(decoder, [3, 3, 4]) == [RxStatus.OK, RxStatus.REPEATED_COUNTER, RxStatus.OK]


def test_a_skipped_counter_is_rejected_and_the_state_resynchronised() -> None:
    decoder = Decoder(CLASSIC)
    statuses = _counters(decoder, [3, 5, 6, 15, 0])
    assert statuses == [RxStatus.OK, RxStatus.SKIPPED_COUNTER, RxStatus.OK, RxStatus.SKIPPED_COUNTER, RxStatus.OK]


def test_zero_is_a_counter_like_any_other_and_a_reset_accepts_anything() -> None:
    decoder = Decoder(CLASSIC)
    assert _counters(decoder, [0, 5]) == [RxStatus.OK, RxStatus.SKIPPED_COUNTER]
    decoder.reset_counters()
    assert _counters(decoder, [15, 0, 0, 3]) == [RxStatus.OK, RxStatus.OK, RxStatus.REPEATED_COUNTER, RxStatus.SKIPPED_COUNTER]
    decoder.reset_counter(CLASSIC["HEARTBEAT"].frame_id)
    assert _counters(decoder, [12]) == [RxStatus.OK]


def test_counters_are_kept_per_message_and_a_reset_of_one_leaves_the_others() -> None:
    decoder = Decoder(CLASSIC)
    assert _counters(decoder, [4], "HEARTBEAT") + _counters(decoder, [9], "ACTUATOR_CMD") == [RxStatus.OK] * 2
    decoder.reset_counter(CLASSIC["HEARTBEAT"].frame_id)
    assert _counters(decoder, [0], "HEARTBEAT") == [RxStatus.OK]
    assert _counters(decoder, [9], "ACTUATOR_CMD") == [RxStatus.REPEATED_COUNTER]
    decoder.reset_counter(0x7FF)  # not received: nothing to forget, no error
    decoder.reset_counter(-1)


def test_a_reset_of_an_identifier_no_message_has_forgets_nothing_and_never_raises() -> None:
    """Not even the decoder's last message's history (its slot is the one a negative index would reach)."""
    decoder = Decoder(CLASSIC)
    last = list(CLASSIC.messages)[-1]
    assert _counters(decoder, [9], last) == [RxStatus.OK]
    for frame_id in (0x7FF, 0x7FE, 0x800, -1, 10**6):  # no message, past the 11-bit range, negative
        decoder.reset_counter(frame_id)
    assert _counters(decoder, [9], last) == [RxStatus.REPEATED_COUNTER]


def _edge_protocol(folder) -> Protocol:
    """The shipped DBC with ESTOP at identifier 0, ACTUATOR_CMD at 1 and HEARTBEAT at 0x7FF: the 11-bit range's ends."""
    text = REPO_DBC.read_text("utf-8")
    for old_id, new_id in ((16, 0), (32, 1), (80, 0x7FF)):
        text = re.sub(rf"\b(BO_|SG_|VAL_) {old_id} ", rf"\1 {new_id} ", text)
    (folder / "edges.dbc").write_text(text, encoding="utf-8")
    protocol = load_protocol(folder / "edges.dbc")
    assert [protocol[n].frame_id for n in ("ESTOP", "ACTUATOR_CMD", "HEARTBEAT")] == [0, 1, 0x7FF]
    return protocol


def test_the_decoders_first_message_and_the_edges_of_the_11_bit_range_reset(tmp_path) -> None:
    protocol = _edge_protocol(tmp_path)
    for names in (["ESTOP", "HEARTBEAT"], ["HEARTBEAT", "ESTOP"]):  # each message in slot 0 once
        decoder = Decoder(protocol, names)
        for name in names:
            codec = protocol[name]
            data = bytearray(codec.length)
            codec.encode_into(data, [0.0] * len(codec.signals), 5)
            assert decoder.decode(codec.frame_id, data) == RxStatus.OK
            assert decoder.decode(codec.frame_id, data) == RxStatus.REPEATED_COUNTER
            decoder.reset_counter(codec.frame_id)
            assert decoder.decode(codec.frame_id, data) == RxStatus.OK, name  # forgotten: any counter is accepted


def test_a_new_decoder_has_counted_nothing_whatever_identifiers_its_protocol_uses(tmp_path) -> None:
    """Its kernels are compiled at construction on frames no message can own (identifier -1, no datagram)."""
    protocol = _edge_protocol(tmp_path)
    decoder = Decoder(protocol)
    assert decoder.last is None and decoder.rejected_total == 0
    for name in protocol.messages:
        assert decoder.accepted(name) == 0
        assert all(decoder.rejected(name, status) == 0 for status in RxStatus if status != RxStatus.OK), name
