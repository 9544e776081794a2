"""The profile's ``can`` section handed to the drivers: a checked, open CAN link from a :class:`CanConfig`.

The drivers take plain arguments, as ``can.Bus`` does (:mod:`drivers.link`); this
module is the one place that turns the harness's :class:`~harness.canbus.config.CanConfig`
into them. The functions keep the names and the order of checks of the drivers' own
(:func:`prepare` refuses a configuration before any bus is opened).
"""

from __future__ import annotations

from collections.abc import Collection
from typing import Any

from drivers import link
from drivers.link import HarnessLink, RigLink
from drivers.protocol.busload import BusLoad
from drivers.protocol.codec import Protocol
from harness.canbus.config import CanConfig


def protocol_arguments(config: CanConfig) -> dict[str, Any]:
    """What :func:`drivers.link.prepare` takes besides rates and bitrate: allowed load, version, DBC path, CAN FD."""
    return {
        "max_bus_load": config.max_bus_load,
        "protocol_version": config.protocol_version,
        "dbc_path": config.dbc_path or None,
        "fd": config.fd,
        "data_bitrate_bps": config.data_bitrate_bps,
    }


#: The python-can interface whose bus checks its peers' credentials (drivers/transports/seqpacket/).
PEER_CHECKED_INTERFACE = "seqpacket"


def bus_options(config: CanConfig, peer_pids: Collection[int] | None = None) -> dict[str, Any]:
    """The bus's own keyword arguments: on ``seqpacket``, who may join (``can.peer_group``, ``peer_pids``).

    Other interfaces get none: their access is the operating system's (a SocketCAN interface, an adapter).
    """
    if config.interface != PEER_CHECKED_INTERFACE:
        return {}
    options: dict[str, Any] = {"peer_group": config.peer_group or None}
    if peer_pids:
        options["peer_pids"] = tuple(peer_pids)
    return options


def link_arguments(config: CanConfig, peer_pids: Collection[int] | None = None) -> dict[str, Any]:
    """Keyword arguments of :func:`drivers.link.open_rig` for ``config`` (the bus and its checks).

    ``peer_pids``: the only processes that may be at the other end of a ``seqpacket`` channel.
    """
    return {
        "interface": config.interface,
        "channel": config.channel,
        "bitrate_bps": config.bitrate_bps,
        "rates_hz": config.rates_hz(),
        "bus_options": bus_options(config, peer_pids),
        **protocol_arguments(config),
    }


def harness_link_arguments(config: CanConfig, peer_pids: Collection[int] | None = None) -> dict[str, Any]:
    """Keyword arguments of :func:`drivers.link.open_harness` for ``config``: those of the rig, and the reader's."""
    return {
        **link_arguments(config, peer_pids),
        "use_msg_timestamp": config.timestamp_source == "message",
        "max_frames_per_poll": config.max_frames_per_poll,
    }


def prepare(config: CanConfig) -> tuple[Protocol, BusLoad]:
    """Load the DBC and check version and bus load, without touching the bus.

    Raises
    ------
    ProtocolError
        The DBC is unreadable or its ProtocolVersion differs from ``config.protocol_version``.
    BusLoadError
        The configured rates need more than ``config.max_bus_load`` of the bitrate.
    """
    return link.prepare(config.rates_hz(), config.bitrate_bps, **protocol_arguments(config))


def open_harness(config: CanConfig, peer_pids: Collection[int] | None = None) -> HarnessLink:
    """Check the configuration, then open the bus for the harness side.

    ``peer_pids``: on ``seqpacket``, the only processes admitted at the other end (the rig a dry run started).

    Raises
    ------
    ProtocolError, BusLoadError
        From :func:`prepare`, before the bus is opened.
    BusError
        The bus cannot be opened (says how to fix it).
    """
    return link.open_harness(**harness_link_arguments(config, peer_pids))


def open_rig(config: CanConfig, peer_pids: Collection[int] | None = None) -> RigLink:
    """Check the configuration, then open the bus for the rig side (the virtual rig); as :func:`open_harness`."""
    return link.open_rig(**link_arguments(config, peer_pids))
