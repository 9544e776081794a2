"""``harness simulate``: offline simulation, passive and controlled side by side."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    DELAY,
    EPILOG,
    RATE,
    STIFFNESS_SCALE,
    add_overrides,
    add_record_options,
    non_empty,
    number_in,
    output_dir,
    output_file,
    study_options,
    wrap,
)
from harness.commands.output import progress_bar


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "simulate",
        help="offline simulation, passive and controlled side by side",
        description=wrap(
            "Simulate the profile's building on its bearings under the record, once passive "
            "(bearings only) and once with the controller, faster than real time, and print the "
            "peak responses with the %% reduction. The controller samples at --rate and holds its "
            "force until the next sample (SPEC 3)."
        ),
        epilog="example:\n  harness simulate profiles/eight_story.yaml --record el_centro --pga 0.3 "
        "--duration 30 --controller FSF-I --json out.json\n\n" + EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("profile", nargs="?", help="profile YAML (default: profiles/nceer_4dof.yaml)")
    add_overrides(parser, "control.designs.phi.p1_per_s=8.0")
    add_record_options(parser)
    control = parser.add_argument_group("control")
    control.add_argument("--controller", type=non_empty, metavar="NAME|none", help="a design of the profile, or 'none' (passive only)")
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
    output = parser.add_argument_group("output")
    output.add_argument("--json", type=output_file, metavar="PATH", help="write peaks and record facts as JSON (SI units)")
    output.add_argument("--out", type=output_dir, metavar="DIR", help="save both cases' time series as run folders in DIR")
    output.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.profile import load_profile
    from harness.report.tables import reduction_table
    from harness.runs.simulate import run_study

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides)
    options = study_options(
        args, controller=args.controller, rate_hz=args.rate, friction=args.friction, transport_delay_s=args.delay,
        design_stiffness_scale=args.design_stiffness_scale, rig_effects=args.rig_effects,
    )
    with progress_bar(console, not args.quiet) as progress:
        tasks: dict[str, int] = {}

        def report(case: str, fraction: float) -> None:
            if case not in tasks:
                tasks[case] = progress.add_task(case, total=1.0)
            progress.update(tasks[case], completed=fraction)

        result = run_study(profile, options, report)
    motion = result.motion
    console.print(
        f"[bold]{profile.name}[/]  record [bold]{motion.name}[/]: PGA {motion.pga_g:.3f} g, "
        f"PGV {motion.pgv_m_s:.3f} m/s, PGD {motion.pgd_m * 1e3:.1f} mm, time scale {motion.time_scale:g}, "
        f"{motion.duration_s:.1f} s"
    )
    for note in getattr(motion, "notes", ()):
        console.print(f"  note: {note}")
    controlled = result.cases.get("controlled")
    settings = result.settings
    title = (
        f"controller {result.controller_name} at {settings.rate_hz:g} Hz, friction from the "
        f"{settings.friction_source}, delay {settings.transport_delay_s * 1e3:g} ms"
    )
    if result.design_stiffness_scale != 1.0:
        title += f", design stiffness x{result.design_stiffness_scale:g}"
    if result.rig_effects:
        title += ", through the rig's sensor, actuator and safety models"
    twin = result.cases.get("controlled")
    if twin is not None and twin.extra.get("outcome") == "tripped":
        console.print(f"[bold red]the controlled case tripped:[/] {escape(twin.extra['trip_reason'])}")
    console.print(reduction_table(result.cases["passive"].peaks, controlled.peaks if controlled else None, title).to_rich())
    cost = sum(case.wall_time_s for case in result.cases.values())
    console.print(f"simulated {len(result.cases)} x {motion.duration_s:.1f} s in {cost:.2f} s of wall time")
    if args.json:
        result.write_json(args.json)
        console.print(f"wrote {args.json}")
    if args.out:
        from harness.runs.simulate_output import write_study_folders

        folder = write_study_folders(result, args.out)
        console.print(f"wrote time series to {folder}")
    return exit_codes.OK
