"""The rig's peaks on its three records, in the layout of the source's experimental tables.

For El Centro (0.34 g), Hachinohe (0.23 g) and Pacoima (0.40 g), each with its time axis
compressed by 2 and run for 30 s, it simulates the quarter-scale rig of
``profiles/nceer_4dof.yaml`` passive (bearings only) and with the profile's controller
(the phi controller, Eq. 22-23), exactly as ``harness simulate`` does, and prints one
table: a row per response, and per record the passive peak, the controlled peak and the
% reduction (SPEC 5), with the peak control force U in % of the total weight.

With ``--dry-runs`` it prints instead the source's experimental table as a dry run would
predict it (issue 20): for each record, ideal control (``harness simulate``), a lockstep dry
run on the force-source rig of earlier versions (first-order actuator, table a motion source)
and a lockstep dry run on the servo-hydraulic rig (the shipped default): drift reduction per
story, floor and base-mat acceleration reduction, sliding displacement over passive, and the
peak force in % of the weight. Every reduction is against the same ideal passive simulation.

With ``--feedforward`` it compares the servo controller's velocity feed-forward (issue 31) on the
lockstep twin; with ``--feedforward --dry-runs`` as dry runs over the bus, the feed-forward rig with
the harness's ``model`` compensation added as a third column, lockstep or (``--real-time``) real time.

Usage: python benchmarks/rig_table.py [--records-dir DIR] [--rig-effects] [--dry-runs] [--feedforward]
       [--real-time] [--set KEY=VALUE ...] [--markdown]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from rich.console import Console  # noqa: E402
from rich.table import Table  # noqa: E402

from harness.profile import load_profile  # noqa: E402
from harness.runs.dry_run import DryRunOptions, dry_run  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study  # noqa: E402
from harness.signals.peaks import reduction_pct  # noqa: E402

#: Ideal control: the column that is a simulation, not a dry run.
IDEAL = "ideal"
#: The columns of the dry-run table: (name, the profile's variant for the lockstep dry run). The
#: profile's ``force_source`` variant is the rig of earlier versions; no variant is the shipped rig.
PREDICTIONS: tuple[tuple[str, str | None], ...] = ((IDEAL, None), ("force source", "force_source"),
                                                   ("servo-hydraulic", None))
#: Rows of the dry-run table: (flattened peak key, label).
PREDICTED = (
    ("drift_1_m", "story 1 drift reduction %"),
    ("drift_2_m", "story 2 drift reduction %"),
    ("drift_3_m", "story 3 drift reduction %"),
    ("floor_acceleration_1_m_s2", "floor 1 acceleration reduction %"),
    ("floor_acceleration_2_m_s2", "floor 2 acceleration reduction %"),
    ("floor_acceleration_3_m_s2", "floor 3 acceleration reduction %"),
    ("base_acceleration_m_s2", "base mat acceleration reduction %"),
)

#: The rig's records and their peak table accelerations (g), SPEC 6b.
RIG_RECORDS = (("el_centro", 0.34), ("hachinohe", 0.23), ("pacoima", 0.40))

#: Rows of the table: (flattened peak key, label, unit, scale from SI, digits).
ROWS = (
    ("sliding_displacement_m", "sliding displacement x_b", "mm", 1e3, 1),
    ("drift_1_m", "story 1 drift", "mm", 1e3, 2),
    ("drift_2_m", "story 2 drift", "mm", 1e3, 2),
    ("drift_3_m", "story 3 drift", "mm", 1e3, 2),
    ("base_acceleration_m_s2", "base mat acceleration", "m/s²", 1.0, 2),
    ("floor_acceleration_1_m_s2", "floor 1 acceleration", "m/s²", 1.0, 2),
    ("floor_acceleration_2_m_s2", "floor 2 acceleration", "m/s²", 1.0, 2),
    ("floor_acceleration_3_m_s2", "floor 3 acceleration", "m/s²", 1.0, 2),
)


def rig_peaks(profile_path: Path, records_dir: str, rig_effects: bool, overrides: list[str]) -> dict:
    """Passive and controlled flattened peaks (SI) per record name, simulated as ``harness simulate`` does."""
    profile = load_profile(profile_path, overrides=overrides)
    results = {}
    for record, pga_g in RIG_RECORDS:
        options = StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0,
                               duration_s=30.0, rig_effects=rig_effects)
        study = run_study(profile, options)
        results[record] = {case: result.peaks.flatten() for case, result in study.cases.items()}
    return results


def cells(passive: float, controlled: float, scale: float, digits: int) -> list[str]:
    """Passive, controlled and % reduction of one response, formatted."""
    reduction = reduction_pct(passive, controlled)
    return [f"{passive * scale:.{digits}f}", f"{controlled * scale:.{digits}f}",
            "-" if reduction is None else f"{reduction:.0f}"]


def table_rows(results: dict) -> list[list[str]]:
    """One list of cells per response row, then the control force row."""
    rows = []
    for key, label, unit, scale, digits in ROWS:
        row = [label, unit]
        for record, _ in RIG_RECORDS:
            row += cells(results[record]["passive"][key], results[record]["controlled"][key], scale, digits)
        rows.append(row)
    force = ["control force U", "% W"]
    for record, _ in RIG_RECORDS:
        force += ["0", f"{results[record]['controlled']['peak_force_pct_weight']:.1f}", ""]
    rows.append(force)
    return rows


def headers() -> list[str]:
    """Column headers: response, unit, then passive / controlled / reduction per record."""
    names = ["response", "unit"]
    for record, pga_g in RIG_RECORDS:
        names += [f"{record} {pga_g:.2f} g passive", f"{record} controlled", f"{record} reduction %"]
    return names


def print_markdown(rows: list[list[str]], names: list[str] | None = None) -> None:
    """The table as GitHub markdown, for benchmarks/README.md."""
    names = names or headers()
    print("| " + " | ".join(names) + " |")
    print("|" + "---|" * len(names))
    for row in rows:
        print("| " + " | ".join(row) + " |")


def print_rich(rows: list[list[str]], title: str) -> None:
    """The table in the terminal."""
    table = Table(title=title, title_justify="left")
    for i, name in enumerate(headers()):
        table.add_column(name, justify="left" if i < 2 else "right")
    for row in rows:
        table.add_row(*row)
    Console(width=200).print(table)


def predictions(profile_path: Path, records_dir: str, overrides: list[str], log_dir: str) -> dict:
    """Per record: the ideal passive peaks, and the controlled peaks of each column of :data:`PREDICTIONS`."""
    results: dict = {}
    for record, pga_g in RIG_RECORDS:
        options = StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0, duration_s=30.0)
        ideal = run_study(load_profile(profile_path, overrides=overrides), options)
        results[record] = {"passive": ideal.cases["passive"].peaks.flatten()}
        for name, variant in PREDICTIONS:
            if name == IDEAL:
                results[record][name] = ideal.cases["controlled"].peaks.flatten()
                continue
            profile = load_profile(profile_path, variant=variant, overrides=overrides)
            run = dry_run(profile, DryRunOptions(study=options, lockstep=True, show_console=False, compare=False,
                                                 log_dir=log_dir))
            outcome = run.session.outcome
            print(f"{record} {name}: {outcome}", file=sys.stderr)
            results[record][name] = {**run.peaks.flatten(), "outcome": str(outcome)}
    return results


def prediction_rows(results: dict) -> list[list[str]]:
    """One row per predicted quantity: its label, then per record the value of each column."""
    rows = []
    for key, label in PREDICTED:
        row = [label]
        for record, _ in RIG_RECORDS:
            passive = results[record]["passive"][key]
            for name, _ in PREDICTIONS:
                reduction = reduction_pct(passive, results[record][name][key])
                row.append("-" if reduction is None else f"{reduction:.0f}")
        rows.append(row)
    ratio, force, outcome = ["sliding displacement / passive"], ["peak force % W"], ["outcome"]
    for record, _ in RIG_RECORDS:
        passive = results[record]["passive"]["sliding_displacement_m"]
        for name, _ in PREDICTIONS:
            peaks = results[record][name]
            ratio.append(f"{peaks['sliding_displacement_m'] / passive:.2f}")
            force.append(f"{peaks['peak_force_pct_weight']:.1f}")
            outcome.append(peaks.get("outcome", "-").split(".")[-1].lower())
    return [*rows, ratio, force, outcome]


def prediction_headers() -> list[str]:
    """Column headers of the dry-run table."""
    return ["quantity", *(f"{record} {pga_g:.2f} g: {name}" for record, pga_g in RIG_RECORDS for name, _ in PREDICTIONS)]


#: The columns of the feed-forward table (issue 31): (name, overrides of the lockstep twin's profile), after ideal control.
#: The plain loop expects the plain loop's bleed (k_h / w_f, 94 kN s/m) in its tracking check.
FEEDFORWARD_COLUMNS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("rig, no feed-forward", ("rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0")),
    ("rig, feed-forward", ()),
)


def _ideal(profile_path: Path, records_dir: str, overrides: list[str], record: str, pga_g: float
           ) -> tuple[StudyOptions, dict]:
    """A record's study options (time scale 2, 30 s) and its ideal passive and controlled peaks."""
    options = StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0, duration_s=30.0)
    ideal = run_study(load_profile(profile_path, overrides=overrides), options)
    return options, {"passive": ideal.cases["passive"].peaks.flatten(), IDEAL: ideal.cases["controlled"].peaks.flatten()}


def feedforward_results(profile_path: Path, records_dir: str, overrides: list[str]) -> dict:
    """Per record: ideal passive and controlled peaks, and each :data:`FEEDFORWARD_COLUMNS` case on the lockstep twin.

    The twin (``harness simulate --rig-effects``) is the virtual rig's plant, actuator, sensors and
    supervisor in lockstep (tests/integration/test_lockstep_equivalence.py holds it to a lockstep dry run).
    """
    results: dict = {}
    for record, pga_g in RIG_RECORDS:
        options, results[record] = _ideal(profile_path, records_dir, overrides, record, pga_g)
        for name, extra in FEEDFORWARD_COLUMNS:
            profile = load_profile(profile_path, overrides=[*overrides, *extra])
            study = run_study(profile, dataclasses.replace(options, rig_effects=True))
            case = study.cases["controlled"]
            tracked = study.force_tracking()["command"]
            results[record][name] = {**case.peaks.flatten(), "outcome": case.extra.get("outcome", "-"),
                                     "delay_ms": math.nan if tracked is None else tracked.delay_s * 1e3,
                                     "rms_pct": math.nan if tracked is None else tracked.rms_error_percent}
            print(f"{record} {name}: {case.extra.get('outcome')} {case.extra.get('trip_reason') or ''}", file=sys.stderr)
    return results


#: The columns of the feed-forward dry runs (issue 31, lockstep or real time): the twin's two, then the
#: feed-forward rig with the harness's own compensation (``model``: ``adaptive`` is not yet usable on it).
FEEDFORWARD_DRY_RUN_COLUMNS: tuple[tuple[str, tuple[str, ...]], ...] = (
    *FEEDFORWARD_COLUMNS,
    ("rig, feed-forward + model compensation", ("control.compensation=model",)),
)


def _tracking_cells(run_path: Path, record_start_s: float | None, duration_s: float) -> dict:
    """Force-tracking delay (ms) and RMS error (%) of a dry run's load cell against the command sent, over the record.

    A delay at the search's limit (:data:`~harness.report.force_tracking.MAX_LAG_S`) is no delay found: the
    table prints it as such.
    """
    from harness.recording import load_run
    from harness.report.force_tracking import run_force_tracking

    start_s = -math.inf if record_start_s is None else record_start_s
    tracked = run_force_tracking(load_run(run_path).signals, asked="force_command_N", start_s=start_s,
                                 end_s=start_s + duration_s)
    return {"delay_ms": math.nan if tracked is None else tracked.delay_s * 1e3,
            "rms_pct": math.nan if tracked is None else tracked.rms_error_percent}


#: Runs of one real-time column at most: the first and those the pre-flight refused (nothing moved).
MAX_RUNS = 5


def _dry_run_past_the_preflight(profile, options: DryRunOptions):
    """A dry run, run again while the pre-flight refuses it (a busy second of the host; never a bound loosened)."""
    from harness.loop.preflight import HostTimingRefused

    for attempt in range(1, MAX_RUNS + 1):
        try:
            return dry_run(profile, options)
        except HostTimingRefused as refused:
            print(f"  refused by the pre-flight (run {attempt} of {MAX_RUNS}): {refused}", file=sys.stderr)
    raise SystemExit(f"the pre-flight refused {MAX_RUNS} runs: this host is too busy for real-time dry runs now")


def feedforward_dry_run_results(profile_path: Path, records_dir: str, overrides: list[str], log_dir: str,
                                lockstep: bool) -> dict:
    """Per record: ideal passive and controlled peaks, and each :data:`FEEDFORWARD_DRY_RUN_COLUMNS` case as a dry run.

    The dry runs go through the whole path, the virtual rig in its own process over the default bus;
    ``lockstep`` False runs them in real time (the pre-flight judges the host before each; a refusal is
    run again, up to :data:`MAX_RUNS` runs, after which the table is not made).
    """
    results: dict = {}
    for record, pga_g in RIG_RECORDS:
        options, results[record] = _ideal(profile_path, records_dir, overrides, record, pga_g)
        for name, extra in FEEDFORWARD_DRY_RUN_COLUMNS:
            profile = load_profile(profile_path, overrides=[*overrides, *extra])
            run = _dry_run_past_the_preflight(profile, DryRunOptions(
                study=options, lockstep=lockstep, show_console=False, compare=False, log_dir=log_dir))
            outcome = str(run.session.outcome).split(".")[-1].lower()
            trip = getattr(run.session, "trip_reason", "") or ""
            results[record][name] = {**run.peaks.flatten(), "outcome": f"{outcome} {trip}".strip(),
                                     **_tracking_cells(run.session.run_path, run.session.loop.record_start_t_s,
                                                       options.duration_s)}
            print(f"{record} {name}: {outcome} {trip}", file=sys.stderr)
    return results


def _delay_cell(delay_ms: float | None) -> str:
    """A force-tracking delay (ms) for the table: ``-`` where none was measured, ``none within N`` at the search's limit."""
    from harness.report.force_tracking import MAX_LAG_S

    if delay_ms is None or math.isnan(delay_ms):
        return "-"
    if abs(delay_ms) >= MAX_LAG_S * 1e3 - 1e-6:
        return f"none within {MAX_LAG_S * 1e3:.0f}"
    return f"{delay_ms:.1f}"


def feedforward_rows(results: dict, columns: tuple[tuple[str, tuple[str, ...]], ...] = FEEDFORWARD_COLUMNS
                     ) -> list[list[str]]:
    """One row per quantity: per record, ideal control then each feed-forward column."""
    names = [IDEAL, *(name for name, _ in columns)]
    rows = []
    for key, label in PREDICTED:
        row = [label]
        for record, _ in RIG_RECORDS:
            passive = results[record]["passive"][key]
            for name in names:
                reduction = reduction_pct(passive, results[record][name][key])
                row.append("-" if reduction is None else f"{reduction:.0f}")
        rows.append(row)
    extra_rows = [["sliding displacement / passive"], ["peak force % W"], ["force-tracking delay ms (command)"],
                  ["force-tracking RMS error % (command)"], ["outcome"]]
    for record, _ in RIG_RECORDS:
        passive = results[record]["passive"]["sliding_displacement_m"]
        for name in names:
            peaks = results[record][name]
            extra_rows[0].append(f"{peaks['sliding_displacement_m'] / passive:.2f}")
            extra_rows[1].append(f"{peaks['peak_force_pct_weight']:.1f}")
            extra_rows[2].append(_delay_cell(peaks.get("delay_ms")))
            extra_rows[3].append(f"{peaks['rms_pct']:.0f}" if "rms_pct" in peaks else "-")
            extra_rows[4].append(str(peaks.get("outcome", "-")))
    return [*rows, *extra_rows]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--profile", default=str(REPO / "profiles" / "nceer_4dof.yaml"))
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"),
                        help="folder with el_centro, hachinohe and pacoima (default ../shared/data/ground_motions)")
    parser.add_argument("--rig-effects", action="store_true",
                        help="controlled case through the rig's sensor, actuator and safety models")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
                        help="override a profile value, e.g. control.designs.phi.p1_per_s=0.315")
    parser.add_argument("--markdown", action="store_true", help="print markdown instead of a rich table")
    parser.add_argument("--dry-runs", action="store_true",
                        help="ideal control against lockstep dry runs on the force-source and the servo-hydraulic rig")
    parser.add_argument("--log-dir", default=None, help="where the dry runs' folders go (default: a temporary folder)")
    parser.add_argument("--feedforward", action="store_true",
                        help="ideal control against the lockstep twin without and with the servo controller's feed-forward")
    parser.add_argument("--real-time", action="store_true",
                        help="with --feedforward --dry-runs: the dry runs in real time instead of lockstep")
    args = parser.parse_args()
    if args.feedforward and args.dry_runs:
        columns = FEEDFORWARD_DRY_RUN_COLUMNS
        names = [IDEAL, *(name for name, _ in columns)]
        with tempfile.TemporaryDirectory() as scratch:
            results = feedforward_dry_run_results(Path(args.profile), args.records_dir, args.overrides,
                                                  args.log_dir or scratch, lockstep=not args.real_time)
            rows = feedforward_rows(results, columns)
        print_markdown(rows, ["quantity", *(f"{record} {pga:.2f} g: {name}" for record, pga in RIG_RECORDS
                                            for name in names)])
        return 0
    if args.feedforward:
        names = [IDEAL, *(name for name, _ in FEEDFORWARD_COLUMNS)]
        print_markdown(feedforward_rows(feedforward_results(Path(args.profile), args.records_dir, args.overrides)),
                       ["quantity", *(f"{record} {pga:.2f} g: {name}" for record, pga in RIG_RECORDS for name in names)])
        return 0
    if args.dry_runs:
        with tempfile.TemporaryDirectory() as scratch:
            rows = prediction_rows(predictions(Path(args.profile), args.records_dir, args.overrides, args.log_dir or scratch))
        print_markdown(rows, prediction_headers())
        return 0
    results = rig_peaks(Path(args.profile), args.records_dir, args.rig_effects, args.overrides)
    rows = table_rows(results)
    if args.markdown:
        print_markdown(rows)
    else:
        kind = "rig effects" if args.rig_effects else "ideal control"
        print_rich(rows, f"peak responses of the rig, passive and controlled ({kind}), time scale 2, 30 s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
