"""Whole-array run folders for the offline simulator.

``harness simulate`` computes a passive and a controlled case at once. Each case is
written as a complete run folder of its own, ``DIR/<name>/`` (``DIR/passive/``,
``DIR/controlled/``), with ``kind: simulation`` and ``case: <name>`` in its metadata.
``DIR`` is then a *case set*: :func:`harness.recording.reader.load_runs` and the report
expand it; each case also loads alone with :func:`harness.recording.reader.load_run`.
Separate folders keep one format (one signals file = one run) for every reader,
including pandas and MATLAB users who open one CSV.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

import harness.recording.strict_json as strict_json
from harness.recording.layout import (
    EVENTS_FILE,
    FORMAT_NAME,
    FORMAT_VERSION,
    METADATA_FILE,
    PROFILE_FILE,
    SIGNALS_FILE,
    RunFolderError,
    check_columns,
    check_outcome,
)
from harness.recording.metadata import (
    environment,
    iso,
    plain_data,
    safe_name,
    utc_now,
    write_json_atomic,
    write_profile,
)
from harness.recording.writer import format_rows, row_format
from harness.signals.columns import TIME

_CHUNK_ROWS = 4096


def write_simulation_case(
    folder: Path | str,
    name: str,
    columns: Sequence[str],
    arrays: Mapping[str, np.ndarray] | np.ndarray,
    metadata: Mapping[str, Any],
    *,
    profile_data: Mapping[str, Any] | None = None,
    events: Iterable[Mapping[str, Any]] = (),
) -> Path:
    """Write one simulated case as the complete run folder ``folder/name/``.

    Parameters
    ----------
    folder : Path or str
        The case set folder (created if missing).
    name : str
        Case name, e.g. ``"passive"`` or ``"controlled"``; also stored as ``metadata["case"]``.
    columns : sequence of str
        Column names, ``t_s`` first (see :mod:`harness.signals.columns`).
    arrays : mapping of str to ndarray, or ndarray of shape (n, len(columns))
        The time histories (SI units), one equal-length 1-D array per column.
    metadata : mapping
        Extra metadata (``profile_name``, ``total_weight_N``, ``record``, ``controller`` ...);
        may set ``outcome`` (default ``"completed"``) and ``trip_reason``.
    profile_data : mapping, optional
        The resolved profile, written to ``profile.yaml`` (``{}`` if absent).
    events : iterable of mapping, optional
        Event records with keys ``t_s``, ``kind``, ``name``, ``detail``.

    Returns
    -------
    Path
        The case folder.

    Raises
    ------
    RunFolderError
        For bad column names, arrays that do not match them, or an existing case folder.
    """
    names = check_columns(list(columns))
    if names[0] != TIME:
        raise RunFolderError(f"found first column {names[0]!r}, expected {TIME!r}")
    table = _as_table(names, arrays)
    case_dir = Path(folder) / safe_name(name)
    case_dir.parent.mkdir(parents=True, exist_ok=True)
    try:
        case_dir.mkdir()
    except FileExistsError as err:
        raise RunFolderError("already exists, expected a new case folder", str(case_dir)) from err
    started = utc_now()
    write_profile(case_dir / PROFILE_FILE, profile_data or {})
    _write_signals(case_dir / SIGNALS_FILE, names, table)
    _write_events(case_dir / EVENTS_FILE, events)
    write_json_atomic(case_dir / METADATA_FILE, _case_metadata(name, names, table.shape[0], started, metadata))
    return case_dir


def _as_table(names: tuple[str, ...], arrays: Mapping[str, np.ndarray] | np.ndarray) -> np.ndarray:
    if isinstance(arrays, np.ndarray):
        table = np.asarray(arrays, dtype=float)
        if table.ndim != 2 or table.shape[1] != len(names):
            raise RunFolderError(f"found an array of shape {table.shape}, expected (n, {len(names)})")
        return table
    missing = [n for n in names if n not in arrays]
    extra = [n for n in arrays if n not in names]
    if missing or extra:
        raise RunFolderError(f"found arrays missing {missing} and extra {extra}, expected exactly the columns")
    lengths = {n: np.shape(arrays[n]) for n in names}
    shapes = set(lengths.values())
    if len(shapes) != 1 or len(next(iter(shapes))) != 1:
        raise RunFolderError(f"found array shapes {lengths}, expected 1-D arrays of one length")
    return np.column_stack([np.asarray(arrays[n], dtype=float) for n in names])


def _write_signals(path: Path, names: tuple[str, ...], table: np.ndarray) -> None:
    line = row_format(len(names))
    with open(path, "w", encoding="utf-8", newline="") as handle:
        handle.write(",".join(names) + "\n")
        for start in range(0, table.shape[0], _CHUNK_ROWS):
            handle.write(format_rows(line, table[start : start + _CHUNK_ROWS]))


def _write_events(path: Path, events: Iterable[Mapping[str, Any]]) -> None:
    with open(path, "w", encoding="utf-8", newline="") as handle:
        for event in events:
            record = {
                "t_s": event.get("t_s"),
                "wall_time": None,
                "kind": event.get("kind", "info"),
                "name": event.get("name", ""),
                "detail": event.get("detail"),
            }
            handle.write(strict_json.dumps(record, str) + "\n")


def _case_metadata(
    name: str, names: tuple[str, ...], n_rows: int, started: Any, extra: Mapping[str, Any]
) -> dict[str, Any]:
    data: dict[str, Any] = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "profile_name": extra.get("profile_name", "simulation"),
        "kind": "simulation",
        "case": name,
        "start_time": iso(started),
        "end_time": iso(utc_now()),
        "outcome": check_outcome(str(extra.get("outcome", "completed"))),
        "trip_reason": extra.get("trip_reason"),
        "columns": list(names),
        "files": {"profile": PROFILE_FILE, "signals": SIGNALS_FILE, "events": EVENTS_FILE, "can": None},
        "recorder": {"rows_written": n_rows, "dropped": {"rows": 0, "frames": 0, "events": 0}},
    }
    data.update(environment())
    reserved = {"format", "format_version", "kind", "case", "columns", "files", "start_time", "end_time"}
    clash = sorted(reserved & set(extra))
    if clash:
        raise RunFolderError(f"found reserved metadata keys {clash}, expected them to be set by the recorder")
    data.update(plain_data({k: v for k, v in extra.items() if k not in ("outcome", "trip_reason", "profile_name")}))
    return data
