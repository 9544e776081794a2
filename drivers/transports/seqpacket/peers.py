"""Who may join a ``seqpacket`` channel: the peer's kernel credentials, checked on every connection.

Each end of a Unix socket can ask the kernel who is at the other end (``SO_PEERCRED``: the
process id, user id and group id the other side had when it connected or listened). These
cannot be forged by the peer. A :class:`PeerPolicy` admits a peer that runs as the same user,
or as a member of a group the profile names (``can.peer_group``), and, when the caller knows
exactly which process must be at the other end (a dry run and the rig process it started),
only that process. The hub checks every connection it accepts; a node checks the hub it
connected to. Both ends therefore refuse a stranger, whether it joins or sits on the channel
first (docs/SAFETY.md, "Threat model").

The group's members are resolved once, when the bus opens, so a check during a loop tick is
a set lookup.
"""

from __future__ import annotations

import grp
import os
import pwd
import socket
import struct
from collections.abc import Collection
from dataclasses import dataclass, field

from drivers.errors import BusError

#: ``struct ucred`` of ``SO_PEERCRED``: pid, uid, gid (three C ints).
_UCRED = struct.Struct("3i")


@dataclass(frozen=True)
class PeerCredentials:
    """The kernel's word on the process at the other end of a Unix socket."""

    pid: int
    uid: int
    gid: int

    def describe(self) -> str:
        """``process 1234 (user 'x' uid 1000, gid 1000)``, for messages."""
        try:
            name = f"user {pwd.getpwuid(self.uid).pw_name!r} "
        except KeyError:
            name = "user "
        return f"process {self.pid} ({name}uid {self.uid}, gid {self.gid})"


def peer_credentials(sock: socket.socket) -> PeerCredentials:
    """The credentials of the process at the other end of the connected Unix socket ``sock``."""
    pid, uid, gid = _UCRED.unpack(sock.getsockopt(socket.SOL_SOCKET, socket.SO_PEERCRED, _UCRED.size))
    return PeerCredentials(pid, uid, gid)


def resolve_group(group: str | int | None) -> tuple[int | None, frozenset[int]]:
    """The gid of ``group`` (a name or a number) and the uids of its listed members; (None, {}) for none.

    Raises
    ------
    BusError
        No such group on this host.
    """
    if group is None or group == "":
        return None, frozenset()
    try:
        entry = grp.getgrgid(int(group)) if isinstance(group, int) or str(group).isdigit() else grp.getgrnam(str(group))
    except KeyError:
        raise BusError(
            f"seqpacket peer group {group!r} does not exist on this host; expected a group name from /etc/group "
            "(can.peer_group), or nothing to admit only this user"
        ) from None
    uids = set()
    for member in entry.gr_mem:
        try:
            uids.add(pwd.getpwnam(member).pw_uid)
        except KeyError:
            continue
    return entry.gr_gid, frozenset(uids)


@dataclass(frozen=True)
class PeerPolicy:
    """Which peers a node admits.

    Attributes
    ----------
    uid : int
        This process's effective user id: a peer running as it is admitted.
    group_gid : int or None
        A group whose members are admitted too (primary group ``gid`` or a listed member).
    member_uids : frozenset of int
        The users listed as members of that group.
    pids : frozenset of int
        When not empty, the only processes admitted (a dry run and the rig process it started).
    """

    uid: int = field(default_factory=os.geteuid)
    group_gid: int | None = None
    member_uids: frozenset[int] = frozenset()
    pids: frozenset[int] = frozenset()

    @classmethod
    def make(cls, group: str | int | None = None, pids: Collection[int] | None = None) -> PeerPolicy:
        """The policy of this process: its user, ``group`` (name or gid; resolved now), and ``pids`` if given."""
        gid, members = resolve_group(group)
        return cls(os.geteuid(), gid, members, frozenset(int(p) for p in pids or ()))

    def admits(self, peer: PeerCredentials) -> bool:
        """Whether ``peer`` is admitted: set lookups only, no user-name lookup (safe inside a loop tick)."""
        if self.pids and peer.pid not in self.pids:
            return False
        return peer.uid == self.uid or (
            self.group_gid is not None and (peer.gid == self.group_gid or peer.uid in self.member_uids)
        )

    def refusal(self, peer: PeerCredentials) -> str:
        """Why ``peer`` is refused; "" when it is admitted. Looks the user's name up (outside a tick)."""
        if self.admits(peer):
            return ""
        if self.pids and peer.pid not in self.pids:
            expected = ", ".join(str(p) for p in sorted(self.pids))
            return f"{peer.describe()} is not the process this bus expects (pid {expected})"
        allowed = f"uid {self.uid}" + ("" if self.group_gid is None else f" or a member of group gid {self.group_gid}")
        return f"{peer.describe()} is another user; only {allowed} may join (can.peer_group names a group to admit)"

    def check(self, sock: socket.socket) -> str:
        """Why the peer at the other end of ``sock`` is refused; "" when it is admitted."""
        return describe_refusal(self, self.screen(sock))

    def screen(self, sock: socket.socket) -> PeerCredentials | OSError | None:
        """The refused peer at the other end of ``sock`` (or why its credentials cannot be read); None if admitted.

        One ``getsockopt`` and set lookups: no name lookup and no text, so the hub can screen a
        connection inside a loop tick and describe it later with :func:`describe_refusal`.
        """
        try:
            peer = peer_credentials(sock)
        except OSError as err:
            return err
        return None if self.admits(peer) else peer


def describe_refusal(policy: PeerPolicy, refused: PeerCredentials | OSError | None) -> str:
    """Why a peer :meth:`PeerPolicy.screen` returned was refused; "" for None (admitted)."""
    if refused is None:
        return ""
    if isinstance(refused, OSError):
        return f"its credentials cannot be read ({refused})"
    return policy.refusal(refused)
