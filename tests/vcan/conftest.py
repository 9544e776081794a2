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


#: MTU of an interface that carries CAN FD frames.
CANFD_MTU = 72


@pytest.fixture
def vcan_channel() -> str:
    """The vcan interface name; skips the test where it does not exist."""
    if not VCAN_PATH.exists():
        pytest.skip(SKIP_REASON)
    return VCAN_CHANNEL


@pytest.fixture
def vcan_fd_channel(vcan_channel: str) -> str:
    """The vcan interface, able to carry CAN FD frames (MTU 72, as scripts/with-vcan creates it); skips otherwise."""
    mtu = int((VCAN_PATH / "mtu").read_text().strip())
    if mtu < CANFD_MTU:
        pytest.skip(
            f"{VCAN_CHANNEL} has MTU {mtu}, too small for CAN FD frames: `ip link set {VCAN_CHANNEL} down && "
            f"ip link set {VCAN_CHANNEL} mtu {CANFD_MTU} && ip link set up {VCAN_CHANNEL}` (scripts/with-vcan does it)"
        )
    return vcan_channel
