"""Sample ages with ``timestamp_source=message``: right on the loop's clock, invalid from the future."""

from __future__ import annotations

import math
import time
import uuid

import can

from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness, open_rig


def _pair():
    config = CanConfig(interface="virtual", channel=f"ts-{uuid.uuid4().hex[:8]}", timestamp_source="message")
    return open_rig(config), open_harness(config)


def test_message_time_is_moved_onto_the_loops_clock():
    rig, harness = _pair()
    try:
        now = 12.5  # the loop's clock: seconds since the run began, nothing like the epoch
        rig.writer.table(0.0, 0.0, 0.0, 0.0)
        harness.reader.poll(now)
        age = harness.reader.table.age(now)
        assert 0.0 <= age < 0.05  # the frame's real age, not now - epoch (about -1.8e9 s)
    finally:
        rig.close()
        harness.close()


class StubBus:
    """Hands out the given messages as they are, timestamps included (python-can's virtual bus restamps)."""

    def __init__(self, messages):
        self.messages = list(messages)

    def recv(self, timeout=None):
        return self.messages.pop(0) if self.messages else None


def test_a_frame_stamped_in_the_future_has_no_valid_age():
    from drivers.protocol.codec import load_protocol
    from drivers.reader import HarnessReader

    protocol = load_protocol()
    codec = protocol["TABLE_SENSORS"]
    future = can.Message(arbitration_id=codec.frame_id, data=codec.encode([0.0, 0.0, 0.0], 0), is_extended_id=False,
                         timestamp=time.time() + 3600.0)
    reader = HarnessReader(StubBus([future]), protocol, use_msg_timestamp=True)
    reader.poll(1.0)
    assert reader.table.count == 1
    assert math.isnan(reader.table.age(1.0))  # NaN fails every 0 <= age <= max check
