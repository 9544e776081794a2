"""``harness simulate --record a,b --controller X,Y``: one study per record and controller, and their summary.

Each combination is an ordinary study (:func:`harness.runs.simulate.run_study`: the passive
case and the controlled one). With an output folder, each is written as its own case set
``DIR/<record>_<controller>/`` (``passive/``, ``controlled/``), and the summary tables
(:mod:`harness.report.batch_summary`) as ``DIR/summary_peaks.csv``,
``DIR/summary_reduction.csv`` and ``DIR/summary.txt``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from harness.profile import Profile
from harness.recording.metadata import safe_name
from harness.report.batch_summary import BatchCase, batch_tables
from harness.report.peak_table import PeakTable
from harness.runs.options import StudyOptions
from harness.runs.simulate import StudyResult, run_study
from harness.runs.simulate_output import write_study_folders

SUMMARY_FILES = ("summary_peaks.csv", "summary_reduction.csv")


def split_list(text: str | None) -> list[str | None]:
    """``"a,b, c"`` -> ``["a", "b", "c"]``; None -> ``[None]`` (the profile's own choice)."""
    if text is None:
        return [None]
    items = [item.strip() for item in text.split(",")]
    return [item for item in items if item] or [None]


@dataclass
class BatchStudy:
    """Every combination's study, in order (records outer, controllers inner), and where they were written."""

    studies: list[StudyResult] = field(default_factory=list)
    folders: list[Path] = field(default_factory=list)
    tables: list[PeakTable] = field(default_factory=list)

    def cases(self) -> list[BatchCase]:
        """The peaks of each combination with a controlled case."""
        return [BatchCase(record_name(study), study.controller_name, study.cases["passive"].peaks,
                          study.cases["controlled"].peaks)
                for study in self.studies if "controlled" in study.cases]


def record_name(study: StudyResult) -> str:
    """The name of the processed record a study ran."""
    return str(getattr(study.motion, "name", "record"))


def combination_folder(out_dir: Path, study: StudyResult) -> Path:
    """``DIR/<record>_<controller>`` of one combination."""
    return out_dir / safe_name(f"{record_name(study)}_{study.controller_name}")


def run_batch(
    profile: Profile, options: StudyOptions, records: Sequence[str | None], controllers: Sequence[str | None],
    out_dir: str | Path | None = None, label: str | None = None, overrides: Sequence[str] = (),
    on_study: Callable[[StudyResult, int, int], None] | None = None,
) -> BatchStudy:
    """Run every record with every controller and summarise them.

    Parameters
    ----------
    profile : Profile
    options : StudyOptions
        The shared options; ``record`` and ``controller`` are replaced per combination.
    records, controllers : sequence of (str or None)
        None keeps the profile's own.
    out_dir : str or Path, optional
        Where to write the case sets and the summary; None writes nothing.
    label : str, optional
        The user's label, prefixed to every combination's (``--label``).
    overrides : sequence of str
        The profile's ``--set`` items, for the metadata.
    on_study : callable, optional
        ``on_study(study, done, total)`` after each combination.
    """
    batch = BatchStudy()
    total = len(records) * len(controllers)
    for record in records:
        for controller in controllers:
            study = run_study(profile, dataclasses.replace(options, record=record, controller=controller))
            batch.studies.append(study)
            if out_dir is not None:
                folder = combination_folder(Path(out_dir), study)
                named = f"{label} {record_name(study)} {study.controller_name}" if label else None
                batch.folders.append(write_study_folders(study, folder, named, overrides))
            if on_study is not None:
                on_study(study, len(batch.studies), total)
    cases = batch.cases()
    batch.tables = batch_tables(cases) if cases else []
    if out_dir is not None and batch.tables:
        write_summary(Path(out_dir), batch.tables)
    return batch


def write_summary(out_dir: Path, tables: Sequence[PeakTable]) -> None:
    """The summary tables as CSV files and one plain-text file in ``out_dir``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, table in zip(SUMMARY_FILES, tables, strict=True):
        (out_dir / name).write_text(table.to_csv(), encoding="utf-8")
    (out_dir / "summary.txt").write_text("\n\n".join(table.to_text() for table in tables) + "\n", encoding="utf-8")
