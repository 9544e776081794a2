"""The harness's error tree.

Every error the harness raises on purpose derives from :class:`HarnessError` and
from the builtin that fits it, so callers can catch either. Messages say what was
expected and what was found.

The CAN drivers have their own tree (:mod:`drivers.errors`: :class:`DriverError`,
:class:`ProtocolError`, :class:`BusError`, :class:`BusLoadError`), because the drivers
import nothing from the harness. This module re-exports those classes, so
``from harness.errors import BusError`` names the very class the drivers raise, and
:data:`EXPECTED_ERRORS` names both roots for the places that handle any expected
error (the command line's exit status 2, the tick's "bus gone").

Why a tuple and not one root: ``except`` matches on the real class hierarchy only
(``abc.ABCMeta.register`` makes ``isinstance`` true, but an ``except HarnessError``
clause still lets a registered class through), and a driver error cannot derive from
:class:`HarnessError` without the drivers importing the harness.
"""

from __future__ import annotations

from drivers.errors import BusError, BusLoadError, DriverError, ProtocolError

__all__ = [
    "EXPECTED_ERRORS", "BusError", "BusLoadError", "DriverError", "HarnessError", "ModelError", "ProfileError",
    "ProtocolError", "RecordError", "SafetyError", "StoppedByOperator",
]


class HarnessError(Exception):
    """Base of every error the harness raises on purpose (the drivers' errors excepted, see the module)."""


#: Every error raised on purpose, by the harness or by its CAN drivers: ``except EXPECTED_ERRORS``.
EXPECTED_ERRORS: tuple[type[Exception], ...] = (HarnessError, DriverError)


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


class SafetyError(HarnessError, RuntimeError):
    """An illegal lifecycle transition or a refused arm."""


class StoppedByOperator(KeyboardInterrupt):
    """The operator's Ctrl-C or SIGTERM, acted on at a safe point before the loop: nothing moved.

    A KeyboardInterrupt, so every ``except Exception`` lets it through and every cleanup runs as
    for Ctrl-C; the command line ends with exit status 4 and the outcome line
    (:mod:`harness.loop.operator`).

    Parameters
    ----------
    where : str
        What the command was doing when it stopped, e.g. ``"while starting the virtual rig"``.
    request : str
        ``Ctrl-C``, ``a second Ctrl-C`` or ``SIGTERM``.
    """

    def __init__(self, where: str, request: str = "Ctrl-C"):
        self.where = where
        self.request = request
        #: The run folder the stop was recorded in (marked ``stopped``), if one had been made.
        self.run_path: str | None = None
        super().__init__(f"stopped by the operator ({request}) before anything moved, {where}")
