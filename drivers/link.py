"""One call from plain settings to a checked, open CAN link with its reader and writer.

:func:`prepare` does everything that can refuse a configuration before the bus is
opened (so nothing is ever sent with a refused configuration): load and compile
the DBC, check its protocol version against the expected one, check the bus load.
:func:`open_harness` then opens the bus and builds the harness's reader and writer around
one shared :class:`~drivers.transports.bus.BusHealth`; :func:`open_rig` builds the rig's writer. The rig
reads frame by frame on its own clock, so it builds its :class:`~drivers.rig_reader.RigReader`
itself, on the link's bus.

Like ``can.Bus``, these take plain arguments (interface, channel, bitrate, rates as a
mapping, DBC path); the harness adapts its profile's ``can`` section to them
(:mod:`harness.canbus.link`).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

import can

from drivers.protocol.busload import BusLoad, check_bus_load
from drivers.protocol.codec import Protocol, check_protocol_version, load_protocol
from drivers.protocol.protocol_values import CURRENT_PROTOCOL_VERSION
from drivers.reader import HarnessReader
from drivers.transports.bus import BusHealth, open_bus
from drivers.writer import HarnessWriter, RigWriter


def prepare(
    rates_hz: Mapping[str, float],
    bitrate_bps: int,
    *,
    max_bus_load: float = 0.5,
    protocol_version: int = CURRENT_PROTOCOL_VERSION,
    dbc_path: str | Path | None = None,
    fd: bool = False,
    data_bitrate_bps: int | None = None,
) -> tuple[Protocol, BusLoad]:
    """Load the DBC and check version and bus load, without touching the bus.

    Parameters
    ----------
    rates_hz : mapping of str to float
        Rate of every message of the DBC (Hz).
    bitrate_bps : int
        Bitrate (bit/s).
    max_bus_load : float
        Largest allowed share of the bitrate (0..1).
    protocol_version : int
        The ``ProtocolVersion`` the DBC must have.
    dbc_path : str or Path, optional
        The DBC; None or empty means the packaged ``drivers/protocol/rig.dbc`` (``drivers/protocol/rig_fd.dbc`` with ``fd``).
    fd : bool
        The CAN FD variant of the protocol: the DBC must describe FD frames, and the bus load counts FD timing.
    data_bitrate_bps : int, optional
        Data-phase bitrate of the FD frames (bit/s); default the nominal one.

    Raises
    ------
    ProtocolError
        The DBC is unreadable, its ProtocolVersion differs from ``protocol_version``, or its
        frame format is not the one ``fd`` asks for.
    BusLoadError
        The rates need more than ``max_bus_load`` of the bitrate.
    """
    protocol = load_protocol(dbc_path or None, fd=fd)
    check_protocol_version(protocol, protocol_version)
    load = check_bus_load(protocol, rates_hz, bitrate_bps, max_bus_load, data_bitrate_bps if fd else None)
    return protocol, load


def _checked_bus(
    interface: str,
    channel: str,
    bitrate_bps: int,
    rates_hz: Mapping[str, float],
    max_bus_load: float,
    protocol_version: int,
    dbc_path: str | Path | None,
    fd: bool = False,
    data_bitrate_bps: int | None = None,
    bus_options: Mapping[str, Any] | None = None,
) -> tuple[can.BusABC, Protocol, BusLoad, BusHealth]:
    """What both sides do before their reader and writer: :func:`prepare`, then open the bus, with a fresh health."""
    protocol, load = prepare(
        rates_hz, bitrate_bps, max_bus_load=max_bus_load, protocol_version=protocol_version, dbc_path=dbc_path,
        fd=fd, data_bitrate_bps=data_bitrate_bps,
    )
    bus = open_bus(interface, channel, bitrate_bps, fd=fd, data_bitrate_bps=data_bitrate_bps, **(bus_options or {}))
    return bus, protocol, load, BusHealth()


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
    """The rig side: :class:`RigWriter` (the rig receives through :class:`~drivers.rig_reader.RigReader` on ``bus``)."""

    writer: RigWriter

    def __enter__(self) -> RigLink:
        return self


def open_harness(
    interface: str,
    channel: str,
    bitrate_bps: int,
    rates_hz: Mapping[str, float],
    *,
    max_bus_load: float = 0.5,
    protocol_version: int = CURRENT_PROTOCOL_VERSION,
    dbc_path: str | Path | None = None,
    use_msg_timestamp: bool = False,
    max_frames_per_poll: int = 256,
    fd: bool = False,
    data_bitrate_bps: int | None = None,
    bus_options: Mapping[str, Any] | None = None,
) -> HarnessLink:
    """Check the settings, then open the bus for the harness side.

    Parameters
    ----------
    interface, channel : str
        The python-can interface and channel (see :func:`drivers.transports.bus.open_bus`).
    bitrate_bps, rates_hz, max_bus_load, protocol_version, dbc_path, fd, data_bitrate_bps
        As for :func:`prepare`; with ``fd`` the bus is opened for CAN FD frames.
    use_msg_timestamp : bool
        The reader takes a frame's receive time from ``msg.timestamp`` instead of ``poll``'s ``now``.
    max_frames_per_poll : int
        Most frames one ``poll`` of the reader handles.
    bus_options : mapping, optional
        Further keyword arguments of the interface's bus (the ``seqpacket`` bus's ``peer_group``, ``peer_pids``).

    Raises
    ------
    ProtocolError, BusLoadError
        From :func:`prepare`, before the bus is opened.
    BusError
        The bus cannot be opened (says how to fix it).
    """
    bus, protocol, load, health = _checked_bus(
        interface, channel, bitrate_bps, rates_hz, max_bus_load, protocol_version, dbc_path, fd, data_bitrate_bps,
        bus_options,
    )
    reader = HarnessReader(bus, protocol, health, use_msg_timestamp=use_msg_timestamp, max_frames=max_frames_per_poll)
    return HarnessLink(bus, protocol, load, health, reader, HarnessWriter(bus, protocol, health))


def open_rig(
    interface: str,
    channel: str,
    bitrate_bps: int,
    rates_hz: Mapping[str, float],
    *,
    max_bus_load: float = 0.5,
    protocol_version: int = CURRENT_PROTOCOL_VERSION,
    dbc_path: str | Path | None = None,
    fd: bool = False,
    data_bitrate_bps: int | None = None,
    bus_options: Mapping[str, Any] | None = None,
) -> RigLink:
    """Check the settings, then open the bus for the rig side (the virtual rig); parameters as :func:`open_harness`."""
    bus, protocol, load, health = _checked_bus(
        interface, channel, bitrate_bps, rates_hz, max_bus_load, protocol_version, dbc_path, fd, data_bitrate_bps,
        bus_options,
    )
    return RigLink(bus, protocol, load, health, RigWriter(bus, protocol, health))
