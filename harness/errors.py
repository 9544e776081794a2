"""The harness's error tree.

Every error the harness raises on purpose derives from :class:`HarnessError` and
from the builtin that fits it, so callers can catch either. Messages say what was
expected and what was found.
"""

from __future__ import annotations


class HarnessError(Exception):
    """Base of every error the harness raises on purpose."""


class ProfileError(HarnessError, ValueError):
    """A profile file is unreadable, has an unknown key, a wrong type, unit or range.

    Parameters
    ----------
    message : str
        What was expected and what was found.
    source : str, optional
        The file the problem is in.
    key_path : str, optional
        Dotted path of the key, e.g. ``structure.floor_masses_kg[2]``.
    """

    def __init__(self, message: str, source: str | None = None, key_path: str | None = None):
        self.source = source
        self.key_path = key_path
        self.detail = message
        where = ""
        if source:
            where += f"{source}: "
        if key_path:
            where += f"{key_path}: "
        super().__init__(where + message)


class RecordError(HarnessError, ValueError):
    """A ground-motion record is missing, malformed, or exceeds the table's limits."""


class ModelError(HarnessError, ValueError):
    """A structural model or controller design is inconsistent (e.g. unstable surface)."""


class ProtocolError(HarnessError, ValueError):
    """A CAN frame or DBC does not match what the protocol expects."""


class BusError(HarnessError, OSError):
    """A CAN bus cannot be opened, used, or has failed."""


class BusLoadError(HarnessError, ValueError):
    """The configured messages and rates need more of the bitrate than allowed."""


class SafetyError(HarnessError, RuntimeError):
    """An illegal lifecycle transition or a refused arm."""


class TripError(SafetyError):
    """A run tripped; ``reason`` names the interlock or detector that fired."""

    def __init__(self, reason: str, message: str = ""):
        self.reason = reason
        super().__init__(f"tripped: {reason}" + (f": {message}" if message else ""))
