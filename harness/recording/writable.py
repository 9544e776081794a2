"""Whether a directory can take the folders a command writes (run folders, results), asked before anything starts.

Permission bits cannot answer it: root passes every ``access()`` test, yet ``/proc/1`` or
``/sys/kernel`` refuse any new entry, and a path below a regular file cannot exist at all.
:func:`directory_problem` therefore tries what the command will do: it creates a folder in
the directory (or, for a directory still to be made, in the nearest one that exists) and
removes it at once. Nothing is left behind, whatever the answer.

This module imports nothing heavy: the command line calls it while it parses its options.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

#: Prefix of the probe folder (removed at once; a crash in between leaves an empty folder of this name).
PROBE_PREFIX = ".harness-write-probe-"


def _nearest_existing(path: Path) -> Path:
    """``path`` or its nearest ancestor that exists (the root always does)."""
    for candidate in (path, *path.parents):
        if candidate.exists():
            return candidate
    return Path(path.anchor or ".")


def directory_problem(path: str | Path) -> str | None:
    """Why folders cannot be created in ``path`` (created first if missing), or None if they can.

    Parameters
    ----------
    path : str or Path
        The directory a command writes into.

    Returns
    -------
    str or None
        What is wrong and what was expected, e.g. ``"/proc/1: cannot create a folder there
        (No such file or directory), expected a writable directory"``; None when it is writable.
    """
    target = Path(path).expanduser().absolute()
    existing = _nearest_existing(target)
    if not existing.is_dir():
        where = "is a file" if existing == target else f"is below {existing}, which is a file"
        return f"{path} {where}, expected a directory (existing or to be created)"
    try:
        probe = tempfile.mkdtemp(prefix=PROBE_PREFIX, dir=existing)
    except OSError as err:
        inside = "" if existing == target else f" (in {existing}, the nearest folder that exists)"
        return f"{path}: cannot create a folder there{inside} ({err.strerror or err}), expected a writable directory"
    os.rmdir(probe)
    return None
