"""A sweep from start to end: the results folder, the cases still to run, the engine, the rows as they come.

:func:`open_folder` claims a results folder (one sweep writes it at a time: a lock file), checks
that it holds this study's results (or none) and saves the study file beside them;
:func:`plan` leaves out the cases already done (by key); :func:`run_sweep` feeds the rest to an
engine and appends each row as it arrives, and on the way out (finished, interrupted or
failed) writes what it has and compacts the parts into ``cases.parquet``.
"""

from __future__ import annotations

import fcntl
import platform
import shutil
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from harness.errors import ProfileError
from harness.recording import strict_json
from harness.sweep.cases import CaseSpec
from harness.sweep.engines import Engine
from harness.sweep.rows import FAILED, OUTCOME
from harness.sweep.store import ResultStore
from harness.sweep.study import Study, read_study_data
from harness.sweep.worker import CaseRunner

STUDY_COPY, METADATA, LOCK = "study.yaml", "sweep.json", ".lock"


@dataclass(frozen=True)
class Plan:
    """The cases of a study and those of them still to run."""

    cases: list[CaseSpec]
    todo: list[CaseSpec]

    @property
    def skipped(self) -> int:
        """Cases already in the results."""
        return len(self.cases) - len(self.todo)


@dataclass
class SweepTotals:
    """What a sweep did: cases run and failed, its wall time, the integrators' CPU time, whether Ctrl-C stopped it."""

    ran: int = 0
    failed: int = 0
    wall_time_s: float = 0.0
    integration_s: float = 0.0
    interrupted: bool = False


def refuse_other_study(folder: Path, study: Study) -> None:
    """Refuse a results folder that holds another study's results (its saved study file names another study).

    Raises
    ------
    ProfileError
        Naming both studies.
    """
    saved = folder / STUDY_COPY
    if not saved.is_file():
        return
    name = read_study_data(saved).get("name")
    if name != study.name:
        raise ProfileError(
            f"{folder} holds the results of study {name!r}; expected those of {study.name!r} or an empty folder "
            "(choose another --out)", study.source_path, "name",
        )


@contextmanager
def open_folder(folder: Path, study: Study) -> Iterator[ResultStore]:
    """Claim ``folder`` for ``study`` and give its store; the lock is released on the way out.

    Raises
    ------
    ProfileError
        If the folder holds another study's results, or another sweep is writing it.
    """
    folder.mkdir(parents=True, exist_ok=True)
    with (folder / LOCK).open("w") as lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError as err:
            raise ProfileError(f"another sweep is writing {folder}; expected one sweep per results folder",
                               study.source_path) from err
        refuse_other_study(folder, study)
        shutil.copyfile(study.source_path, folder / STUDY_COPY)
        yield ResultStore(folder)


def plan(cases: list[CaseSpec], store: ResultStore, retry_failed: bool = False) -> Plan:
    """Leave out the cases whose key is in the results (failed ones too, unless ``retry_failed``)."""
    outcomes = store.outcomes()
    done = {key for key, outcome in outcomes.items() if not (retry_failed and outcome == FAILED)}
    return Plan(cases, [case for case in cases if case.key not in done])


def run_sweep(
    todo: list[CaseSpec], engine: Engine, runner: CaseRunner, store: ResultStore,
    on_row: Callable[[dict[str, Any]], None] | None = None,
) -> SweepTotals:
    """Run ``todo`` on ``engine``, writing each row as it comes; compact the results at the end.

    Ctrl-C stops the sweep: the rows received so far are kept (``SweepTotals.interrupted``), and a
    rerun goes on from there.
    """
    totals, started = SweepTotals(), time.perf_counter()
    try:
        for row in engine.rows(runner, todo):
            store.append(row)
            totals.ran += 1
            totals.failed += row[OUTCOME] == FAILED
            totals.integration_s += float(row.get("integration_s") or 0.0)
            if on_row is not None:
                on_row(row)
    except KeyboardInterrupt:
        totals.interrupted = True
    finally:
        totals.wall_time_s = time.perf_counter() - started
        store.compact()
    return totals


def write_metadata(
    folder: Path, study: Study, engine: Engine, cases: Plan, totals: SweepTotals | None, started: datetime,
    report: dict[str, Any],
) -> Path:
    """``sweep.json``: the study, the engine, the counts and times of the last sweep into ``folder``.

    Written as the sweep starts (``totals`` None: ``ended`` is null) and again as it ends;
    ``report`` holds the report's settings (:class:`harness.sweep.report.ReportSettings`).
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        harness_version = version("shaketable-harness")
    except PackageNotFoundError:
        harness_version = "unknown"
    data = {
        "study": study.name, "study_file": study.source_path, "profile": str(study.profile_path()),
        "cases": len(cases.cases), "skipped_as_done": cases.skipped, "engine": engine.description,
        "workers": engine.workers, "started": started.isoformat(),
        "ended": None if totals is None else datetime.now(UTC).isoformat(),
        **({} if totals is None else asdict(totals)),
        "host": platform.node(), "python": platform.python_version(), "harness": harness_version,
        "storage": ResultStore(folder).format, "report": report,
    }
    path = folder / METADATA
    path.write_text(strict_json.dumps(data, indent=2) + "\n")
    return path
