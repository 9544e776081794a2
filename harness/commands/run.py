"""``harness run``: the real rig, the same loop without the virtual rig.

The options, the question before arming and what is printed; the run itself (its table
link, which answers arm, the session) is :mod:`harness.runs.run`'s.
"""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    EPILOG,
    LOOP_RATE_HELP,
    RATE,
    RESET_DRIVE_HELP,
    add_bus_options,
    add_profile_options,
    add_record_options,
    check_run_length,
    load_acknowledged,
    non_empty,
    number_in,
    output_dir,
    study_options,
    wrap,
)
from harness.commands.output import (
    compile_kernels,
    print_host_timing,
    print_outcome,
    print_timing,
)

if TYPE_CHECKING:
    from harness.motions import GroundMotion
    from harness.profile import Profile
    from harness.runs.session import SessionResult


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "run",
        help="the real rig: the same loop, no virtual rig",
        description=wrap(
            "Run the control loop against the real rig on a CAN channel: the same code as a dry run "
            "without the virtual rig. The lab's table controller plays the record; this command runs for "
            "the record's duration (from the profile or --duration). It asks before it arms the actuator, "
            "naming the record, its PGA, time scale and duration (--yes skips the question). A drive that latched "
            "a watchdog fault (every drive does when the previous run's harness disconnected) is reset with "
            "--reset-drive. At the end it prints the run's peak responses. Ctrl-C stops safely (ramp down, drive "
            "off); a second Ctrl-C trips."
        ),
        epilog=(
            "examples:\n  harness run profiles/my_rig.yaml --interface socketcan --channel can0\n"
            "  harness run profiles/my_rig.yaml --interface socketcan --channel can0 --reset-drive\n\n" + EPILOG
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_profile_options(parser, "profile YAML of the rig")
    add_record_options(parser)
    add_bus_options(parser)
    parser.add_argument("--rate", type=number_in(RATE), metavar="HZ",
                        help=f"loop rate (default: the profile's control.rate_hz), {RATE.describe()}{LOOP_RATE_HELP}")
    parser.add_argument("--controller", type=non_empty, metavar="NAME", help="a design of the profile")
    parser.add_argument("--yes", action="store_true", help="do not ask before arming")
    parser.add_argument("--reset-drive", action="store_true", help=RESET_DRIVE_HELP)
    parser.add_argument("--log-dir", type=output_dir, metavar="DIR", help="where run folders go (default: logs/)")
    parser.add_argument("--quiet", action="store_true",
                        help="print the outcome line only (no live console); it still asks before arming")
    parser.set_defaults(handler=run, safe_points=True)  # moves the rig: Ctrl-C is a flag (harness/cli.py)


def run(args: argparse.Namespace, console: Console) -> int:
    from pathlib import Path

    from harness.paths import LOG_DIR
    from harness.runs.loop_rate import check_loop_rate
    from harness.runs.options import resolve_profile
    from harness.runs.run import answer_arms, arm_question, prepare_rig_run, run_on_rig, session_settings

    profile = load_acknowledged(args, console)
    profile = resolve_profile(profile, study_options(args, controller=args.controller, rate_hz=args.rate))
    check_loop_rate(profile, args.rate is not None, virtual_rig=False)
    check_run_length(profile, args)
    rig_run = prepare_rig_run(profile, args.interface, args.channel)
    note = escape(rig_run.table_link_note)
    console.print(note if rig_run.table_link is not None else f"[bold yellow]{note}[/]", highlight=False)
    if not args.yes:
        try:
            # escaped: "[y/N]" is text, not rich markup; soft wrap: one line, the answer typed after it
            console.print(escape(arm_question(rig_run, args.reset_drive)), end="", soft_wrap=True, highlight=False)
            answer = console.input()
        except (EOFError, OSError):  # no terminal to answer from (stdin closed or captured): that is a no
            answer = ""
        if not answer_arms(answer):
            console.print("not armed")
            return exit_codes.INPUT_ERROR
    settings = session_settings(rig_run, Path(args.log_dir) if args.log_dir else LOG_DIR, show_console=not args.quiet,
                                reset_drive=args.reset_drive)
    compile_kernels(console)
    session = run_on_rig(rig_run, settings, console=console, on_host_timing=print_host_timing(console))
    print_run_peaks(console, profile, rig_run.motion, session)
    print_timing(console, session.loop.timing, profile.control.rate_hz)
    print_outcome(console, session, weakened=profile.safety_weakened)
    return session.exit_code


def print_run_peaks(console: Console, profile: Profile, motion: GroundMotion, session: SessionResult) -> None:
    """The run's peak responses, as the dry run prints them, without a reference: what the run measured."""
    from harness.recording import load_run
    from harness.recording.peaks import run_peaks
    from harness.report.tables import reduction_table
    from harness.runs.dry_run import record_span_s
    from harness.signals.peaks import ComparisonWindow

    if session.record_problem:
        console.print(f"[bold red]the recorder failed[/]: {escape(session.record_problem)}; the peaks below come "
                      "from the rows written before that", highlight=False)
    console.print(
        f"[bold]{escape(profile.name)}[/] run, record [bold]{escape(motion.name)}[/]: PGA {motion.pga_g:.3f} g, "
        f"PGD {motion.pgd_m * 1e3:.1f} mm, time scale {motion.time_scale:g}, {motion.duration_s:.1f} s", highlight=False,
    )
    title = f"peak responses of the run (measured; no reference), {ComparisonWindow(0.0, motion.duration_s).describe()}"
    span_s = record_span_s(session, motion)
    if span_s is not None:
        title += f", over the {span_s:.2f} s of record that ran before the run ended ({session.outcome})"
    peaks = run_peaks(load_run(session.run_path))
    console.print(reduction_table(peaks, None, title, labels=("run", "")).to_rich())
