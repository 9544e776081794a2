"""Read run folders back: :func:`load_run` for one folder, :func:`load_runs` for many.

A folder whose sub-folders are run folders (the offline simulator's
``DIR/passive/`` and ``DIR/controlled/``) is a *case set*: :func:`load_runs`
expands it into its runs, :func:`load_run` refuses it and names the cases.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from harness.recording.layout import (
    FORMAT_NAME,
    FORMAT_VERSION,
    METADATA_FILE,
    RunFolderError,
)
from harness.signals.columns import SIMULATED_CONTROL, count_stories


@dataclass(frozen=True)
class RunData:
    """Everything one run folder holds, in memory.

    Attributes
    ----------
    path : Path
        The run folder.
    metadata : dict
        ``metadata.json``.
    profile : dict
        ``profile.yaml`` (the resolved profile as plain data).
    columns : tuple of str
        Signal column names in file order.
    signals : dict of str to ndarray
        One float64 array per column, all the same length (SI units, see the names).
    events : list of dict
        ``events.jsonl`` records: ``t_s``, ``wall_time``, ``kind``, ``name``, ``detail``.
    can_log : Path or None
        The candump log, replayable with ``python -m can.player``.
    incomplete : bool
        True if the run did not finish cleanly (outcome ``"incomplete"``).
    warnings : tuple of str
        What was odd while reading (a torn last line, an incomplete run ...).
    """

    path: Path
    metadata: dict[str, Any]
    profile: dict[str, Any]
    columns: tuple[str, ...]
    signals: dict[str, np.ndarray]
    events: list[dict[str, Any]]
    can_log: Path | None
    incomplete: bool
    warnings: tuple[str, ...] = field(default=())

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.signals[name]
        except KeyError as err:
            raise KeyError(f"run {self.path.name} has no column {name!r}; it has {', '.join(self.columns)}") from err

    def has(self, *names: str) -> bool:
        """True if every named column is present."""
        return all(name in self.signals for name in names)

    @property
    def n_rows(self) -> int:
        """Number of recorded ticks."""
        return len(self.signals[self.columns[0]]) if self.columns else 0

    @property
    def n_stories(self) -> int:
        """Number of stories with a drift column."""
        return count_stories(self.columns)

    @property
    def kind(self) -> str:
        """``"run"``, ``"dry-run"`` or ``"simulation"``."""
        return str(self.metadata.get("kind", "?"))

    @property
    def outcome(self) -> str:
        """``completed``, ``tripped``, ``error`` or ``incomplete``."""
        return str(self.metadata.get("outcome", "incomplete"))

    @property
    def case(self) -> str | None:
        """Simulation case name (``"passive"``, ``"controlled"`` ...), if any."""
        case = self.metadata.get("case")
        return str(case) if case is not None else None

    @property
    def is_passive(self) -> bool:
        """True for a bearings-only run (case or controller ``"passive"``)."""
        return self.case == "passive" or self.metadata.get("controller") == "passive"

    @property
    def record_name(self) -> str | None:
        """Name of the ground-motion record, if the metadata says."""
        record = self.metadata.get("record")
        if isinstance(record, Mapping):
            name = record.get("name")
            return str(name) if name is not None else None
        return str(record) if isinstance(record, str) else None

    @property
    def label(self) -> str:
        """A short human label: ``metadata["label"]`` or profile, kind and case."""
        if self.metadata.get("label"):
            return str(self.metadata["label"])
        kind = "sim" if self.kind == "simulation" else self.kind
        parts = [str(self.metadata.get("profile_name", self.path.name)), kind]
        if self.case:
            parts.append(self.case)
        unique = [part for index, part in enumerate(parts) if part not in parts[:index]]
        return " ".join(unique)


def load_run(path: Path | str) -> RunData:
    """Read one run folder.

    Parameters
    ----------
    path : Path or str
        The run folder (the one holding ``metadata.json``).

    Returns
    -------
    RunData

    Raises
    ------
    RunFolderError
        If the folder is missing, is not a run folder (or is a set of cases), has an
        unknown format or version, or lacks a file its metadata lists.
    """
    folder = Path(path)
    if not folder.is_dir():
        found = "is a file" if folder.exists() else "no such folder"
        raise RunFolderError(f"{found}, expected a run folder", str(folder))
    meta_path = folder / METADATA_FILE
    if not meta_path.is_file():
        cases = case_folders(folder)
        if cases:
            names = ", ".join(p.name for p in cases)
            raise RunFolderError(
                f"is a set of run folders ({names}), expected one run folder; load_runs reads them all", str(folder)
            )
        raise RunFolderError(f"found no {METADATA_FILE}, expected a run folder written by the harness", str(folder))
    metadata = _read_metadata(meta_path)
    files = metadata["files"]
    profile = _read_profile(_required(folder, files, "profile"))
    columns, signals, notes = _read_signals(_required(folder, files, "signals"), metadata)
    events, event_notes = _read_events(_required(folder, files, "events"))
    can_log = _required(folder, files, "can") if files.get("can") else None
    incomplete = metadata.get("outcome", "incomplete") == "incomplete"
    if incomplete:
        notes.insert(
            0, f"run {folder.name} did not finish cleanly (outcome 'incomplete'); its data end at the last flush"
        )
    elif metadata.get("record_complete") is False:
        notes.insert(0, f"run {folder.name}: {record_loss_text(metadata)}")
    return RunData(folder, metadata, profile, columns, signals, events, can_log, incomplete, tuple(notes + event_notes))


def load_runs(paths: Iterable[Path | str]) -> list[RunData]:
    """Read run folders, expanding a set of cases (a folder of run folders) into its runs in name order."""
    runs: list[RunData] = []
    for item in paths:
        folder = Path(item)
        if folder.is_dir() and not (folder / METADATA_FILE).is_file() and case_folders(folder):
            runs.extend(load_run(case) for case in case_folders(folder))
        else:
            runs.append(load_run(folder))
    return runs


def case_folders(folder: Path) -> list[Path]:
    """Sub-folders of ``folder`` that hold a ``metadata.json``: ``passive`` first, then by name."""
    if not folder.is_dir():
        return []
    found = [p for p in folder.iterdir() if p.is_dir() and (p / METADATA_FILE).is_file()]
    return sorted(found, key=lambda p: (p.name != "passive", p.name))


def _read_metadata(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise RunFolderError(f"cannot read it as JSON ({err}), expected run metadata", str(path)) from err
    if not isinstance(data, dict) or data.get("format") != FORMAT_NAME:
        found = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise RunFolderError(f"found format {found!r}, expected {FORMAT_NAME!r}: not a harness run folder", str(path))
    version = data.get("format_version")
    if version != FORMAT_VERSION:
        raise RunFolderError(
            f"found format_version {version!r}, expected {FORMAT_VERSION}; this harness cannot read that run folder "
            "format (use the harness version that wrote it)",
            str(path),
        )
    if not isinstance(data.get("files"), dict) or not isinstance(data.get("columns"), list):
        raise RunFolderError("found no 'files' or 'columns' entry, expected both", str(path))
    return data


def _required(folder: Path, files: Mapping[str, Any], key: str) -> Path:
    name = files.get(key)
    if not isinstance(name, str):
        raise RunFolderError(f"metadata lists no {key} file, expected a file name", str(folder))
    path = folder / name
    if not path.is_file():
        raise RunFolderError(f"missing {name} (the {key} file its metadata lists)", str(folder))
    return path


def _read_profile(path: Path) -> dict[str, Any]:
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        raise RunFolderError(f"cannot read it as YAML ({err})", str(path)) from err
    return data if isinstance(data, dict) else {}


def record_loss_text(metadata: Mapping[str, Any]) -> str:
    """One sentence on what a run's recorder lost, from ``metadata.json`` (``record_complete`` false)."""
    found = metadata.get("recorder")
    recorder: Mapping[str, Any] = found if isinstance(found, Mapping) else {}
    found = recorder.get("lost")
    lost: Mapping[str, Any] = found if isinstance(found, Mapping) else {}
    counts = ", ".join(f"{lost[key]} {key}" for key in ("rows", "frames", "events") if lost.get(key))
    error = recorder.get("error")
    return (
        "the record is incomplete"
        + (f": {counts} lost" if counts else "")
        + (f" ({error})" if error else "")
        + f"; of its rows, the first {recorder.get('rows_written', '?')} were confirmed written"
    )


def _read_text(path: Path, what: str) -> str:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError as err:
        raise RunFolderError(
            f"byte 0x{err.object[err.start]:02x} at offset {err.start} is not UTF-8 text, expected {what} "
            "written by the harness (is the file damaged?)", str(path),
        ) from err
    except OSError as err:
        raise RunFolderError(f"cannot read it ({err.strerror or err}), expected {what}", str(path)) from err


def _read_signals(path: Path, metadata: Mapping[str, Any]) -> tuple[tuple[str, ...], dict[str, np.ndarray], list[str]]:
    text = _read_text(path, "CSV text")
    lines = text.split("\n")
    header = tuple(lines[0].strip().split(",")) if lines[0].strip() else ()
    expected = tuple(metadata["columns"])
    if header != expected:
        shown = lines[0].strip()
        shown = repr(shown if len(shown) <= 120 else shown[:117] + "...")
        raise RunFolderError(
            f"found header {shown} on line 1, expected the columns in metadata.json {','.join(expected)!r}", str(path)
        )
    notes: list[str] = []
    body = lines[1:]
    if body and body[-1] != "":
        notes.append(f"{path.name}: dropped a torn last line {len(lines)} (the run stopped while writing it)")
    numbered = [(number, line) for number, line in enumerate(body[:-1], start=2) if line]
    width = len(header)
    table = np.empty((0, width))
    if numbered:
        try:
            table = np.loadtxt([line for _, line in numbered], delimiter=",", ndmin=2, dtype=float)
        except ValueError as err:
            raise RunFolderError(_bad_row(numbered, width), str(path)) from err
    if table.shape[1] != width:
        raise RunFolderError(f"found {table.shape[1]} values per line, expected {width} (the header's columns)", str(path))
    _check_row_count(path, metadata, len(numbered))
    signals = {name: np.ascontiguousarray(table[:, i]) for i, name in enumerate(header)}
    notes.extend(_non_finite_notes(path, signals, [number for number, _ in numbered]))
    return header, signals, notes


def _non_finite_notes(path: Path, signals: Mapping[str, np.ndarray], line_numbers: list[int]) -> list[str]:
    """One note naming the rows and columns of ``path`` holding NaN or Inf, if any (logs/README.md: "not measured").

    The one place they belong is left out: a simulated case's controller internals in its last
    row, where the controller took no sample (:func:`harness.runs.simulate_output.unsampled_end`).
    """
    rows: set[int] = set()
    columns = []
    for column, values in signals.items():
        bad = ~np.isfinite(values)
        if column in SIMULATED_CONTROL and len(bad):
            bad[-1] = False
        if bad.any():
            columns.append(column)
            rows.update(np.flatnonzero(bad).tolist())
    if not columns:
        return []
    lines = sorted(line_numbers[row] for row in rows)
    shown = ", ".join(str(line) for line in lines[:5]) + (", ..." if len(lines) > 5 else "")
    listed = ", ".join(columns[:6]) + (f" and {len(columns) - 6} more" if len(columns) > 6 else "")
    return [f"run {path.parent.name}: {len(lines)} row(s) of {path.name} hold NaN or Inf (line {shown}) in {listed}: "
            "no measurement there (an identification refuses such a row)"]


def _bad_row(numbered: list[tuple[int, str]], width: int) -> str:
    """The first line that is not ``width`` numbers, for the message."""
    for number, line in numbered:
        fields = line.split(",")
        try:
            [float(field) for field in fields]
        except ValueError:
            return f"line {number}: found {line[:80]!r}, expected {width} comma-separated numbers"
        if len(fields) != width:
            return f"line {number}: found {len(fields)} values, expected {width} comma-separated numbers"
    return f"cannot parse the rows, expected {width} comma-separated numbers per line"


def _check_row_count(path: Path, metadata: Mapping[str, Any], rows: int) -> None:
    """Refuse a finished run whose file holds fewer rows than its recorder confirmed writing (cut after the run)."""
    recorder = metadata.get("recorder")
    written = recorder.get("rows_written") if isinstance(recorder, Mapping) else None
    if metadata.get("outcome", "incomplete") == "incomplete" or not isinstance(written, int) or rows >= written:
        return
    raise RunFolderError(
        f"holds {rows} rows (lines 2 to {rows + 1}), but metadata.json says the recorder wrote {written}: "
        f"rows {rows + 1} to {written} (lines {rows + 2} to {written + 1}) are missing, so the file was cut or "
        "damaged after the run; expected the whole file (restore it from a copy)", str(path),
    )


def _read_events(path: Path) -> tuple[list[dict[str, Any]], list[str]]:
    events: list[dict[str, Any]] = []
    notes: list[str] = []
    for number, line in enumerate(_read_text(path, "JSON lines").splitlines(), start=1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            notes.append(f"{path.name}: skipped unreadable line {number}")
            continue
        if isinstance(record, dict):
            events.append(record)
    return events, notes
