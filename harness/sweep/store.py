"""The results of a sweep on disk: one row per case, written as cases finish, read back to resume.

Layout of a results folder::

    cases.parquet          every row so far (after a sweep ends: compacted from the parts)
    parts/part-NNNNNN.parquet   rows written while the sweep runs, a part every 64 rows or 10 s
    cases.csv              the same rows as CSV (export, written when a sweep ends)
    study.yaml, sweep.json the study as given and what ran it (harness.sweep.driver)

Parquet through pyarrow (``pip install pyarrow``, or the ``sweep`` extra). Each part is written
whole to a temporary name and renamed, so a sweep that is killed loses at most the rows not
yet flushed, and never leaves a half-written file behind. Without pyarrow the parts and the
compacted file are CSV (``cases.csv`` only) and :attr:`ResultStore.format` says so.

Reading merges ``cases.parquet`` and the parts; a case that appears twice (a failed case run
again with ``--retry-failed``) keeps its latest row.
"""

from __future__ import annotations

import csv
import math
import os
import time
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from harness.sweep.rows import ERROR, OUTCOME, WORKER

CASES_PARQUET, CASES_CSV, PARTS = "cases.parquet", "cases.csv", "parts"
#: Rows buffered before a part is written, and the longest a row waits (s).
FLUSH_ROWS, FLUSH_S = 64, 10.0


def have_pyarrow() -> bool:
    """True if pyarrow can be imported (Parquet); else results are CSV."""
    try:
        import pyarrow  # noqa: F401
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        return False
    return True


def _replace_atomically(write, path: Path) -> None:
    """Call ``write(tmp_path)`` and rename the result to ``path``."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    write(tmp)
    os.replace(tmp, path)


class ResultStore:
    """Rows of one results folder.

    Parameters
    ----------
    folder : Path
        Created if missing.
    parquet : bool, optional
        Write Parquet (default: when pyarrow is installed); False writes CSV.
    """

    def __init__(self, folder: str | Path, parquet: bool | None = None):
        self.folder = Path(folder)
        self.parts = self.folder / PARTS
        self.parts.mkdir(parents=True, exist_ok=True)
        self.parquet = have_pyarrow() if parquet is None else parquet
        self.format = "parquet" if self.parquet else "csv"
        self._buffer: list[dict[str, Any]] = []
        self._flushed_at = time.monotonic()
        self._sequence = self._next_sequence()

    @property
    def suffix(self) -> str:
        return ".parquet" if self.parquet else ".csv"

    def _next_sequence(self) -> int:
        numbers = [int(p.stem.split("-")[1]) for p in self.parts.glob("part-*.*") if p.stem.split("-")[1].isdigit()]
        return max(numbers, default=-1) + 1

    def append(self, row: dict[str, Any]) -> None:
        """Add a row; a part is written every :data:`FLUSH_ROWS` rows or :data:`FLUSH_S` seconds."""
        self._buffer.append(row)
        if len(self._buffer) >= FLUSH_ROWS or time.monotonic() - self._flushed_at >= FLUSH_S:
            self.flush()

    def flush(self) -> None:
        """Write the buffered rows as one part."""
        self._flushed_at = time.monotonic()
        if not self._buffer:
            return
        path = self.parts / f"part-{self._sequence:06d}{self.suffix}"
        rows, self._buffer = self._buffer, []
        _replace_atomically(lambda tmp: self._write(rows, tmp), path)
        self._sequence += 1

    def _write(self, rows: list[dict[str, Any]], path: Path) -> None:
        if self.parquet:
            import pyarrow as pa
            import pyarrow.parquet as pq

            pq.write_table(pa.Table.from_pylist(rows), path)
        else:
            write_csv(rows, path)

    def _files(self) -> list[Path]:
        """The compacted file (if any), then the parts in the order they were written."""
        main = self.folder / (CASES_PARQUET if self.parquet else CASES_CSV)
        return ([main] if main.is_file() else []) + sorted(self.parts.glob(f"part-*{self.suffix}"))

    def rows(self) -> list[dict[str, Any]]:
        """Every row, one per case (the latest where a case appears twice), in case order."""
        if self.parquet:
            return self.table().to_pylist()
        latest: dict[str, dict[str, Any]] = {}
        for path in self._files():
            for row in read_csv_rows(path):
                latest[str(row["case_id"])] = row
        return sorted(latest.values(), key=lambda row: int(row.get("case_index") or 0))

    def table(self) -> Any:
        """Every row as one ``pyarrow.Table`` (Parquet only), deduplicated and in case order."""
        import pyarrow as pa
        import pyarrow.parquet as pq

        files = self._files()
        if not files:
            return pa.table({})
        table = pa.concat_tables([pq.read_table(path) for path in files], promote_options="permissive")
        ids = np.asarray(table.column("case_id").to_pylist(), dtype=object)
        _, last_reversed = np.unique(ids[::-1], return_index=True)
        keep = np.sort(len(ids) - 1 - last_reversed)
        return table.take(keep).sort_by("case_index")

    def columns(self) -> dict[str, np.ndarray]:
        """Every column of :meth:`rows`: floats for numbers (NaN where missing), objects for text."""
        if self.parquet:
            table = self.table()
            return {name: _array(table.column(name).to_pylist()) for name in table.column_names}
        rows = self.rows()
        return {name: _array([row.get(name) for row in rows]) for name in header(rows)}

    def outcomes(self) -> dict[str, str]:
        """Case key -> outcome of every case in the folder."""
        if not self.parquet:
            return {str(row["case_id"]): str(row[OUTCOME]) for row in self.rows()}
        import pyarrow.parquet as pq

        found: dict[str, str] = {}
        for path in self._files():
            table = pq.read_table(path, columns=["case_id", OUTCOME])
            found.update(zip(table.column("case_id").to_pylist(), table.column(OUTCOME).to_pylist(), strict=True))
        return found

    def compact(self) -> Path:
        """Merge everything into ``cases.parquet`` (or ``cases.csv``), remove the parts, and export ``cases.csv``."""
        self.flush()
        main = self.folder / (CASES_PARQUET if self.parquet else CASES_CSV)
        parts = [path for path in self._files() if path != main]
        if self.parquet:
            import pyarrow.csv as pcsv
            import pyarrow.parquet as pq

            table = self.table()
            _replace_atomically(lambda tmp: pq.write_table(table, tmp), main)
            _replace_atomically(lambda tmp: pcsv.write_csv(table, tmp), self.folder / CASES_CSV)
        else:
            rows = self.rows()
            _replace_atomically(lambda tmp: write_csv(rows, tmp), main)
        for part in parts:
            part.unlink()
        return main


def _array(values: list[Any]) -> np.ndarray:
    """Floats if every value is a number or missing, else objects (text)."""
    if all(value is None or (isinstance(value, (int, float)) and not isinstance(value, bool)) for value in values):
        return np.array([np.nan if value is None else float(value) for value in values], dtype=float)
    return np.array(["" if value is None else value for value in values], dtype=object)


def header(rows: Iterable[Mapping[str, Any]]) -> list[str]:
    """Every column name of ``rows``, in the order first seen."""
    names: dict[str, None] = {}
    for row in rows:
        names.update(dict.fromkeys(row))
    return list(names)


def _csv_value(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Inf" if value > 0 else "-Inf")
    return "" if value is None else value


def write_csv(rows: list[dict[str, Any]], path: Path) -> None:
    """Rows as CSV: one header line, ``NaN`` for a missing number, as run folders write them."""
    with path.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=header(rows), restval="")
        writer.writeheader()
        for row in rows:
            writer.writerow({key: _csv_value(value) for key, value in row.items()})


#: Columns that hold text even when a value looks like a number (a key of only digits).
TEXT_COLUMNS = frozenset({"case_id", "record", "controller", OUTCOME, ERROR, WORKER})


def _parse(text: str) -> Any:
    if text == "":
        return None
    try:
        number = float(text)
    except ValueError:
        return text
    return int(text) if text.lstrip("-").isdigit() else number


def read_csv_rows(path: Path) -> list[dict[str, Any]]:
    """Rows of a CSV written by :func:`write_csv`, numbers parsed back."""
    with path.open(newline="") as handle:
        return [
            {key: value if key in TEXT_COLUMNS else _parse(value) for key, value in row.items()}
            for row in csv.DictReader(handle)
        ]
