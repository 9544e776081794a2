"""The preallocated rings the tick writes into: order, wrap-around, drops, frame fields."""

from __future__ import annotations

import can
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.recording.ring import FrameRing, RecordingError, RowRing


def test_rows_come_out_in_order_across_the_wrap() -> None:
    ring = RowRing(2, 4)
    for i in range(3):
        assert ring.push((float(i), -float(i)))
    assert ring.drain()[:, 0].tolist() == [0.0, 1.0, 2.0]
    for i in range(3, 7):
        assert ring.push(np.array([float(i), -float(i)]))
    block = ring.drain()
    assert block[:, 0].tolist() == [3.0, 4.0, 5.0, 6.0]
    assert block[:, 1].tolist() == [-3.0, -4.0, -5.0, -6.0]


def test_full_ring_drops_and_counts_instead_of_blocking() -> None:
    ring = RowRing(1, 3)
    accepted = [ring.push((float(i),)) for i in range(5)]
    assert accepted == [True, True, True, False, False]
    assert ring.dropped == 2
    assert ring.drain()[:, 0].tolist() == [0.0, 1.0, 2.0]
    assert ring.push((9.0,))


def test_drained_block_is_a_copy_not_a_view_of_the_ring() -> None:
    ring = RowRing(1, 2)
    ring.push((1.0,))
    block = ring.drain()
    ring.push((2.0,))
    ring.push((3.0,))
    assert block[0, 0] == 1.0


@pytest.mark.parametrize("row", [(1.0,), (1.0, 2.0, 3.0), np.zeros(3)])
def test_wrong_row_length_is_refused_with_both_counts(row: tuple[float, ...]) -> None:
    ring = RowRing(2, 4)
    with pytest.raises(RecordingError, match=r"found a row of \d values, expected 2"):
        ring.push(row)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.one_of(st.integers(min_value=1, max_value=7), st.just(0)), max_size=40))
def test_interleaved_pushes_and_drains_lose_nothing_but_counted_drops(steps: list[int]) -> None:
    """Each step pushes n rows (0 = drain); accepted rows come out once, in order."""
    ring = RowRing(1, 5)
    accepted: list[float] = []
    drained: list[float] = []
    counter = 0
    for n in steps:
        if n == 0:
            drained += ring.drain()[:, 0].tolist()
            continue
        for _ in range(n):
            if ring.push((float(counter),)):
                accepted.append(float(counter))
            counter += 1
    drained += ring.drain()[:, 0].tolist()
    assert drained == accepted
    assert len(accepted) + ring.dropped == counter


def _frames() -> list[can.Message]:
    return [
        can.Message(timestamp=1.5, arbitration_id=0x123, data=b"\x01\x02", is_extended_id=False, is_rx=True, channel="vcan0"),
        can.Message(timestamp=1.6, arbitration_id=0x1ABCDE, data=bytes(range(8)), is_extended_id=True, is_rx=False, channel=1),
        can.Message(timestamp=1.7, arbitration_id=0x7FF, is_remote_frame=True, dlc=0, is_extended_id=False, is_rx=True),
        can.Message(
            timestamp=1.8, arbitration_id=0x10, data=bytes(range(64)), is_fd=True, bitrate_switch=True, is_extended_id=False
        ),
    ]


def test_frame_ring_keeps_every_field() -> None:
    ring = FrameRing(8)
    for msg in _frames():
        assert ring.push(msg)
    out = ring.drain()
    assert len(out) == 4
    for sent, got in zip(_frames(), out, strict=True):
        assert got.equals(sent, timestamp_delta=0.0)
        assert got.is_rx == sent.is_rx
        assert got.channel == sent.channel
    assert out[3].bitrate_switch


def test_frame_ring_drops_when_full() -> None:
    ring = FrameRing(2)
    results = [ring.push(msg) for msg in _frames()]
    assert results == [True, True, False, False]
    assert ring.dropped == 2
    assert [m.arbitration_id for m in ring.drain()] == [0x123, 0x1ABCDE]


def test_drain_can_take_a_bounded_chunk() -> None:
    ring = RowRing(1, 8)
    for i in range(5):
        ring.push((float(i),))
    assert ring.drain(2)[:, 0].tolist() == [0.0, 1.0]
    assert ring.pending == 3
    assert ring.drain()[:, 0].tolist() == [2.0, 3.0, 4.0]
