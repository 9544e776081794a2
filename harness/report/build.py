"""``harness report RUN [RUN ...]``: tables, plots, one HTML page and a console summary.

Every run gets a label made from what differs between the runs (:mod:`harness.report.labels`),
used in every table, legend, CSV header and file name. Which peak tables a set of runs gets:

- always the peak table of all runs side by side;
- a passive/controlled table for each controlled run that has a passive run of the
  same record (a passive run is ``case: passive`` or ``controller: passive``);
- for a dry run, the table against its simulated passive reference and the one against
  its rig twin, as its console printed them (:mod:`harness.report.reference`);
- a comparison table for each two runs of the same record that are both controlled
  or both passive and not cases of one simulation (e.g. a table run against its
  simulation). Runs whose metadata names no record match any record.

Then the context: the record's facts, the table's target against achieved motion, the
actuator's force tracking (every controlled run with a load cell), the controller's parameters,
the loop timing, and each run's events and interlocks. Among the warnings: a run whose virtual
rig's truth differed from the design (``rig.truth``) says where, and a run whose table did not
play its record, or played it doubtfully (the table check, harness/report/table_check.py), says
so; its reductions are then withheld, or flagged.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from harness.recording.layout import METADATA_FILE
from harness.recording.reader import RunData, case_folders, load_runs
from harness.report.context import controller_table, record_table, timing_table
from harness.report.drive_faults import fault_text
from harness.report.events_table import event_tables
from harness.report.force_tracking_table import force_tracking_table
from harness.report.html import report_html
from harness.report.labels import file_slug, with_labels
from harness.report.peak_table import PeakTable
from harness.report.plots import PLOT_NAMES, PLOTS, PlotOptions
from harness.report.reference import reference_tables, target_motion_table
from harness.report.replay_link import replay_links
from harness.report.result import ReportResult
from harness.report.summary import summary_text
from harness.report.table_check import run_table_check
from harness.report.tables import comparison_table, pair_table, runs_table
from harness.report.text_table import TextTable

#: ``progress(message, done, total)``: called before each step and once at the end (done == total).
Progress = Callable[[str, int, int], None]

REPORT_HTML = "report.html"
SUMMARY_TXT = "summary.txt"
MAX_COMPARISONS = 6

__all__ = ["build_report", "load_labelled"]


def _same_record(a: RunData, b: RunData) -> bool:
    return a.record_name is None or b.record_name is None or a.record_name == b.record_name


def passive_pairs(runs: Sequence[RunData]) -> list[tuple[RunData, RunData]]:
    """(passive, controlled) pairs of the same record; a case set's own passive case is preferred."""
    passives = [r for r in runs if r.is_passive]
    pairs = []
    for run in runs:
        if run.is_passive:
            continue
        matches = [p for p in passives if _same_record(p, run)]
        matches.sort(key=lambda p: p.path.parent != run.path.parent)
        if matches:
            pairs.append((matches[0], run))
    return pairs


def comparison_pairs(runs: Sequence[RunData]) -> list[tuple[RunData, RunData]]:
    """Pairs of runs of the same record, alike in being passive or not, from different run sets."""
    pairs = []
    for i, first in enumerate(runs):
        for second in runs[i + 1 :]:
            same_set = first.case is not None and second.case is not None and first.path.parent == second.path.parent
            if first.is_passive == second.is_passive and _same_record(first, second) and not same_set:
                pairs.append((first, second))
    return pairs[:MAX_COMPARISONS]


def build_tables(runs: Sequence[RunData]) -> list[PeakTable]:
    """The peak table, then passive/controlled tables, the dry runs' reference tables, then comparison tables."""
    tables = [runs_table(runs)]
    tables += [pair_table(p, c) for p, c in passive_pairs(runs)]
    tables += reference_tables(runs)
    tables += [comparison_table(a, b) for a, b in comparison_pairs(runs)]
    return tables


def build_context(runs: Sequence[RunData]) -> list[TextTable]:
    """Record, target against achieved table motion, force tracking, controller, loop timing, then events and interlocks."""
    tables = [record_table(runs), target_motion_table(runs), force_tracking_table(runs), controller_table(runs),
              timing_table(runs)]
    return [table for table in tables if table is not None] + event_tables(runs)


def _record_warnings(runs: Sequence[RunData]) -> list[str]:
    notes = [w for run in runs for w in run.warnings]
    names = {run.record_name for run in runs if run.record_name}
    if len(names) > 1:
        listed = ", ".join(sorted(names))
        notes.append(f"the runs use different records ({listed}); only runs of one record are compared")
    for run in runs:
        if run.n_rows == 0:
            notes.append(f"run {run.label} has no recorded rows; its plots are empty")
        if run.outcome in ("tripped", "error"):
            reason = run.metadata.get("trip_reason") or "no reason recorded"
            servo = fault_text(run) if reason == "drive_fault" else ""
            notes.append(f"run {run.label} ended {run.outcome}: {reason}" + (f" ({servo})" if servo else ""))
        recorder = run.metadata.get("recorder") or {}
        dropped = recorder.get("dropped") or {}
        if any(dropped.values()):
            notes.append(f"run {run.label}: the recorder dropped {dropped} (queue full); the signals have gaps")
        if recorder.get("error"):
            notes.append(f"run {run.label}: the recorder stopped writing ({recorder['error']}); later data are missing")
        truth = truth_note(run)
        if truth:
            notes.append(f"run {run.label}: {truth}")
        check = run_table_check(run.metadata)
        if check.verdict in ("mismatch", "marginal"):
            notes.append(f"run {run.label}: {check.line}")
    return notes


def truth_note(run: RunData) -> str:
    """Where the run's virtual rig differs from the design (``metadata["rig_truth"]``, harness/rig/truth.py); "" if not.

    The controller, the friction estimator and the supervisor used the design; the rig, and the
    simulated passive reference and twin a dry run is compared with, the truth.
    """
    truth = run.metadata.get("rig_truth")
    summary = truth.get("summary") if isinstance(truth, dict) else None
    if not summary:
        return ""
    if run.is_passive:
        return f"{summary}. This passive case ran on the true values"
    return (f"{summary}. The controller, its friction estimator and the supervisor used the design values; "
            "the virtual rig (and a dry run's simulated passive reference and twin) the true ones")


def _expand_batch(folder: Path) -> list[Path]:
    """A batch folder (``simulate --out`` with lists: a folder of case sets) as its case sets; else ``[folder]``."""
    if not folder.is_dir() or (folder / METADATA_FILE).is_file() or case_folders(folder):
        return [folder]
    sets = sorted(p for p in folder.iterdir() if p.is_dir() and case_folders(p))
    return sets or [folder]


def load_labelled(run_paths: Sequence[Path | str], labels: Sequence[str] | None = None) -> list[RunData]:
    """Read the run folders and label every run (:func:`harness.report.labels.with_labels`).

    Parameters
    ----------
    run_paths : sequence of Path or str
        Run folders or case sets.
    labels : sequence of str, optional
        A label per path, in order (``--label``); a case set's cases get it followed by their case name.
    """
    runs: list[RunData] = []
    given: list[str | None] = []
    for index, item in enumerate(run_paths):
        loaded = load_runs(_expand_batch(Path(item)))
        chosen = labels[index] if labels is not None and index < len(labels) else None
        for run in loaded:
            case_set = len(loaded) > 1 and run.case is not None
            given.append(None if chosen is None else f"{chosen} {run.case}" if case_set else chosen)
        runs += loaded
    return with_labels(runs, given)


def build_report(
    run_paths: Sequence[Path | str], out_dir: Path | str | None = None, progress: Progress | None = None,
    labels: Sequence[str] | None = None, plot_options: PlotOptions | None = None,
) -> ReportResult:
    """Build the report of one or more run folders (or simulation case sets).

    Parameters
    ----------
    run_paths : sequence of Path or str
        Run folders, or folders of simulation cases (``DIR/passive``, ``DIR/controlled``).
    out_dir : Path or str, optional
        Output folder (created); default ``<first path given>/report``.
    progress : callable, optional
        ``progress(message, done, total)`` before each step and at the end.
    labels : sequence of str, optional
        A label per path (``--label``), instead of the one made from what differs.
    plot_options : PlotOptions, optional
        Story height for drift ratios, ...

    Returns
    -------
    ReportResult

    Raises
    ------
    RunFolderError
        If a path is not a run folder or has an unknown format version. An incomplete
        run is read and reported with a warning.
    """
    if not run_paths:
        raise ValueError("found no run folders, expected at least one")
    notify = progress or (lambda message, done, total: None)
    total = len(PLOTS) + 3
    notify("reading run folders", 0, total)
    runs = load_labelled(run_paths, labels)
    target = Path(out_dir) if out_dir is not None else Path(run_paths[0]) / "report"
    target.mkdir(parents=True, exist_ok=True)
    _remove_previous(target)
    result = ReportResult(out_dir=target, html_path=target / REPORT_HTML, runs=runs, warnings=_record_warnings(runs),
                          replay=replay_links(runs))
    notify("computing peak tables", 1, total)
    result.tables = build_tables(runs)
    result.context = build_context(runs)
    all_tables: list[PeakTable | TextTable] = [*result.tables, *result.context]
    result.table_files = [_write_table_csv(target, index, table) for index, table in enumerate(all_tables, start=1)]
    options = plot_options or PlotOptions()
    for step, plot in enumerate(PLOTS, start=2):
        notify(f"plotting {plot.__name__.removesuffix('_plot').replace('_', ' ')}", step, total)
        written = plot(runs, target, options)
        if written is not None:
            result.plots.append(written)
    notify("writing HTML", total - 1, total)
    result.summary = summary_text(result)
    (target / SUMMARY_TXT).write_text(result.summary + "\n", encoding="utf-8")
    page = report_html(runs, result.tables, result.plots, result.warnings, result.context, result.replay)
    result.html_path.write_text(page, encoding="utf-8")
    notify("done", total, total)
    return result


def _remove_previous(out_dir: Path) -> None:
    """Remove the tables and plots an earlier report wrote into ``out_dir`` (names change with the labels)."""
    for path in [*out_dir.glob("table_*.csv"), *(out_dir / f"{name}.png" for name in PLOT_NAMES)]:
        path.unlink(missing_ok=True)


def _write_table_csv(out_dir: Path, index: int, table: PeakTable | TextTable) -> Path:
    path = out_dir / f"table_{index}_{file_slug(table.title)}.csv"
    path.write_text(table.to_csv(), encoding="utf-8")
    return path
