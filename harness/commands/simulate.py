"""``harness simulate``: offline simulation, passive and controlled side by side.

Comma-separated lists of records and controllers make a batch: every record with every controller.
"""

from __future__ import annotations

import argparse
from typing import Any

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    DELAY,
    JSON_FORCE_HELP,
    RATE,
    SIMULATE_EPILOG,
    STIFFNESS_SCALE,
    add_overrides,
    add_profile_argument,
    add_record_options,
    check_json_target,
    check_run_length,
    json_file,
    non_empty,
    number_in,
    output_dir,
    study_options,
    wrap,
)
from harness.commands.output import json_console, print_always, progress_bar, write_json

EXAMPLES = """\
examples:
  harness simulate eight_story --record el_centro --pga 0.3 --duration 30 --controller FSF-I --json out.json
  harness simulate eight_story --record el_centro,hachinohe,pacoima --controller FSF-I,OF-I --out study/
      (a batch: one folder per record and controller, and the summary tables)
  harness simulate --rig-effects --drive-from logs/<RUN> --overlay <OUT>/identified.yaml --controller phi
      (the twin's table plays the motion that run achieved, its measured x_0 and xdot_0 tick by tick:
      the new controller, bound or compensation on the shaking the rig really produced)
"""


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "simulate",
        help="offline simulation, passive and controlled side by side",
        description=wrap(
            "Simulate the profile's building on its bearings under the record, once passive "
            "(bearings only) and once with the controller, faster than real time, and print the "
            "peak responses with the % reduction. The controller samples at --rate and holds its "
            "force until the next sample (SPEC 3). Comma-separated lists in --record and --controller "
            "run every record with every controller (a batch) and print the peaks per record and the "
            "mean and largest % reduction per controller; with --out, each combination is written to "
            "its own folder DIR/<record>_<controller>/ beside the summary tables."
        ),
        epilog=EXAMPLES + "\n" + SIMULATE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_profile_argument(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    add_overrides(parser, "control.designs.phi.p1_per_s=8.0")
    add_record_options(parser)
    control = parser.add_argument_group("control")
    control.add_argument("--controller", type=non_empty, metavar="NAME[,NAME...]|none",
                         help="a design of the profile, a comma-separated list of them (a batch), or 'none' (passive only)")
    control.add_argument("--rate", type=number_in(RATE), metavar="HZ", help=f"controller sample rate (Hz), {RATE.describe()}")
    control.add_argument("--friction", choices=("estimator", "model"), help="friction term: online estimate or the model's")
    control.add_argument("--delay", type=number_in(DELAY), metavar="S",
                         help=f"further transport delay from sample to force (s), {DELAY.describe()}")
    control.add_argument(
        "--design-stiffness-scale", type=number_in(STIFFNESS_SCALE), metavar="X",
        help=f"controller's model has story stiffness x X (robustness: 0.7, 1.3), {STIFFNESS_SCALE.describe()}",
    )
    control.add_argument(
        "--rig-effects", action="store_true",
        help="controlled case through the profile's rig models: sensor noise, quantization and delay, "
        "actuator dynamics and limits, and the safety supervisor (what a dry run should reproduce); "
        "--delay then adds sensor delay: one loop period (e.g. 0.002) mirrors a real-time dry run",
    )
    control.add_argument(
        "--drive-from", type=non_empty, metavar="RUN_DIR",
        help="with --rig-effects: drive the twin's table with the table motion the run in RUN_DIR (a dry run's or "
        "run's folder) achieved, its measured table displacement and velocity at each tick, in place of the record: "
        "twin sample k is the run's tick k, so the rate must be the run's (--rate); the table follows that motion "
        "exactly (rig.table.model motion_source). Closed loop on the twin of the profile given (PROFILE, --overlay "
        "identified.yaml, --set; a note says so when the run's profile had another name): the structure answers this "
        "controller, the table does what it did in the run. --duration keeps its first seconds; --record, --records-dir, --pga "
        "and --time-scale do not apply",
    )
    output = parser.add_argument_group("output")
    output.add_argument("--json", type=json_file, metavar="PATH",
                        help="write peaks and record facts as JSON (SI units); '-' writes it to standard output (and the "
                        "rest to standard error)")
    output.add_argument("--force", action="store_true", help=JSON_FORCE_HELP)
    output.add_argument("--out", type=output_dir, metavar="DIR", help="save both cases' time series as run folders in DIR")
    output.add_argument("--label", type=non_empty, metavar="TEXT",
                        help="label of this study in reports (default: made from what differs between the runs compared)")
    output.add_argument("--quiet", action="store_true", help="print the outcome line only (no progress bar, no tables)")
    parser.set_defaults(handler=run)


def _study_options(args: argparse.Namespace) -> Any:
    return study_options(
        args, controller=args.controller, rate_hz=args.rate, friction=args.friction, transport_delay_s=args.delay,
        design_stiffness_scale=args.design_stiffness_scale, rig_effects=args.rig_effects, drive_from=args.drive_from,
    )


#: The record options a drive from a run's achieved motion replaces, by their attribute on the parsed arguments.
_RECORD_OPTIONS = {"record": "--record", "records_dir": "--records-dir", "pga": "--pga", "time_scale": "--time-scale"}


def _check_drive_from(args: argparse.Namespace) -> None:
    """Refuse a record option beside ``--drive-from``: the run's achieved motion is the table's drive.

    Raises
    ------
    DriveFromError
        Naming the options given and what ``--drive-from`` expects instead.
    """
    from harness.simulation.drive import DriveFromError

    given = [flag for name, flag in _RECORD_OPTIONS.items() if getattr(args, name) is not None]
    if args.drive_from is not None and given:
        raise DriveFromError(f"found {', '.join(given)} with --drive-from {args.drive_from}, expected neither: the "
                             "table motion that run achieved replaces the record (--duration keeps its first seconds)")


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.profile import load_profile
    from harness.runs.simulate_batch import split_list

    console = json_console(console, args.json)
    _check_drive_from(args)
    check_json_target(args.json, args.force)
    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides, overlay=args.overlay)
    check_run_length(profile, args)
    records, controllers = split_list(args.record), split_list(args.controller)
    if len(records) > 1 or len(controllers) > 1:
        return run_batch_command(args, console, profile, records, controllers)
    return run_single(args, console, profile)


def _print_study(console: Console, result: Any) -> None:
    """The record's facts, the controller's settings and the peak table of one study."""
    from harness.report.force_tracking import tracking_lines
    from harness.report.tables import reduction_table
    from harness.rig.truth import truth_summary

    motion = result.motion
    variant = f" (variant [bold]{escape(result.profile.variant)}[/])" if result.profile.variant else ""
    console.print(
        f"[bold]{result.profile.name}[/]{variant}  record [bold]{motion.name}[/]: PGA {motion.pga_g:.3f} g, "
        f"PGV {motion.pgv_m_s:.3f} m/s, PGD {motion.pgd_m * 1e3:.1f} mm, time scale {motion.time_scale:g}, "
        f"{motion.duration_s:.1f} s"
    )
    for note in getattr(motion, "notes", ()):
        console.print(f"  note: {note}")
    for warning in motion.warnings:
        console.print(f"  [bold yellow]warning:[/] {escape(warning)}", highlight=False)
    settings = result.settings
    title = (
        f"controller {result.controller_name} at {settings.rate_hz:g} Hz, friction from the "
        f"{settings.friction_source}, delay {settings.transport_delay_s * 1e3:g} ms"
    )
    if result.design_stiffness_scale != 1.0:
        title += f", design stiffness x{result.design_stiffness_scale:g}"
    if result.rig_effects:
        title += f", compensation {result.profile.control.compensation}, through the rig's sensor, actuator and safety models"
    elif result.profile.control.compensation != "none" and "controlled" in result.cases:
        console.print(f"  note: no compensation in the ideal simulation (it has no actuator); control.compensation "
                      f"{result.profile.control.compensation} applies with --rig-effects", highlight=False)
        truth_note = truth_summary(result.truth_differences())
        if truth_note:
            console.print(f"  [yellow]note: {escape(truth_note)}[/]", highlight=False)
    controlled = result.cases.get("controlled")
    if controlled is not None and controlled.extra.get("state_source", "measured") != "measured":
        console.print(f"  [yellow]note: the controller read the {controlled.extra['state_source']}[/]", highlight=False)
    if controlled is not None and result.rig_effects:
        for line in tracking_lines(result.force_tracking()):
            console.print(f"  {line}", highlight=False)
    ended = _early_end(controlled)
    if ended:
        console.print(f"{ended}: {escape(controlled.extra['trip_reason'])}")
    peaks = controlled.peaks if controlled is not None else None
    console.print(reduction_table(result.cases["passive"].peaks, peaks, title).to_rich(console.width))


def _early_end(controlled: Any) -> str:
    """``the controlled case tripped`` or ``... stopped early`` (a check's safe stop), marked up; "" if it completed."""
    outcome = controlled.extra.get("outcome") if controlled is not None else None
    if outcome == "tripped":
        return "[bold red]the controlled case tripped[/]"
    if outcome == "stopped":
        return "[yellow]the controlled case stopped early[/]"
    return ""


def run_single(args: argparse.Namespace, console: Console, profile: Any) -> int:
    """One record and one controller: the peaks side by side, and the files asked for."""
    from harness.runs.simulate import run_study

    with progress_bar(console, not args.quiet) as progress:
        tasks: dict[str, Any] = {}

        def report(case: str, fraction: float) -> None:
            if case not in tasks:
                tasks[case] = progress.add_task(case, total=1.0)
            progress.update(tasks[case], completed=fraction)

        result = run_study(profile, _study_options(args), report)
    _print_study(console, result)
    cost = sum(case.wall_time_s for case in result.cases.values())
    outcome = f"simulated {len(result.cases)} x {result.motion.duration_s:.1f} s in {cost:.2f} s of wall time"
    controlled = result.cases.get("controlled")
    ended = _early_end(controlled)
    if ended:
        outcome += f"; {ended} ({escape(controlled.extra['trip_reason'])})"  # type: ignore[union-attr]
    if args.json:
        outcome += f"; wrote {escape(write_json(args.json, result.to_json()))}"
    if args.out:
        from harness.runs.simulate_output import write_study_folders

        folder = write_study_folders(result, args.out, args.label, args.overrides)
        outcome += f"; wrote time series to {escape(str(folder))}"
    print_always(console, outcome, highlight=False, soft_wrap=True)
    return exit_codes.OK


def run_batch_command(args: argparse.Namespace, console: Console, profile: Any, records: list, controllers: list) -> int:
    """Every record with every controller: a line per study, the summary tables, and the files asked for."""
    from harness.report.tables import in_console_wording
    from harness.runs.simulate_batch import record_name, run_batch

    if "none" in controllers:
        print_always(console, "[bold red]error:[/] 'none' cannot be part of a list of controllers (every study has its "
                      "passive case); expected designs of the profile", highlight=False)
        return exit_codes.INPUT_ERROR

    with progress_bar(console, not args.quiet) as progress:
        task = progress.add_task("batch", total=len(records) * len(controllers))

        def done(study: Any, count: int, total: int) -> None:
            progress.update(task, completed=count)
            peaks = study.cases.get("controlled", study.cases["passive"]).peaks
            console.print(f"  {count}/{total}  {record_name(study)} with {study.controller_name}: peak drift "
                          f"{max(peaks.drift_m, default=0.0) * 1e3:.3f} mm, sliding "
                          f"{peaks.sliding_displacement_m * 1e3:.1f} mm", highlight=False)

        batch = run_batch(profile, _study_options(args), records, controllers, args.out, args.label, args.overrides, done)
    for table in batch.tables:
        console.print()
        console.print(in_console_wording(table).to_rich(console.width))
    cost = sum(case.wall_time_s for study in batch.studies for case in study.cases.values())
    outcome = (f"simulated {len(batch.studies)} studies ({len(records)} record{'s' if len(records) != 1 else ''} x "
               f"{len(controllers)} controller{'s' if len(controllers) != 1 else ''}) in {cost:.2f} s of wall time")
    if args.json:
        outcome += f"; wrote {escape(write_json(args.json, {'runs': [study.to_json() for study in batch.studies]}))}"
    if args.out:
        outcome += (f"; wrote {len(batch.folders)} case sets and the summary tables (summary_peaks.csv, "
                    f"summary_reduction.csv, summary.txt) to {escape(str(args.out))}")
    print_always(console, outcome, highlight=False, soft_wrap=True)
    return exit_codes.OK
