"""The driver contract (tests/unit/test_bus_contract.py) on real SocketCAN: ``vcan0``.

Same test bodies as the virtual-interface run; only the two fixtures differ. Skipped,
naming scripts/with-vcan, where ``/sys/class/net/vcan0`` does not exist.
"""

from __future__ import annotations

import pytest

from tests.unit.test_bus_contract import BusContract, Channel

pytestmark = pytest.mark.vcan


class TestSocketcanContract(BusContract):
    """The contract on the kernel's SocketCAN ``vcan0``."""

    @pytest.fixture
    def config(self, vcan_channel: str) -> Channel:
        return Channel("socketcan", vcan_channel)

    @pytest.fixture
    def nonexistent(self, vcan_channel: str) -> tuple[Channel, str]:
        return Channel("socketcan", "vcan_nonexist"), r"ip link add dev vcan_nonexist type vcan"
