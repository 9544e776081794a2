"""Tests that need a real SocketCAN ``vcan0`` (run ``pytest -m vcan tests/vcan``, or scripts/with-vcan)."""
