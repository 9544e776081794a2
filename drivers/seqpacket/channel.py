"""Channels of the ``seqpacket`` interface: a channel name and the socket address its hub listens on.

A plain name (``harness``, or ``@harness``) is the Linux abstract socket address
``"\\0shaketable-can/harness"``: no file, freed by the kernel when the hub exits.
A channel containing ``/`` is a filesystem path; a stale socket file there (connect
refused) is unlinked before binding, and the hub unlinks the file it created on
shutdown (:class:`drivers.seqpacket.bus.SeqPacketBus`).
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass

from drivers.errors import BusError

#: Abstract-namespace prefix of plain channel names (the leading NUL makes it abstract).
ABSTRACT_PREFIX = "\0shaketable-can/"
_NAME_RE = re.compile(r"[A-Za-z0-9_.:+=-]+")
_MAX_NAME_BYTES = 108 - len(ABSTRACT_PREFIX)  # sun_path holds 108 bytes
_MAX_PATH_BYTES = 107  # sun_path minus the terminating NUL


@dataclass(frozen=True)
class ChannelAddress:
    """Where a channel's hub listens.

    Attributes
    ----------
    name : str
        The channel as given (``harness``, ``@harness`` or a path).
    address : str
        What ``bind``/``connect`` take: ``"\\0shaketable-can/<name>"`` or the path.
    path : str or None
        The filesystem path, or None for an abstract address.
    """

    name: str
    address: str
    path: str | None


def parse_channel(channel: object) -> ChannelAddress:
    """Map a channel name to its socket address.

    Parameters
    ----------
    channel : str
        A plain name such as ``harness`` or ``@harness`` (abstract address, no file), or a
        path containing ``/`` such as ``/tmp/rig.sock`` (a socket file).

    Returns
    -------
    ChannelAddress

    Raises
    ------
    BusError
        Not a string, empty, illegal characters, too long, or a path whose directory is missing.
    """
    expected = (
        "expected a name of letters, digits and ._:+=- such as 'harness' (an abstract socket, no file) "
        "or a socket path containing '/' such as '/tmp/rig.sock'"
    )
    if not isinstance(channel, str):
        raise BusError(f"seqpacket channel {channel!r} is a {type(channel).__name__}; {expected}")
    if "\0" in channel:
        raise BusError(f"seqpacket channel {channel!r} contains a NUL byte; {expected}")
    if "/" in channel:
        return _parse_path(channel, expected)
    name = channel[1:] if channel.startswith("@") else channel
    if not _NAME_RE.fullmatch(name):
        raise BusError(f"seqpacket channel {channel!r} is not a usable name; {expected}")
    if len(name.encode()) > _MAX_NAME_BYTES:
        raise BusError(
            f"seqpacket channel {channel!r} is {len(name)} characters; at most {_MAX_NAME_BYTES} fit an abstract socket address"
        )
    return ChannelAddress(channel, ABSTRACT_PREFIX + name, None)


def _parse_path(channel: str, expected: str) -> ChannelAddress:
    size = len(os.fsencode(channel))
    if size > _MAX_PATH_BYTES:
        raise BusError(f"seqpacket channel path {channel!r} is {size} bytes; a Unix socket path holds at most {_MAX_PATH_BYTES}")
    if channel.endswith("/"):
        raise BusError(f"seqpacket channel path {channel!r} names a directory; {expected}")
    directory = os.path.dirname(channel) or "."
    if not os.path.isdir(directory):
        raise BusError(f"seqpacket channel path {channel!r}: directory {directory!r} does not exist; create it first")
    return ChannelAddress(channel, channel, channel)
