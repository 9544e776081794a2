"""``harness report RUN [RUN ...]``: tables, plots, one HTML page and a console summary.

Which tables a set of runs gets:

- always the peak table of all runs side by side;
- a passive/controlled table for each controlled run that has a passive run of the
  same record (a passive run is ``case: passive`` or ``controller: passive``);
- a comparison table for each two runs of the same record that are both controlled
  or both passive and not cases of one simulation (e.g. a table run against its
  simulation). Runs whose metadata names no record match any record.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from harness.recording.reader import RunData, load_runs
from harness.report.figure import PlotFile
from harness.report.html import report_html
from harness.report.peak_table import PeakTable
from harness.report.plots import PLOTS
from harness.report.tables import comparison_table, pair_table, runs_table

#: ``progress(message, done, total)``: called before each step and once at the end (done == total).
Progress = Callable[[str, int, int], None]

REPORT_HTML = "report.html"
SUMMARY_TXT = "summary.txt"
MAX_COMPARISONS = 6


@dataclass
class ReportResult:
    """What :func:`build_report` produced.

    Attributes
    ----------
    out_dir : Path
        Where the files are.
    html_path : Path
        The self-contained page.
    plots : list of PlotFile
        Written PNGs (plots without data are skipped).
    tables : list of PeakTable
        Peak, pair and comparison tables.
    runs : list of RunData
        The runs read.
    table_files : list of Path
        One CSV per table (``table_1_peak_responses.csv`` ...), for spreadsheets and MATLAB.
    warnings : list of str
        Incomplete runs, torn files, mismatched records ...
    summary : str
        Plain-text summary for the console (also in ``summary.txt``).
    """

    out_dir: Path
    html_path: Path
    plots: list[PlotFile] = field(default_factory=list)
    tables: list[PeakTable] = field(default_factory=list)
    runs: list[RunData] = field(default_factory=list)
    table_files: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    summary: str = ""


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
    """The peak table, then passive/controlled tables, then comparison tables."""
    tables = [runs_table(runs)]
    tables += [pair_table(p, c) for p, c in passive_pairs(runs)]
    tables += [comparison_table(a, b) for a, b in comparison_pairs(runs)]
    return tables


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
            notes.append(f"run {run.label} ended {run.outcome}: {reason}")
        recorder = run.metadata.get("recorder") or {}
        dropped = recorder.get("dropped") or {}
        if any(dropped.values()):
            notes.append(f"run {run.label}: the recorder dropped {dropped} (queue full); the signals have gaps")
        if recorder.get("error"):
            notes.append(f"run {run.label}: the recorder stopped writing ({recorder['error']}); later data are missing")
    return notes


def build_report(
    run_paths: Sequence[Path | str], out_dir: Path | str | None = None, progress: Progress | None = None
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
    runs = load_runs(run_paths)
    target = Path(out_dir) if out_dir is not None else Path(run_paths[0]) / "report"
    target.mkdir(parents=True, exist_ok=True)
    result = ReportResult(out_dir=target, html_path=target / REPORT_HTML, runs=runs, warnings=_record_warnings(runs))
    notify("computing peak tables", 1, total)
    result.tables = build_tables(runs)
    result.table_files = [_write_table_csv(target, index, table) for index, table in enumerate(result.tables, start=1)]
    for step, plot in enumerate(PLOTS, start=2):
        notify(f"plotting {plot.__name__.removesuffix('_plot').replace('_', ' ')}", step, total)
        written = plot(runs, target)
        if written is not None:
            result.plots.append(written)
    notify("writing HTML", total - 1, total)
    result.summary = summary_text(result)
    (target / SUMMARY_TXT).write_text(result.summary + "\n", encoding="utf-8")
    result.html_path.write_text(report_html(runs, result.tables, result.plots, result.warnings), encoding="utf-8")
    notify("done", total, total)
    return result


def _write_table_csv(out_dir: Path, index: int, table: PeakTable) -> Path:
    slug = "".join(ch if ch.isalnum() else "_" for ch in table.title.lower()).strip("_")
    while "__" in slug:
        slug = slug.replace("__", "_")
    path = out_dir / f"table_{index}_{slug[:60]}.csv"
    path.write_text(table.to_csv(), encoding="utf-8")
    return path


def summary_text(result: ReportResult) -> str:
    """Plain-text summary for the console: runs, warnings, tables and where the files are."""
    lines = ["Runs:"]
    for run in result.runs:
        reason = f" ({run.metadata.get('trip_reason')})" if run.metadata.get("trip_reason") else ""
        lines.append(f"  {run.label}: {run.kind}, {run.outcome}{reason}, {run.n_rows} ticks, {run.path}")
    if result.warnings:
        lines.append("Warnings:")
        lines += [f"  ! {w}" for w in result.warnings]
    for table in result.tables:
        lines += ["", table.to_text()]
    lines += [
        "",
        f"Report: {result.html_path}",
        f"Plots: {len(result.plots)} PNG files, tables: {len(result.table_files)} CSV files in {result.out_dir}",
    ]
    return "\n".join(lines)
