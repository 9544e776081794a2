"""``harness dry-run``: the whole test against the virtual rig over CAN (the main job)."""

from __future__ import annotations

import argparse

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
    command_console,
    compile_kernels,
    print_always,
    print_host_timing,
    print_outcome,
    print_timing,
)


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "dry-run",
        help="the whole test against the virtual rig over CAN (the main job)",
        description=wrap(
            "Run the real control loop against the virtual rig, which emulates the 4-DOF rig (base mat "
            "on friction bearings, three stories, shaking table, sensor noise, quantization, delay, "
            "actuator dynamics) and speaks the same CAN protocol. It arms when every pre-arm check passes, "
            "starts the table, runs the record, ramps the force down, writes a run folder and prints the "
            "peaks beside the simulated passive reference. With no arguments: profiles/nceer_4dof.yaml, "
            "the synthetic record, in real time, with the rig in its own process on a private Unix-socket "
            "CAN bus (python-can interface 'seqpacket': no set-up, no root). Before arming, a one-second "
            "pre-flight check measures whether this host can hold the loop's rate within the stall budget. "
            "Ctrl-C stops safely (ramp down, drive off); a second Ctrl-C trips."
        ),
        epilog=(
            "examples:\n  harness dry-run\n  harness dry-run profiles/nceer_4dof.yaml --record el_centro --pga 0.34 "
            "--time-scale 2 --records-dir ../shared/data/ground_motions\n"
            "  harness dry-run --interface socketcan --channel vcan0          (starts `harness rig` itself)\n"
            "  harness dry-run --lockstep                                      (deterministic; any machine)\n"
            "  harness dry-run --lockstep --set safety.stroke.soft_limit_m=0.006 --set safety.stroke.fade_band_m=0.002 "
            "--set safety.stroke.hard_limit_m=0.008   (watch it trip)\n\n" + EPILOG
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_profile_options(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    add_record_options(parser)
    add_bus_options(parser)
    loop = parser.add_argument_group("loop")
    loop.add_argument("--rate", type=number_in(RATE), metavar="HZ",
                      help=f"loop rate (default: the profile's control.rate_hz), {RATE.describe()}{LOOP_RATE_HELP}; "
                      "a whole number of rig.physics_substep_s per period")
    loop.add_argument("--controller", type=non_empty, metavar="NAME",
                      help="a design of the profile (default: control.controller)")
    loop.add_argument("--lockstep", action="store_true",
                      help="the rig advances one step per command (deterministic; slow machines)")
    loop.add_argument("--external-rig", action="store_true", help="a `harness rig` already serves the channel; do not start one")
    loop.add_argument("--reset-drive", action="store_true", help=f"with --external-rig: {RESET_DRIVE_HELP}")
    output = parser.add_argument_group("output")
    output.add_argument("--log-dir", type=output_dir, metavar="DIR", help="where run folders go (default: logs/)")
    output.add_argument("--quiet", action="store_true", help="print the outcome line only (no live console, no tables)")
    parser.set_defaults(handler=run, safe_points=True)  # moves the rig: Ctrl-C is a flag (harness/cli.py)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.report.table_check import table_check
    from harness.report.tables import reduction_table
    from harness.runs.dry_run import DryRunOptions, dry_run
    from harness.runs.loop_rate import check_loop_rate
    from harness.runs.options import resolve_profile
    from harness.signals.peaks import ComparisonWindow

    if args.reset_drive and not args.external_rig:
        command_console(stderr=True).print(  # an error: on standard error, and never silenced by --quiet
            "[bold red]error:[/] --reset-drive resets the drive of a rig that already serves the channel: "
            "add --external-rig (a rig this command starts has a fresh drive)", highlight=False, soft_wrap=True)
        return exit_codes.INPUT_ERROR
    profile = load_acknowledged(args, console)
    study = study_options(args, controller=args.controller, rate_hz=args.rate)
    resolved = resolve_profile(profile, study)  # dry_run resolves it again; checked here, before anything starts
    check_loop_rate(resolved, args.rate is not None, virtual_rig=True)
    check_run_length(resolved, args)
    options = DryRunOptions(
        study=study, interface=args.interface,
        channel=args.channel, log_dir=args.log_dir, lockstep=args.lockstep, external_rig=args.external_rig,
        show_console=not args.quiet, reset_drive=args.reset_drive,
    )
    compile_kernels(console)
    result = dry_run(profile, options, console, on_host_timing=print_host_timing(console))
    session, motion = result.session, result.motion
    if session.record_problem:
        console.print(f"[bold red]the recorder failed[/]: {escape(session.record_problem)}; the peaks below come "
                      "from the rows written before that", highlight=False)
    console.print(
        f"[bold]{profile.name}[/] dry run, record [bold]{motion.name}[/]: PGA {motion.pga_g:.3f} g, "
        f"PGD {motion.pgd_m * 1e3:.1f} mm, time scale {motion.time_scale:g}, {motion.duration_s:.1f} s"
    )
    for warning in motion.warnings:
        console.print(f"  [bold yellow]warning:[/] {escape(warning)}", highlight=False)
    title = f"peak responses: simulated passive reference and the dry run, {ComparisonWindow(0.0, motion.duration_s).describe()}"
    if result.span_s is not None:
        title += f", over the {result.span_s:.2f} s of record that ran before the run ended ({session.outcome})"
    assert result.passive is not None, "the command's dry run is compared (DryRunOptions.compare)"
    check = table_check(session.loop.table_record)  # a table that did not play the told record: no reductions
    table = reduction_table(result.passive.peaks, result.peaks, title, labels=("passive (sim.)", "dry run"),
                            withheld=check.withheld, flagged=check.flagged)
    console.print(table.to_rich(console.width))
    if check.withheld:
        console.print("against `harness simulate --rig-effects`: not compared (the twin played the told record, "
                      "the table did not)", highlight=False)
    else:
        worst, difference_pct = result.largest_twin_difference()
        console.print(f"against `harness simulate --rig-effects` (the rig's models offline): largest peak difference "
                      f"{difference_pct:.1f} % ({worst})")
    print_timing(console, session.loop.timing, result.profile.control.rate_hz)
    print_outcome(console, session, virtual_rig=not options.external_rig, weakened=profile.safety_weakened)
    if result.truth_note:
        console.print(f"  [yellow]{escape(result.truth_note)}[/]", highlight=False)
    if result.table_refused:  # the rig answered the start with a refusal: the run did not test this record
        print_always(console, f"[bold red]warning:[/] {escape(result.table_refused)}", highlight=False, soft_wrap=True)
        return exit_codes.STOPPED if session.exit_code == exit_codes.OK else session.exit_code
    return session.exit_code
