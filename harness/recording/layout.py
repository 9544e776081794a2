"""What a run folder holds: file names, format version, outcomes, and its error.

A run folder (one per run, under ``logs/``) contains:

``metadata.json``
    Who, what, when and how it ended (see :mod:`harness.recording.metadata`). Holds
    ``"format": "shaketable-harness-run"`` and ``"format_version"``; a reader refuses
    any other format or version instead of guessing.
``profile.yaml``
    The fully resolved profile the run used (plain data, SI values).
``signals.csv``
    One row per loop tick; a one-line header of column names whose suffix names the
    unit (``t_s``, ``drift_1_m``, ``force_command_N``). :mod:`harness.signals.columns` defines
    the names and the order each kind of run writes them in.
``events.jsonl``
    One JSON object per line: ``{"t_s", "wall_time", "kind", "name", "detail"}``.
``can.log``
    Raw CAN traffic, candump ``-L`` format (:class:`can.CanutilsLogWriter`); only for
    runs that had a bus (``metadata["files"]["can"]`` is ``null`` otherwise).
``ticks.bin``
    The loop's tick record, what ``harness replay`` needs to run the ticks again
    (:mod:`harness.loop.tick_log`): per tick ``len(metadata["tick_columns"])`` little-endian
    float64 values, exact; only for runs of the control loop recorded since replay exists.
"""

from __future__ import annotations

import re
from typing import Final, Literal, cast, get_args

from harness.errors import HarnessError

FORMAT_NAME: Final = "shaketable-harness-run"
FORMAT_VERSION: Final = 1

METADATA_FILE: Final = "metadata.json"
PROFILE_FILE: Final = "profile.yaml"
SIGNALS_FILE: Final = "signals.csv"
EVENTS_FILE: Final = "events.jsonl"
CAN_FILE: Final = "can.log"
TICKS_FILE: Final = "ticks.bin"

#: What produced a run folder.
RunKind = Literal["dry-run", "run", "simulation"]
#: How a run ended: ``stopped`` by the operator (safe stop), ``refused`` before arming by the
#: pre-flight check, ``incomplete`` while it is still being written or after a crash.
Outcome = Literal["completed", "stopped", "tripped", "refused", "error", "incomplete"]

RUN_KINDS: Final[tuple[str, ...]] = get_args(RunKind)
OUTCOMES: Final[tuple[str, ...]] = get_args(Outcome)

#: A column name MATLAB keeps as-is (valid identifier, at most namelengthmax = 63 chars).
_COLUMN_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]{0,62}$")


class RunFolderError(HarnessError, ValueError):
    """A run folder is missing files, has an unknown format version, or is not a run folder.

    Parameters
    ----------
    message : str
        What was expected and what was found.
    path : str, optional
        The folder or file concerned.
    """

    def __init__(self, message: str, path: str | None = None):
        self.path = path
        super().__init__(f"{path}: {message}" if path else message)


def check_columns(columns: tuple[str, ...] | list[str]) -> tuple[str, ...]:
    """Validate column names for the signals file.

    Parameters
    ----------
    columns : sequence of str
        Column names, the first of which should be ``t_s``.

    Returns
    -------
    tuple of str
        The same names.

    Raises
    ------
    RunFolderError
        If there are none, a name is duplicated, or a name is not a plain identifier of
        at most 63 characters (so pandas and MATLAB ``readtable`` keep it unchanged).
    """
    names = tuple(columns)
    if not names:
        raise RunFolderError("found no columns, expected at least 't_s'")
    for name in names:
        if not isinstance(name, str) or not _COLUMN_NAME.match(name):
            raise RunFolderError(
                f"found column name {name!r}, expected letters, digits and '_' starting with a letter, "
                "at most 63 characters (a MATLAB identifier)"
            )
    seen: set[str] = set()
    for name in names:
        if name in seen:
            raise RunFolderError(f"found column {name!r} twice, expected unique names")
        seen.add(name)
    return names


def check_kind(kind: str) -> RunKind:
    """Return ``kind`` if it is a known run kind; raise RunFolderError otherwise."""
    if kind not in RUN_KINDS:
        raise RunFolderError(f"found run kind {kind!r}, expected one of {', '.join(RUN_KINDS)}")
    return cast(RunKind, kind)


def check_outcome(outcome: str) -> Outcome:
    """Return ``outcome`` if it is a known outcome; raise RunFolderError otherwise."""
    if outcome not in OUTCOMES:
        raise RunFolderError(f"found outcome {outcome!r}, expected one of {', '.join(OUTCOMES)}")
    return cast(Outcome, outcome)
