"""Run metadata: software versions, git commit, host, times; written atomically.

``metadata.json`` is written when a run starts (outcome ``"incomplete"``) and
rewritten at the end through a temporary file and :func:`os.replace`, so a reader
sees either the old or the new file, never a half-written one.
"""

from __future__ import annotations

import datetime as _dt
import importlib.metadata
import os
import platform
import re
import socket
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

import harness.recording.strict_json as strict_json
from harness.recording.layout import RunFolderError

#: Distributions whose versions every run records.
PACKAGES: tuple[str, ...] = ("shaketable-harness", "numpy", "scipy", "python-can", "cantools", "numba")

GIT_TIMEOUT_S = 2.0

_UNSAFE = re.compile(r"[^A-Za-z0-9_.-]+")


def package_versions(names: tuple[str, ...] = PACKAGES) -> dict[str, str | None]:
    """Installed version of each distribution (``None`` when it is not installed)."""
    versions: dict[str, str | None] = {}
    for name in names:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = None
    return versions


def git_commit(cwd: Path | None = None, timeout_s: float = GIT_TIMEOUT_S) -> str | None:
    """``git rev-parse HEAD`` of the source tree, or ``None`` if there is no git, repo or answer in time.

    Parameters
    ----------
    cwd : Path, optional
        Where to ask; defaults to the folder holding this package.
    timeout_s : float
        Seconds to wait for git (s).
    """
    where = cwd if cwd is not None else Path(__file__).resolve().parent
    try:
        done = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=where, capture_output=True, text=True, timeout=timeout_s, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return None
    commit = done.stdout.strip()
    return commit if done.returncode == 0 and commit else None


def git_dirty(cwd: Path | None = None, timeout_s: float = GIT_TIMEOUT_S) -> bool | None:
    """True if tracked files differ from the commit (``git status --porcelain``), None if unknown."""
    where = cwd if cwd is not None else Path(__file__).resolve().parent
    try:
        done = subprocess.run(
            ["git", "status", "--porcelain", "--untracked-files=no"],
            cwd=where,
            capture_output=True,
            text=True,
            timeout=timeout_s,
            check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return None
    return bool(done.stdout.strip()) if done.returncode == 0 else None


def utc_now() -> _dt.datetime:
    """The current time, timezone-aware UTC."""
    return _dt.datetime.now(_dt.UTC)


def iso(moment: _dt.datetime) -> str:
    """ISO 8601 text of ``moment`` with microseconds."""
    return moment.isoformat(timespec="microseconds")


def environment() -> dict[str, Any]:
    """Host, Python and package versions, git commit and whether the tree was modified, for ``metadata.json``."""
    commit = git_commit()
    return {
        "host": socket.gethostname(),
        "platform": platform.platform(),
        "python": sys.version.split()[0],
        "python_implementation": platform.python_implementation(),
        "packages": package_versions(),
        "git_commit": commit,
        "git_dirty": git_dirty() if commit else None,
    }


def write_json_atomic(path: Path, data: Mapping[str, Any]) -> None:
    """Write ``data`` as JSON to ``path`` via a temporary file, fsync and :func:`os.replace`.

    Parameters
    ----------
    path : Path
        Final file name.
    data : mapping
        JSON-serialisable data (:func:`json_default` converts numpy values, paths and times);
        a non-finite float is written ``null`` (:mod:`harness.recording.strict_json`).

    Raises
    ------
    OSError
        If the file cannot be written; ``path`` then keeps its previous content.
    """
    temporary = path.with_name(f".{path.name}.tmp")
    text = strict_json.dumps(data, json_default, indent=2, sort_keys=False)
    try:
        with open(temporary, "w", encoding="utf-8") as handle:
            handle.write(text + "\n")
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    except OSError:  # disk full, file-size limit: keep the old file whole and leave no half-written one
        temporary.unlink(missing_ok=True)
        raise
    _fsync_dir(path.parent)



def write_json_in_place(path: Path, data: Mapping[str, Any]) -> bool:
    """Overwrite ``path`` with ``data`` in the blocks it already holds, when they are enough (a full disk's last resort).

    A disk too full for :func:`write_json_atomic`'s temporary file can still take a rewrite that
    needs no new block. Nothing is written when the text would need more room than the file's
    blocks (the file then keeps its previous content, rather than a half-written one).

    Returns
    -------
    bool
        True if written and flushed to the disk.
    """
    text = (strict_json.dumps(data, json_default, indent=2, sort_keys=False) + "\n").encode("utf-8")
    try:
        allocated = os.stat(path).st_blocks * 512
        if len(text) > allocated:
            return False
        with open(path, "r+b") as handle:
            handle.write(text)
            handle.truncate()
            handle.flush()
            os.fsync(handle.fileno())
    except OSError:
        return False
    return True

def _fsync_dir(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def json_default(value: Any) -> Any:
    """Make numpy scalars, arrays, paths and datetimes JSON-friendly."""
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, (Path, _dt.datetime)):
        return str(value) if isinstance(value, Path) else iso(value)
    if isinstance(value, (set, frozenset, tuple)):
        return list(value)
    raise TypeError(f"found {type(value).__name__} in metadata, expected JSON data (numbers, strings, lists, mappings)")


def safe_name(text: str) -> str:
    """``text`` with every run of characters other than letters, digits, ``_.-`` replaced by ``-``."""
    cleaned = _UNSAFE.sub("-", text).strip("-.")
    return cleaned or "unnamed"


def write_profile(path: Path, data: Mapping[str, Any]) -> None:
    """Write the resolved profile ``data`` to ``path`` as YAML (key order kept)."""
    try:
        text = yaml.safe_dump(plain_data(data), sort_keys=False, allow_unicode=True)
    except yaml.YAMLError as err:
        raise RunFolderError(f"the resolved profile is not plain data: {err}", str(path)) from err
    path.write_text(text, encoding="utf-8")


def plain_data(value: Any) -> Any:
    """Turn tuples, read-only mappings and numpy scalars into YAML-safe data."""
    if isinstance(value, Mapping):
        return {str(k): plain_data(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain_data(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    return value
