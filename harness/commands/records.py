"""``harness records``: list the ground-motion records, or show one: raw and processed, its spectrum, the table's fit."""

from __future__ import annotations

import argparse
import textwrap
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.table import Table

from harness import exit_codes
from harness.commands.options import (
    DURATION,
    PGA,
    RECORD_DURATION_HELP,
    SIMULATE_EPILOG,
    TIME_SCALE,
    add_overrides,
    non_empty,
    number_in,
    output_file,
    profile_path,
    study_options,
    wrap,
)

#: Periods at which the response spectrum is printed (s, in the processed motion's time).
SPECTRUM_PERIODS_S = (0.1, 0.2, 0.3, 0.5, 1.0, 2.0, 3.0)
#: ``--plot`` without a file: ``<record>_motion.png`` in the working directory.
DEFAULT_PLOT = ""


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "records",
        help="list ground-motion records, or show one after processing",
        description=wrap(
            "With no NAME, list the named records and whether their files are in the records "
            "directory. With a NAME or PATH, process it as a run would (time scale, duration, PGA, "
            "baseline correction) and show PGA, PGV, PGD, duration, Arias intensity, significant "
            "duration, periods, the 5 %-damped response spectrum, and whether it fits the table: a "
            "record that exceeds the table's limits is still shown, with the largest PGA that fits "
            "(exit status 2). --plot writes a PNG of the raw record beside the processed motion and "
            "both response spectra (default file: NAME_motion.png)."
        ),
        epilog="examples:\n  harness records --records-dir ../shared/data/ground_motions\n"
        "  harness records el_centro --records-dir ../shared/data/ground_motions --pga 0.34 --time-scale 2 --plot\n\n"
        + SIMULATE_EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("record", nargs="?", metavar="NAME|PATH")
    parser.add_argument("--profile", type=profile_path, help="take scaling and the table's limits from this profile "
                        "(a file or a shipped profile's name)")
    add_overrides(parser, "table.stroke_limit_m=0.1")
    parser.add_argument("--records-dir", type=non_empty, metavar="DIR", help="where named records are found")
    parser.add_argument("--pga", type=number_in(PGA), metavar="G", help=f"scale to this PGA (g), {PGA.describe()}")
    parser.add_argument("--time-scale", type=number_in(TIME_SCALE), metavar="F",
                        help=f"compress time by F, {TIME_SCALE.describe()}")
    parser.add_argument("--duration", type=number_in(DURATION), metavar="S",
                        help=f"cut to this length (s), {DURATION.describe()}{RECORD_DURATION_HELP}")
    parser.add_argument("--plot", nargs="?", const=DEFAULT_PLOT, type=_plot_file, metavar="PNG",
                        help="write a plot of the raw and processed motion and their spectra (default: NAME_motion.png)")
    parser.set_defaults(handler=run)


def _plot_file(text: str) -> str:
    return output_file(text) if text else text


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.profile import load_profile

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides, overlay=args.overlay)
    if args.record is None:
        return list_command(args, console, profile)
    return show_command(args, console, profile)


#: Narrowest the description column of the records table may get before the list is printed as lines (characters).
MIN_DESCRIPTION_WIDTH = 30


def list_command(args: argparse.Namespace, console: Console, profile: Any) -> int:
    """The named records, whether each is in the records directory, and other record files found there.

    Names and file names are never cut (a user types them): where a table with them does not fit
    the terminal, each record takes two lines instead.
    """
    from harness.motions import list_records, records_dir_from

    directory = records_dir_from(args.records_dir, profile.record.records_dir, base_dir=profile.base_dir)
    listing = list_records(directory)
    console.print(f"[bold]records in {escape(str(directory))}[/]" if directory else "[bold]records[/] (no records "
                  "directory set)", soft_wrap=True)
    rows = [(item.name, "yes" if item.available else "no", item.path.name if item.path else "-", item.description)
            for item in listing]
    fixed = sum(max(len(row[i]) for row in rows) for i in range(3)) + 3 * 3 + 4
    if fixed + MIN_DESCRIPTION_WIDTH <= console.width:
        console.print(_records_table(rows))
    else:
        for name, here, file, description in rows:
            style = "green" if here == "yes" else "red"
            console.print(f"  [bold]{escape(name)}[/]  [{style}]{here}[/]  {escape(file)}", soft_wrap=True, highlight=False)
            for line in textwrap.wrap(description, max(20, console.width - 6)):
                console.print(f"      {escape(line)}", highlight=False)
    if not directory:
        console.print("Set the directory with --records-dir, $HARNESS_RECORDS_DIR or the profile's record.records_dir.")
    return exit_codes.OK


def _records_table(rows: list[tuple[str, str, str, str]]) -> Table:
    from rich import box

    table = Table(box=box.SIMPLE_HEAD, pad_edge=False, show_edge=False)
    table.add_column("name", no_wrap=True, style="bold")
    table.add_column("here", no_wrap=True)
    table.add_column("file", no_wrap=True)
    table.add_column("description", min_width=MIN_DESCRIPTION_WIDTH)
    for name, here, file, description in rows:
        table.add_row(escape(name), here if here == "yes" else f"[red]{here}[/]", escape(file), escape(description))
    return table


def _facts_table(motion: Any, profile: Any) -> Table:
    from harness.motions import summarize

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
    return table


def _spectrum_table(raw: Any, motion: Any) -> Table:
    """Sa (g) of the processed motion and of the raw record at a few periods, and each one's peak."""
    from harness.motions import G_M_S2, response_spectrum

    table = Table(title="5 %-damped pseudo-acceleration Sa (g)", title_justify="left")
    table.add_column("period T (s)", justify="right")
    table.add_column("processed", justify="right")
    table.add_column("raw record", justify="right")
    processed, original = response_spectrum(motion.accel_m_s2, motion.dt_s), response_spectrum(raw.accel_m_s2, raw.dt_s)
    for period in SPECTRUM_PERIODS_S:
        table.add_row(f"{period:g}", f"{processed.sa_at(period) / G_M_S2:.3f}", f"{original.sa_at(period) / G_M_S2:.3f}")
    (peak, at), (raw_peak, raw_at) = processed.peak(), original.peak()
    table.add_row("peak", f"{peak / G_M_S2:.3f} at {at:.2f} s", f"{raw_peak / G_M_S2:.3f} at {raw_at:.2f} s")
    return table


def _fit(console: Console, motion: Any, profile: Any) -> bool:
    """Say whether the motion fits the profile's table, and the largest PGA that does; True if it fits."""
    from harness.motions import largest_fitting_pga_g, table_excesses

    table = profile.table
    if table is None:
        console.print(f"{profile.name} has no table section: no limits to check")
        return True
    limits = (f"stroke ±{table.stroke_limit_m * 1e3:.0f} mm, {table.velocity_limit_m_s:g} m/s, "
              f"{table.acceleration_limit_g:g} g")
    largest, binding = largest_fitting_pga_g(motion, table)
    excesses = table_excesses(motion, table)
    if not excesses:
        console.print(f"fits the table of {profile.name} ({limits}); the largest PGA that fits is {largest:.3f} g "
                      f"(set by the {binding} limit)")
        return True
    for excess in excesses:
        console.print(f"[bold red]exceeds[/] the table's {escape(excess.limit)}: needs {excess.needed:.4g} {excess.unit}, "
                      f"the table has {excess.available:.4g} {excess.unit}", highlight=False)
    console.print(f"the largest PGA that fits the table of {profile.name} ({limits}) at this time scale is "
                  f"[bold]{largest:.3f} g[/] (set by the {binding} limit): --pga {largest * 0.999:.3f}", highlight=False)
    return False


def show_command(args: argparse.Namespace, console: Console, profile: Any) -> int:
    """One record after processing: facts, spectrum, table fit, notes, and the plot if asked."""
    from harness.motions.loading import load_raw_and_motion
    from harness.runs.options import resolve_profile

    resolved = resolve_profile(profile, study_options(args))
    record = resolved.record
    raw, motion = load_raw_and_motion(record, base_dir=resolved.base_dir, records_dir_flag=record.records_dir)
    console.print(_facts_table(motion, profile))
    console.print(_spectrum_table(raw, motion))
    for note in motion.notes:
        console.print(f"  note: {escape(note)}")
    for warning in motion.warnings:
        console.print(f"  [bold yellow]warning:[/] {escape(warning)}", highlight=False)
    fits = _fit(console, motion, resolved)
    if args.plot is not None:
        from harness.recording.metadata import safe_name
        from harness.report.motion_plot import motion_plot

        path = Path(args.plot or f"{safe_name(motion.name)}_motion.png")
        plot = motion_plot(motion, path, raw=raw, table=resolved.table)
        console.print(f"wrote {plot.path}")
    return exit_codes.OK if fits else exit_codes.INPUT_ERROR
