"""``harness records``: list the ground-motion records, or show one after processing."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    DURATION,
    EPILOG,
    PGA,
    TIME_SCALE,
    add_overrides,
    non_empty,
    number_in,
    output_file,
    study_options,
    wrap,
)


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "records",
        help="list ground-motion records, or show one after processing",
        description=wrap(
            "With no NAME, list the named records and whether their files are in the records "
            "directory. With a NAME or PATH, process it as a run would (time scale, duration, PGA, "
            "baseline correction) and show PGA, PGV, PGD, duration, Arias intensity, significant "
            "duration and periods; --plot writes a PNG of acceleration, velocity and displacement."
        ),
        epilog="example:\n  harness records el_centro --records-dir ../shared/data/ground_motions --pga 0.34 "
        "--time-scale 2 --plot el_centro.png\n\n" + EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("record", nargs="?", metavar="NAME|PATH")
    parser.add_argument("--profile", type=non_empty, help="take scaling and the table's limits from this profile")
    add_overrides(parser, "table.stroke_limit_m=0.1")
    parser.add_argument("--records-dir", type=non_empty, metavar="DIR", help="where named records are found")
    parser.add_argument("--pga", type=number_in(PGA), metavar="G", help=f"scale to this PGA (g), {PGA.describe()}")
    parser.add_argument("--time-scale", type=number_in(TIME_SCALE), metavar="F", help=f"compress time by F, {TIME_SCALE.describe()}")
    parser.add_argument("--duration", type=number_in(DURATION), metavar="S", help=f"cut to this length (s), {DURATION.describe()}")
    parser.add_argument("--plot", type=output_file, metavar="PNG", help="write a plot of the processed motion")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from rich.table import Table

    from harness.motions import list_records, records_dir_from, summarize
    from harness.profile import load_profile
    from harness.runs.simulate import prepare_motion

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides)
    if args.record is None:
        directory = records_dir_from(args.records_dir, profile.record.records_dir, base_dir=profile.base_dir)
        table = Table(title=f"records in {directory or '(no records directory set)'}", title_justify="left")
        for column in ("name", "available", "file", "description"):
            table.add_column(column)
        for item in list_records(directory):
            table.add_row(item.name, "yes" if item.available else "[red]no[/]", str(item.path or "-"), item.description)
        console.print(table)
        console.print("Set the directory with --records-dir, $HARNESS_RECORDS_DIR or the profile's record.records_dir.")
        return exit_codes.OK
    motion = prepare_motion(profile, study_options(args))
    facts = summarize(motion)
    table = Table(title=f"{motion.name} after processing ({profile.name})", title_justify="left")
    table.add_column("quantity")
    table.add_column("value", justify="right")
    rows = [
        ("PGA", f"{facts.pga_g:.4f} g"), ("PGV", f"{facts.pgv_m_s:.4f} m/s"), ("PGD", f"{facts.pgd_m * 1e3:.2f} mm"),
        ("duration", f"{facts.duration_s:.2f} s"), ("time step", f"{facts.dt_s * 1e3:.3f} ms"),
        ("time scale", f"{motion.time_scale:g}"), ("Arias intensity", f"{facts.arias_intensity_m_s:.4f} m/s"),
        ("significant duration (5-95 %)", f"{facts.significant_duration_s:.2f} s ({facts.t5_s:.2f}-{facts.t95_s:.2f} s)"),
        ("predominant period", f"{facts.predominant_period_s:.3f} s"), ("mean period", f"{facts.mean_period_s:.3f} s"),
    ]
    for name, value in rows:
        table.add_row(name, value)
    console.print(table)
    for note in motion.notes:
        console.print(f"  note: {escape(note)}")
    if profile.table is not None:
        console.print(f"fits the table of {profile.name} (stroke {profile.table.stroke_limit_m * 1e3:.0f} mm, "
                      f"{profile.table.velocity_limit_m_s:g} m/s, {profile.table.acceleration_limit_g:g} g)")
    if args.plot:
        from harness.report.motion_plot import motion_plot

        plot = motion_plot(motion, args.plot)
        console.print(f"wrote {plot.path}")
    return exit_codes.OK
