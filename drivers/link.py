"""One call from a ``CanConfig`` to a checked, open CAN link with its reader and writer.

:func:`prepare` does everything that can refuse a configuration before the bus is
opened (so nothing is ever sent with a refused configuration): load and compile
the DBC, check its protocol version against the profile, check the bus load.
:func:`open_harness` and :func:`open_rig` then open the bus and build the side's
reader and writer around one shared :class:`~drivers.bus.BusHealth`.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import TracebackType

import can

from drivers.bus import BusHealth, open_bus
from drivers.busload import BusLoad, check_bus_load
from drivers.codec import Protocol, check_protocol_version, load_protocol
from drivers.config import CanConfig
from drivers.reader import HarnessReader, RigReader
from drivers.writer import HarnessWriter, RigWriter


def prepare(config: CanConfig) -> tuple[Protocol, BusLoad]:
    """Load the DBC and check version and bus load, without touching the bus.

    Raises
    ------
    ProtocolError
        The DBC is unreadable or its ProtocolVersion differs from ``config.protocol_version``.
    BusLoadError
        The configured rates need more than ``config.max_bus_load`` of the bitrate.
    """
    protocol = load_protocol(config.dbc_path or None)
    check_protocol_version(protocol, config.protocol_version)
    load = check_bus_load(config, protocol)
    return protocol, load


@dataclass
class _Link:
    """An open bus with its protocol, bus load and health; closes the bus on exit."""

    bus: can.BusABC
    protocol: Protocol
    load: BusLoad
    health: BusHealth

    def close(self) -> None:
        """Shut the bus down (idempotent)."""
        self.bus.shutdown()

    def __enter__(self) -> _Link:
        return self

    def __exit__(self, kind: type[BaseException] | None, error: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


@dataclass
class HarnessLink(_Link):
    """The harness side: :class:`HarnessReader` (sensors, status, E-stop) and :class:`HarnessWriter`."""

    reader: HarnessReader
    writer: HarnessWriter

    def __enter__(self) -> HarnessLink:
        return self


@dataclass
class RigLink(_Link):
    """The rig side: :class:`RigReader` (commands, heartbeat, rig control, E-stop) and :class:`RigWriter`."""

    reader: RigReader
    writer: RigWriter

    def __enter__(self) -> RigLink:
        return self


def open_harness(config: CanConfig) -> HarnessLink:
    """Check the configuration, then open the bus for the harness side.

    Raises
    ------
    ProtocolError, BusLoadError
        From :func:`prepare`, before the bus is opened.
    BusError
        The bus cannot be opened (says how to fix it).
    """
    protocol, load = prepare(config)
    bus = open_bus(config)
    health = BusHealth()
    return HarnessLink(
        bus, protocol, load, health, HarnessReader(bus, protocol, config, health), HarnessWriter(bus, protocol, health)
    )


def open_rig(config: CanConfig) -> RigLink:
    """Check the configuration, then open the bus for the rig side (the virtual rig)."""
    protocol, load = prepare(config)
    bus = open_bus(config)
    health = BusHealth()
    return RigLink(bus, protocol, load, health, RigReader(bus, protocol, config, health), RigWriter(bus, protocol, health))
