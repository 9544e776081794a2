"""Fixtures for the SocketCAN tests: skip, with the way to get vcan0, where it does not exist."""

from __future__ import annotations

from pathlib import Path

import pytest

VCAN_CHANNEL = "vcan0"
VCAN_PATH = Path("/sys/class/net") / VCAN_CHANNEL
SKIP_REASON = (
    f"no SocketCAN {VCAN_CHANNEL} here ({VCAN_PATH} does not exist): create it with "
    f"`ip link add dev {VCAN_CHANNEL} type vcan && ip link set up {VCAN_CHANNEL}`, or run "
    "`scripts/with-vcan pytest -m vcan tests/vcan` (User-Mode Linux) where the kernel has no CAN"
)


@pytest.fixture
def vcan_channel() -> str:
    """The vcan interface name; skips the test where it does not exist."""
    if not VCAN_PATH.exists():
        pytest.skip(SKIP_REASON)
    return VCAN_CHANNEL
