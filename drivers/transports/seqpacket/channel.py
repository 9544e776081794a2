"""Channels of the ``seqpacket`` interface: a channel name and the socket address its hub listens on.

A plain name (``harness``) is a socket file in this user's private directory
(:func:`private_directory`: ``$XDG_RUNTIME_DIR/shaketable-can/``, else
``/tmp/shaketable-can-<uid>/``), which only this user can write, so no other user can
bind a channel's name first. ``@harness`` is the Linux abstract socket address
``"\\0shaketable-can/harness"``: no file, freed by the kernel when the hub exits, but
open to every user of the host (an abstract name has no permissions): the peer check
(:mod:`.peers`) then refuses strangers, yet another user can take the name first (the
channel is then refused, not joined). A channel containing ``/`` is a filesystem path in a
directory that must be owned by this user (or root) and not writable by others
(:func:`check_directory`); a stale socket file there (connect refused) is unlinked before
binding, and the hub unlinks the file it created on shutdown
(:class:`drivers.transports.seqpacket.bus.SeqPacketBus`).
"""

from __future__ import annotations

import os
import re
import stat
from dataclasses import dataclass

from drivers.errors import BusError

#: Abstract-namespace prefix of plain channel names (the leading NUL makes it abstract).
ABSTRACT_PREFIX = "\0shaketable-can/"
_NAME_RE = re.compile(r"[A-Za-z0-9_.:+=-]+")
_MAX_NAME_BYTES = 108 - len(ABSTRACT_PREFIX)  # sun_path holds 108 bytes
_MAX_PATH_BYTES = 107  # sun_path minus the terminating NUL
#: Subdirectory of ``$XDG_RUNTIME_DIR`` holding the plain-named channels.
RUNTIME_SUBDIR = "shaketable-can"
#: Fallback private directory where ``$XDG_RUNTIME_DIR`` is unset or unusable (``{uid}``: the effective uid).
FALLBACK_DIRECTORY = "/tmp/shaketable-can-{uid}"


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
    private : bool
        The path is in :func:`private_directory` (a plain name), which the bus makes if missing.
    """

    name: str
    address: str
    path: str | None
    private: bool = False


def parse_channel(channel: object) -> ChannelAddress:
    """Map a channel name to its socket address.

    Parameters
    ----------
    channel : str
        A plain name such as ``harness`` (a socket file in :func:`private_directory`),
        ``@harness`` (abstract address, no file), or a path containing ``/`` such as
        ``/home/lab/run/rig.sock`` (a socket file).

    Returns
    -------
    ChannelAddress

    Raises
    ------
    BusError
        Not a string, empty, illegal characters, too long, or a path whose directory is missing.
    """
    expected = (
        "expected a name of letters, digits and ._:+=- such as 'harness' (a socket in this user's private "
        "directory), '@harness' (an abstract socket) or a socket path containing '/' such as '/home/lab/run/rig.sock'"
    )
    if not isinstance(channel, str):
        raise BusError(f"seqpacket channel {channel!r} is a {type(channel).__name__}; {expected}")
    if "\0" in channel:
        raise BusError(f"seqpacket channel {channel!r} contains a NUL byte; {expected}")
    if "/" in channel:
        return _parse_path(channel, expected)
    abstract = channel.startswith("@")
    name = channel[1:] if abstract else channel
    if not _NAME_RE.fullmatch(name):
        raise BusError(f"seqpacket channel {channel!r} is not a usable name; {expected}")
    if not abstract:
        path = os.path.join(private_directory(), name)
        if len(os.fsencode(path)) > _MAX_PATH_BYTES:
            raise BusError(
                f"seqpacket channel {channel!r} makes the socket path {path!r}, over the {_MAX_PATH_BYTES} bytes a Unix "
                "socket path holds; pick a shorter name"
            )
        return ChannelAddress(channel, path, path, private=True)
    if len(name.encode()) > _MAX_NAME_BYTES:
        raise BusError(
            f"seqpacket channel {channel!r} is {len(name)} characters; at most {_MAX_NAME_BYTES} fit an abstract socket address"
        )
    return ChannelAddress(channel, ABSTRACT_PREFIX + name, None)


def private_directory() -> str:
    """Where this user's plain-named channels live: ``$XDG_RUNTIME_DIR/shaketable-can``, else ``/tmp/shaketable-can-<uid>``.

    ``$XDG_RUNTIME_DIR`` is used when it is a directory owned by this user that no one else
    can write (as systemd makes ``/run/user/<uid>``). The directory itself is made and
    checked when a bus opens (:func:`ensure_private_directory`).
    """
    runtime = os.environ.get("XDG_RUNTIME_DIR", "")
    if runtime and os.path.isabs(runtime) and not directory_problem(runtime, os.geteuid(), None, private=True):
        return os.path.join(runtime, RUNTIME_SUBDIR)
    return FALLBACK_DIRECTORY.format(uid=os.geteuid())


def ensure_private_directory(path: str) -> None:
    """Make the private directory ``path`` (mode 0700) if it is missing, then check it is this user's alone.

    Raises
    ------
    BusError
        ``path`` exists but is not a directory, is a symbolic link, belongs to another user or
        can be read or written by others: someone else could have bound a channel there first.
    """
    try:
        os.mkdir(path, 0o700)
    except FileExistsError:
        pass
    except OSError as err:
        raise BusError(f"cannot make the private seqpacket directory {path!r}: {err}") from err
    problem = directory_problem(path, os.geteuid(), None, private=True)
    if problem:
        raise BusError(
            f"refusing the seqpacket directory {path!r}: {problem}; a stranger could sit on its channels. "
            "Remove it (a fresh one is made), or set XDG_RUNTIME_DIR to a directory only you can write"
        )


def check_directory(path: str, group_gid: int | None) -> None:
    """Check that the directory of a socket-path channel is safe to serve a channel in.

    Owned by this user or root, and not writable by other users; writable by its group only
    when that group is the one admitted (``group_gid``, ``can.peer_group``).

    Raises
    ------
    BusError
        Says which rule the directory breaks and how to fix it.
    """
    problem = directory_problem(path, os.geteuid(), group_gid, private=False)
    if problem:
        raise BusError(
            f"refusing seqpacket channel directory {path!r}: {problem}; another user could bind the channel first. "
            "Use a directory you own that only you (or can.peer_group's group) can write, or a plain channel name"
        )


def directory_problem(path: str, uid: int, group_gid: int | None, private: bool) -> str:
    """What makes ``path`` unsafe for channels of user ``uid``; "" when it is safe.

    ``private``: it must be ``uid``'s and closed to group and others (mode ``0700``);
    otherwise root may own it too, and its group may write it when that group is ``group_gid``.
    """
    try:
        info = os.lstat(path)
    except OSError as err:
        return f"it cannot be examined ({err.strerror})"
    if stat.S_ISLNK(info.st_mode):
        return "it is a symbolic link"
    if not stat.S_ISDIR(info.st_mode):
        return "it is not a directory"
    owners = (uid,) if private else (uid, 0)
    if info.st_uid not in owners:
        return f"it is owned by uid {info.st_uid}, not by you (uid {uid})"
    mode = stat.S_IMODE(info.st_mode)
    if private and mode & 0o077:
        return f"its mode is {mode:04o}; expected 0700 (only you may enter it)"
    if mode & stat.S_IWOTH:
        return f"its mode is {mode:04o}: every user can write it"
    if mode & stat.S_IWGRP and (group_gid is None or info.st_gid != group_gid):
        return f"its mode is {mode:04o}: group gid {info.st_gid} can write it, and that is not can.peer_group's group"
    return ""


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
