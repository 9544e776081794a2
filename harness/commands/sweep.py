"""``harness sweep``: a study of many cases (records x PGA x designs x parameters x samples), one simulation each."""

from __future__ import annotations

import argparse
import dataclasses
import shlex
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    ProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)
from rich.text import Text

from harness import exit_codes
from harness.commands.options import non_empty, output_dir, study_path, wrap
from harness.commands.output import print_always
from harness.report.text_table import TextTable

if TYPE_CHECKING:
    from harness.profile import Profile
    from harness.sweep.driver import SweepTotals
    from harness.sweep.summary import ValueTable
    from harness.sweep.worker import SimulatedCase

EXAMPLES = """\
examples:
  harness sweep profiles/studies/robustness_table2.yaml --report table2/
      the source's Table 2: FSF-I designed with story stiffness x0.7, x1.0, x1.3
  harness sweep profiles/studies/ida_friction.yaml --workers 2 --report ida/
      3 records x 4 PGA levels x 2 designs x 8 friction samples on two local workers
  harness sweep STUDY.yaml --scheduler tcp://head-node:8786      (a running Dask cluster)
  harness sweep STUDY.yaml --local-cluster --workers 2            (a Dask LocalCluster)
  harness sweep --summarize logs/sweeps/ida_friction --report ida/
  harness sweep STUDY.yaml --case 3f2a9c    (the harness simulate command of one case)

A rerun of the same study into the same --out folder skips the cases already there
(each case is keyed by a hash of its resolved inputs); a study extended with more
levels or samples runs only the new cases. Results: --out/cases.parquet (and
cases.csv), one row per case: inputs, every peak, % reductions, outcome, error,
wall time. Study files: profiles/studies/ and README, "Studies at scale"; a shipped
study is found by its name (ida_friction) or as profiles/studies/NAME.yaml from any folder.

records: names in a study (el_centro, hachinohe, pacoima, synthetic:SEED) are looked up
in --records-dir, else the study's options.records_dir, else $HARNESS_RECORDS_DIR, else
the profile's record.records_dir; a path is relative to the study file.

exit status:
  0  completed (cases that failed are rows with their error; the sweep still completed)
  1  internal error (bug)
  2  bad input: the study file, its profile or a value it gives, or the results folder
  4  stopped by Ctrl-C: the rows so far are kept, and the same command goes on from there
"""


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "sweep",
        help="a study of many offline simulations: IDA, robustness, Monte Carlo; local cores or Dask",
        description=wrap(
            "Run every case of a study file, each one offline simulation exactly as harness simulate runs "
            "it (passive and controlled), on all local cores by default or on a Dask cluster, writing one "
            "row per case as it goes and skipping cases already done. --report writes summary tables, IDA "
            "and fragility curves (CSV and PNG)."
        ),
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("study", nargs="?", type=study_path, metavar="STUDY",
                        help="study file (YAML), or the name of a shipped study (compensation, ida_friction, robustness_table2), "
                        "found from any folder")
    parser.add_argument("--summarize", type=non_empty, metavar="RESULTS", help="report on a results folder instead of running")
    parser.add_argument("--out", type=output_dir, metavar="DIR", help="results folder (default: logs/sweeps/<study name>)")
    parser.add_argument("--report", type=output_dir, metavar="DIR", help="write summary tables, IDA and fragility curves here")
    parser.add_argument("--records-dir", type=non_empty, metavar="DIR",
                        help="where named records are found (instead of the study's options.records_dir)")
    engine = parser.add_argument_group("engine (default: local worker processes, one per core)")
    engine.add_argument("--workers", type=_count, metavar="N",
                        help="worker processes (default: every core); 0 runs the cases in this process")
    engine.add_argument("--scheduler", type=non_empty, metavar="ADDRESS", help="a running Dask scheduler, e.g. tcp://head:8786")
    engine.add_argument("--local-cluster", action="store_true", help="start a Dask LocalCluster of --workers processes")
    engine.add_argument("--batch", type=_count, default=4, metavar="N", help="cases per Dask task (default 4)")
    cases = parser.add_argument_group("cases")
    cases.add_argument("--retry-failed", action="store_true", help="run again the cases recorded as failed")
    cases.add_argument("--plan", action="store_true", help="count the cases (all, done, to run) and stop")
    cases.add_argument("--case", type=non_empty, metavar="ID", help="print the harness simulate command of a case (key prefix)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run)


def _count(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"found {text!r}, expected a whole number >= 0") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"found {value}, expected a whole number >= 0")
    return value


def simulate_case(profile: Profile, options: dict[str, Any]) -> SimulatedCase:
    """One case of a sweep: ``harness simulate``'s own ``run_study``, its peaks and integration time."""
    from harness.runs.options import StudyOptions
    from harness.runs.simulate import run_study
    from harness.sweep.worker import SimulatedCase

    result = run_study(profile, StudyOptions(**options))
    return SimulatedCase(
        {name: case.peaks for name, case in result.cases.items()},
        sum(case.wall_time_s for case in result.cases.values()),
    )


def run(args: argparse.Namespace, console: Console) -> int:
    if args.summarize:
        return _summarize(Path(args.summarize), Path(args.report) if args.report else None, console)
    if not args.study:
        print_always(console, "[bold red]error:[/] give a study file, or --summarize RESULTS (see harness sweep --help)")
        return exit_codes.INPUT_ERROR
    if args.scheduler and args.local_cluster:
        print_always(console, "[bold red]error:[/] --scheduler and --local-cluster: expected one Dask cluster, not both")
        return exit_codes.INPUT_ERROR
    return _sweep(args, console)


def _sweep(args: argparse.Namespace, console: Console) -> int:
    from harness.sweep.cases import base_of, case_count, expand
    from harness.sweep.study import load_study

    study = load_study(args.study)
    if args.records_dir:
        options = dataclasses.replace(study.options, records_dir=str(Path(args.records_dir).expanduser().resolve()))
        study = dataclasses.replace(study, options=options)
    count = case_count(study)  # from the axes alone, at once; refuses a study beyond MAX_CASES before it is built
    folder = Path(args.out) if args.out else Path("logs") / "sweeps" / study.name
    if args.plan:
        console.print(f"[bold]{study.name}[/]: {count.total} cases ({count.describe()})", highlight=False)
        return _plan(args, console, study, folder)
    with console.status(f"expanding {study.name} and checking every value on the profile ..."):
        cases = expand(study)
    base = base_of(study)
    if args.case:
        return _show_case(cases, base, args.case, console)
    return _run_cases(args, console, study, cases, folder)


def _plan(args: argparse.Namespace, console: Console, study, folder: Path) -> int:
    """``--plan``: the cases already in ``folder`` and those to run, after checking every value; nothing is written.

    The count came from the axes (printed at once); the cases are then built, within
    ``MAX_CASES``, to check each value on the profile and to match them with the rows by key.
    """
    from harness.sweep.cases import expand
    from harness.sweep.driver import STUDY_COPY, plan, refuse_other_study
    from harness.sweep.store import ResultStore

    has_results = (folder / STUDY_COPY).is_file()
    if has_results:
        refuse_other_study(folder, study)
    with console.status(f"checking every value of {study.name} on the profile ..."):
        cases = expand(study)
    if not has_results:
        console.print(f"[bold]{study.name}[/]: {len(cases)} cases, 0 already in {folder} (no results there yet), "
                      f"{len(cases)} to run", highlight=False)
        return exit_codes.OK
    todo = plan(cases, ResultStore(folder), args.retry_failed)
    console.print(f"[bold]{study.name}[/]: {len(cases)} cases, {todo.skipped} already in {folder}, {len(todo.todo)} to run",
                  highlight=False)
    return exit_codes.OK


def _show_case(cases, base, prefix: str, console: Console) -> int:
    found = [case for case in cases if case.key.startswith(prefix)]
    if len(found) != 1:
        print_always(console, f"[bold red]error:[/] {len(found)} cases have a key starting with {prefix!r}; expected one")
        return exit_codes.INPUT_ERROR
    print_always(console, shlex.join(["harness", *found[0].simulate_argv(base)]), highlight=False, soft_wrap=True, markup=False)
    return exit_codes.OK


def _run_cases(args: argparse.Namespace, console: Console, study, cases, folder: Path) -> int:
    from harness.sweep.driver import open_folder, plan, run_sweep, write_metadata
    from harness.sweep.worker import CaseRunner

    base = _base(study)
    with open_folder(folder, study) as store:
        todo = plan(cases, store, args.retry_failed)
        plan_line = (f"[bold]{study.name}[/]: {len(cases)} cases, {todo.skipped} already in {folder}, "
                     f"{len(todo.todo)} to run; results as {store.format}"
                     + ("" if store.parquet else " (pyarrow is not installed: pip install pyarrow for Parquet)"))
        if args.plan:  # the count is what --plan asks for
            print_always(console, plan_line)
        else:
            console.print(plan_line)
        if args.plan or not todo.todo:
            return _finish(args, console, folder, store, None)
        runner = CaseRunner(base, simulate_case)
        engine = _engine(args, console, runner)
        started = datetime.now(UTC)
        report = _report_settings(study, base).to_json()
        try:
            write_metadata(folder, study, engine, todo, None, started, report)
            with _progress(console, args.quiet) as progress:
                task = progress.add_task(f"{study.name}", total=len(todo.todo), failed=0)
                failed = 0

                def advance(row: dict[str, Any]) -> None:
                    nonlocal failed
                    failed += row["outcome"] != "ok"
                    progress.update(task, advance=1, failed=failed)

                totals = run_sweep(todo.todo, engine, runner, store, advance)
        finally:
            engine.close()
        write_metadata(folder, study, engine, todo, totals, started, report)
        _print_totals(console, totals, engine.description)
        status = _finish(args, console, folder, store, totals)
    return exit_codes.STOPPED if totals.interrupted else status


def _base(study):
    from harness.sweep.cases import base_of

    return base_of(study)


def _report_settings(study, base):
    from harness.sweep.report import ReportSettings

    stroke = study.fragility.sliding_displacement_limit_m or base.load().safety.stroke.hard_limit_m
    grid = [*study.axes.set, *(f"scale:{key}" for key in study.axes.scale)]
    return ReportSettings(study.name, grid, stroke, study.fragility.drift_limit_m)


def _engine(args: argparse.Namespace, console: Console, runner):
    from harness.sweep.engines import InlineEngine, LocalEngine

    if args.scheduler or args.local_cluster:
        from harness.sweep.dask_engine import DaskEngine

        with console.status("connecting to the Dask cluster and warming its workers ..."):
            return DaskEngine(args.scheduler, args.workers or None, args.batch, prepare=runner.warm)
    if args.workers == 0:
        return InlineEngine(prepare=runner.warm)
    with console.status("starting the worker processes (each loads the integration kernels once) ..."):
        return LocalEngine(args.workers, prepare=runner.warm)


class RateColumn(ProgressColumn):
    """Cases per second, and the failed count."""

    def render(self, task) -> Text:
        speed = task.finished_speed or task.speed
        rate = f"{speed:.2f} cases/s" if speed else "-- cases/s"
        failed = task.fields.get("failed", 0)
        return Text(rate + (f", {failed} failed" if failed else ""), style="progress.data.speed")


def _progress(console: Console, quiet: bool) -> Progress:
    return Progress(
        TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), RateColumn(),
        TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn(), console=console, disable=quiet,
        refresh_per_second=4,
    )


def _print_totals(console: Console, totals: SweepTotals, engine: str) -> None:
    per_case = totals.wall_time_s / totals.ran if totals.ran else 0.0
    rate = totals.ran / totals.wall_time_s if totals.wall_time_s else 0.0
    console.print(f"ran {totals.ran} cases in {totals.wall_time_s:.1f} s on {engine}: {rate:.2f} cases/s "
                  f"({per_case:.3f} s each), integration {totals.integration_s:.1f} s of CPU")
    if totals.failed:
        console.print(f"[yellow]{totals.failed} cases failed[/]: their rows hold the error (outcome 'failed'); "
                      "--retry-failed runs them again")
    if totals.interrupted:
        console.print("[yellow]stopped by Ctrl-C[/]: the rows so far are kept; the same command goes on from there")


def _finish(args: argparse.Namespace, console: Console, folder: Path, store, totals: SweepTotals | None) -> int:
    """Where the results are (the outcome line, unless a report follows), and the report if asked."""
    report = bool(args.report) and (folder / "sweep.json").is_file()
    if totals is not None or (folder / "sweep.json").is_file():
        failed = f"; {totals.failed} cases failed" if totals is not None and totals.failed else ""
        results = f"results: {folder}/cases.{store.format}" + (", cases.csv" if store.parquet else "") + failed
        if report or args.plan:
            console.print(results)
        else:
            print_always(console, results)
    if report:
        return _summarize(folder, Path(args.report), console)
    return exit_codes.OK


def _summarize(results: Path, report: Path | None, console: Console) -> int:
    from harness.sweep.report import load_settings, write_report
    from harness.sweep.store import ResultStore

    if not (results / "sweep.json").is_file():
        print_always(console, f"[bold red]error:[/] {results} holds no sweep (no sweep.json); expected a results folder "
                     "of harness sweep")
        return exit_codes.INPUT_ERROR
    columns = ResultStore(results).columns()
    if not columns:
        print_always(console, f"[yellow]{results} holds no case yet[/]")
        return exit_codes.OK
    files, tables = write_report(columns, load_settings(results), report or results / "report")
    for table in tables:
        console.print(_text_table(table).to_rich(console.width))
    print_always(console, "wrote " + ", ".join(str(path) for path in files), highlight=False, soft_wrap=True)
    for warning in _fragility_warnings(files):
        print_always(console, f"[yellow]warning:[/] {escape(warning)}", highlight=False, soft_wrap=True)
    return exit_codes.OK


def _fragility_warnings(files: list[Path]) -> list[str]:
    """One line per fragility curve whose fit ``fragility.csv`` marks as not meaningful (harness/sweep/curves.py)."""
    import csv

    from harness.sweep.curves import NOT_MEANINGFUL

    found = next((path for path in files if path.name == "fragility.csv"), None)
    if found is None:
        return []
    with found.open(newline="", encoding="utf-8") as handle:
        marked = {(row["response"], row["design"]): row["note"] for row in csv.DictReader(handle)
                  if NOT_MEANINGFUL in row.get("note", "")}
    return [f"fragility of {response}, {design}: {note}" for (response, design), note in marked.items()]


#: Most rows of a summary table shown on the console; beyond it only the rows over all records.
CONSOLE_ROWS = 15


#: The summary tables' columns of text (the rest are numbers).
TEXT_COLUMNS = ("design", "record")


def _text_table(table: ValueTable) -> TextTable:
    """A summary table for the console: at most :data:`CONSOLE_ROWS` rows, numbers to 3 significant figures.

    Rendered with :meth:`TextTable.to_rich`, its columns wrap their headings and split into
    blocks that repeat the design (and record) rather than cutting a cell.
    """
    from harness.sweep.summary import ALL

    rows = table.rows
    note = ""
    if len(rows) > CONSOLE_ROWS and "record" in table.header:
        at = table.header.index("record")
        rows = [row for row in rows if row[at] == ALL]
        note = " (over all records; per record in summary.csv)"
    keys = 0
    while keys < len(table.header) and table.header[keys] in TEXT_COLUMNS:
        keys += 1
    return TextTable(table.title + note, tuple(name.replace("_", " ") for name in table.header),
                     tuple(tuple(table.cells(row)) for row in rows), key_columns=max(keys, 1),
                     numeric=tuple(name not in TEXT_COLUMNS for name in table.header))
