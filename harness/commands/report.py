"""``harness report``: peak tables, plots and an HTML page from run folders."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    OFFLINE_EPILOG,
    number_in,
    output_dir,
    wrap,
)
from harness.commands.output import print_always, progress_bar
from harness.config.input_limits import NumberRange

EXAMPLES = """\
examples:
  harness report logs/<run folder>            (the folder a dry run's or run's outcome line names)
  harness simulate eight_story --controller FSF-I --duration 10 --out study_fsf1/
  harness simulate eight_story --controller OF-I --duration 10 --out study_of1/
  harness report study_fsf1/ study_of1/ --label FSF-I --label OF-I --out compare/
      (the two simulate commands make the case sets this one compares)
"""

#: A story height for drift ratios (m): from a model building to a tall story.
STORY_HEIGHT = NumberRange(0.0, 20.0, "m")


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "report",
        help="tables and plots from run folders",
        description=wrap(
            "Build the peak-response tables (with % reduction for passive/controlled pairs, a dry run "
            "against its simulated passive reference and its rig twin, and a comparison for two runs of the "
            "same record), the context of each run (record, target against achieved table motion, controller "
            "parameters, loop timing, events and interlocks), plots (peak profiles, drift histories, table "
            "motion, bearing hysteresis, stroke against its limits, forces, sliding variable, loop timing) and "
            "one self-contained HTML page from one or more run folders (harness dry-run / run / simulate "
            "--out). Runs are labelled by what differs between them (controller, record, PGA, time scale, "
            "variant, --set overrides, kind); --label names them yourself."
        ),
        epilog=EXAMPLES + "\n" + OFFLINE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("runs", nargs="+", metavar="RUN", help="run folder, or a simulate --out folder of cases")
    parser.add_argument("--out", type=output_dir, metavar="DIR", help="where to write (default: RUN/report)")
    parser.add_argument("--label", action="append", metavar="TEXT",
                        help="label of the RUN in the same position (repeatable; a case set's cases get TEXT and their "
                        "case name); default: what differs between the runs")
    parser.add_argument("--story-height", type=number_in(STORY_HEIGHT), metavar="M",
                        help=f"story height (m): drifts are then plotted as a ratio of it (%%), {STORY_HEIGHT.describe()}")
    parser.add_argument("--quiet", action="store_true", help="print the outcome line only (no progress bar, no tables)")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.report import build_report, summary_text
    from harness.report.plots import PlotOptions

    if args.label and len(args.label) > len(args.runs):
        print_always(console, f"[bold red]error:[/] found {len(args.label)} --label for {len(args.runs)} RUN, expected "
                     "at most one per RUN", highlight=False)
        return exit_codes.INPUT_ERROR
    with progress_bar(console, not args.quiet) as progress:
        task = progress.add_task("report", total=1.0)

        def report(message: str, done: int, total: int) -> None:
            progress.update(task, description=message[:12], completed=done / max(total, 1))

        result = build_report(args.runs, args.out, progress=report, labels=args.label,
                              plot_options=PlotOptions(story_height_m=args.story_height))
    console.print(summary_text(result, width=console.width), highlight=False, markup=False, soft_wrap=True)
    for warning in result.warnings:
        console.print(f"[yellow]warning:[/] {escape(warning)}")
    warnings = f"; {len(result.warnings)} warning{'s' if len(result.warnings) != 1 else ''} (summary.txt)" \
        if result.warnings else ""
    print_always(console, f"wrote {len(result.plots)} plots and {escape(str(result.html_path))}{warnings}", soft_wrap=True)
    return exit_codes.OK
