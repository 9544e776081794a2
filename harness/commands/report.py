"""``harness report``: peak tables, plots and an HTML page from run folders."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    EPILOG,
    output_dir,
    wrap,
)
from harness.commands.output import progress_bar


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "report",
        help="tables and plots from run folders",
        description=wrap(
            "Build the peak-response tables (with %% reduction for passive/controlled pairs and a "
            "comparison for two runs of the same record), plots (drift histories, table motion, "
            "bearing hysteresis, stroke against its limits, forces, sliding variable, loop timing) "
            "and one self-contained HTML page from one or more run folders "
            "(harness dry-run / run / simulate --out)."
        ),
        epilog="example:\n  harness report logs/2026-11-22T03-10-05_nceer_4dof_dry-run study/ --out report/\n\n" + EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("runs", nargs="+", metavar="RUN", help="run folder, or a simulate --out folder of cases")
    parser.add_argument("--out", type=output_dir, metavar="DIR", help="where to write (default: RUN/report)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.report import build_report, summary_text

    with progress_bar(console, not args.quiet) as progress:
        task = progress.add_task("report", total=1.0)

        def report(message: str, done: int, total: int) -> None:
            progress.update(task, description=message[:12], completed=done / max(total, 1))

        result = build_report(args.runs, args.out, progress=report)
    console.print(summary_text(result), highlight=False, markup=False)
    for warning in result.warnings:
        console.print(f"[yellow]warning:[/] {escape(warning)}")
    console.print(f"wrote {len(result.plots)} plots and {result.html_path}")
    return exit_codes.OK
