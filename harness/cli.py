"""The ``harness`` command line: argument parsing and console output only; the work is elsewhere."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
import textwrap
from collections.abc import Callable, Sequence
from pathlib import Path

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from harness import exit_codes
from harness import input_limits as limits
from harness.errors import HarnessError

EPILOG = """\
exit status:
  0  completed            3  tripped safely (force zeroed, drive disabled), or
  1  internal error (bug)     completed but the record was lost (repeat the test)
  2  bad input or refused configuration, before anything moved
  4  stopped early by the operator (safe stop)

records: a NAME (el_centro, el_centro_classic, hachinohe, pacoima, synthetic,
synthetic:SEED) is looked up in --records-dir, else $HARNESS_RECORDS_DIR, else the
profile's record.records_dir; a PATH (.AT2, .csv, .txt) is read directly.
"""


def _wrap(text: str) -> str:
    """Wrap a description to the terminal's usual width (the formatter keeps it as given)."""
    return textwrap.fill(text, width=78)


# Ranges of the numeric options; harness/input_limits.py gives the reason for each bound.
RATE = limits.NumberRange(0.0, limits.MAX_RATE_HZ, "Hz")
PGA = limits.NumberRange(0.0, limits.MAX_PGA_G, "g")
TIME_SCALE = limits.NumberRange(limits.MIN_TIME_SCALE, limits.MAX_TIME_SCALE, low_open=False)
DURATION = limits.NumberRange(0.0, limits.MAX_DURATION_S, "s")
DELAY = limits.NumberRange(0.0, limits.MAX_DELAY_S, "s", low_open=False)
STIFFNESS_SCALE = limits.NumberRange(limits.MIN_STIFFNESS_SCALE, limits.MAX_STIFFNESS_SCALE, low_open=False)
SEED = limits.NumberRange(0, limits.MAX_SEED, low_open=False, integer=True)
PID = limits.NumberRange(1, limits.MAX_PID, low_open=False, integer=True)


def _in(allowed: limits.NumberRange) -> Callable[[str], float | int]:
    """An argparse ``type=`` that parses a number and refuses it outside ``allowed``.

    argparse then exits with status 2 and ``argument --rate: found -500 Hz, expected a number
    of Hz in (0, 5000]``.
    """

    def parse(text: str) -> float | int:
        try:
            return allowed.check(text)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    return parse


def _non_empty(text: str) -> str:
    """An argparse ``type=`` for a name or path that must not be blank (``--record ""`` is a mistake)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty value, expected a name or a path")
    return text


def _output_file(text: str) -> str:
    """An argparse ``type=`` for a file the command writes: not a directory, in an existing directory."""
    path = Path(text).expanduser()
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty path, expected a file name to write")
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a directory, expected a file name to write")
    if not path.parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: its directory {path.parent} does not exist, expected an existing directory")
    return text


def _output_dir(text: str) -> str:
    """An argparse ``type=`` for a directory the command writes into (created if missing): not a file."""
    path = Path(text).expanduser()
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty path, expected a directory")
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file, expected a directory (existing or to be created)")
    return text


def _add_record_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("record (overrides the profile's record section)")
    group.add_argument("--record", type=_non_empty, metavar="NAME|PATH", help="record name or file (default: the profile's)")
    group.add_argument("--records-dir", type=_non_empty, metavar="DIR", help="where named records are found")
    group.add_argument("--pga", type=_in(PGA), metavar="G", help=f"scale to this peak table acceleration (g), {PGA.describe()}")
    group.add_argument("--time-scale", type=_in(TIME_SCALE), metavar="F",
                       help=f"compress time by F (2 = twice the frequency), {TIME_SCALE.describe()}")
    group.add_argument("--duration", type=_in(DURATION), metavar="S", help=f"run length (s), {DURATION.describe()}")


def _add_simulate(sub) -> None:
    parser = sub.add_parser(
        "simulate",
        help="offline simulation, passive and controlled side by side",
        description=_wrap(
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
    _add_overrides(parser, "control.designs.phi.p1_per_s=8.0")
    _add_record_options(parser)
    control = parser.add_argument_group("control")
    control.add_argument("--controller", type=_non_empty, metavar="NAME|none", help="a design of the profile, or 'none' (passive only)")
    control.add_argument("--rate", type=_in(RATE), metavar="HZ", help=f"controller sample rate (Hz), {RATE.describe()}")
    control.add_argument("--friction", choices=("estimator", "model"), help="friction term: online estimate or the model's")
    control.add_argument("--delay", type=_in(DELAY), metavar="S",
                         help=f"further transport delay from sample to force (s), {DELAY.describe()}")
    control.add_argument(
        "--design-stiffness-scale", type=_in(STIFFNESS_SCALE), metavar="X",
        help=f"controller's model has story stiffness x X (robustness: 0.7, 1.3), {STIFFNESS_SCALE.describe()}",
    )
    control.add_argument(
        "--rig-effects", action="store_true",
        help="controlled case through the profile's rig models: sensor noise, quantization and delay, "
        "actuator dynamics and limits, and the safety supervisor (what a dry run should reproduce); "
        "--delay then adds sensor delay: one loop period (e.g. 0.002) mirrors a real-time dry run",
    )
    output = parser.add_argument_group("output")
    output.add_argument("--json", type=_output_file, metavar="PATH", help="write peaks and record facts as JSON (SI units)")
    output.add_argument("--out", type=_output_dir, metavar="DIR", help="save both cases' time series as run folders in DIR")
    output.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=_cmd_simulate)


def _add_report(sub) -> None:
    parser = sub.add_parser(
        "report",
        help="tables and plots from run folders",
        description=_wrap(
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
    parser.add_argument("--out", type=_output_dir, metavar="DIR", help="where to write (default: RUN/report)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(handler=_cmd_report)


def _add_records(sub) -> None:
    parser = sub.add_parser(
        "records",
        help="list ground-motion records, or show one after processing",
        description=_wrap(
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
    parser.add_argument("--profile", type=_non_empty, help="take scaling and the table's limits from this profile")
    _add_overrides(parser, "table.stroke_limit_m=0.1")
    parser.add_argument("--records-dir", type=_non_empty, metavar="DIR", help="where named records are found")
    parser.add_argument("--pga", type=_in(PGA), metavar="G", help=f"scale to this PGA (g), {PGA.describe()}")
    parser.add_argument("--time-scale", type=_in(TIME_SCALE), metavar="F", help=f"compress time by F, {TIME_SCALE.describe()}")
    parser.add_argument("--duration", type=_in(DURATION), metavar="S", help=f"cut to this length (s), {DURATION.describe()}")
    parser.add_argument("--plot", type=_output_file, metavar="PNG", help="write a plot of the processed motion")
    parser.set_defaults(handler=_cmd_records)


def _add_bus_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("CAN bus (overrides the profile's can section)")
    group.add_argument("--interface", type=_non_empty, metavar="I", help="python-can interface: virtual, socketcan, pcan, kvaser, ...")
    group.add_argument("--channel", type=_non_empty, metavar="C", help="channel, e.g. vcan0, can0, PCAN_USBBUS1")


def _add_overrides(parser: argparse.ArgumentParser, example: str) -> None:
    """``--variant`` and ``--set``: every command that loads a profile takes both, validated like the file."""
    parser.add_argument("--variant", type=_non_empty, help="apply a named variant of the profile (e.g. a_mu_0.5)")
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
        help=f"override a profile value, validated like the file, e.g. --set {example} (repeatable)",
    )


def _add_profile_options(parser: argparse.ArgumentParser, default_help: str) -> None:
    parser.add_argument("profile", nargs="?", help=default_help)
    _add_overrides(parser, "safety.stroke.hard_limit_m=0.05")
    parser.add_argument(
        "--allow-weaker-safety", action="store_true",
        help="accept --set values that weaken the profile's own safety settings; each is recorded in metadata.json, "
        "on the live console and in the outcome (docs/SAFETY.md). Without it such a run is refused",
    )


def _add_dry_run(sub) -> None:
    parser = sub.add_parser(
        "dry-run",
        help="the whole test against the virtual rig over CAN (the main job)",
        description=_wrap(
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
            "  harness dry-run --set safety.stroke.hard_limit_m=0.02           (watch it trip)\n\n" + EPILOG
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_profile_options(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    _add_record_options(parser)
    _add_bus_options(parser)
    loop = parser.add_argument_group("loop")
    loop.add_argument("--rate", type=_in(RATE), metavar="HZ",
                      help=f"loop rate (default: the profile's loop.rate_hz), {RATE.describe()}")
    loop.add_argument("--controller", type=_non_empty, metavar="NAME", help="a design of the profile (default: control.controller)")
    loop.add_argument("--lockstep", action="store_true", help="the rig advances one step per command (deterministic; slow machines)")
    loop.add_argument("--external-rig", action="store_true", help="a `harness rig` already serves the channel; do not start one")
    output = parser.add_argument_group("output")
    output.add_argument("--log-dir", type=_output_dir, metavar="DIR", help="where run folders go (default: logs/)")
    output.add_argument("--quiet", action="store_true", help="no live console")
    parser.set_defaults(handler=_cmd_dry_run)


def _add_rig(sub) -> None:
    parser = sub.add_parser(
        "rig",
        help="serve the virtual rig on a bus (for dry runs across processes)",
        description=_wrap(
            "Serve the virtual 4-DOF rig (table, plant on friction bearings, sensors, servo actuator with "
            "its drive watchdog, fault injection) on a CAN channel until Ctrl-C, in real time or in lockstep "
            "(one step per actuator command). The harness side is `harness dry-run --external-rig` on the "
            "same channel. The drive is disabled on the way out."
        ),
        epilog="example:\n  harness rig profiles/nceer_4dof.yaml --interface socketcan --channel vcan0\n\n" + EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_profile_options(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    _add_record_options(parser)
    _add_bus_options(parser)
    parser.add_argument("--rate", type=_in(RATE), metavar="HZ",
                        help=f"the harness's loop rate: the rig's step period is 1/HZ, {RATE.describe()}")
    parser.add_argument("--lockstep", action="store_true", help="advance one step per actuator command")
    parser.add_argument("--seed", type=_in(SEED), help=f"noise seed (default: rig.seed of the profile), {SEED.describe()}")
    parser.add_argument("--parent-pid", type=_in(PID), metavar="PID",
                        help="stop serving (drive disabled) when process PID is gone; `harness dry-run` sets it")
    parser.set_defaults(handler=_cmd_rig)


@contextlib.contextmanager
def _stop_on_signals():
    """Ctrl-C and SIGTERM raise KeyboardInterrupt (a clean stop), even if the shell started
    this process with SIGINT ignored, as it does for background jobs; the handlers before
    are put back afterwards (``main`` may run in a longer-lived process)."""

    def interrupt(signum, frame):
        raise KeyboardInterrupt

    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGINT, interrupt)
    signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGTERM, before[1])


def _cmd_rig(args: argparse.Namespace, console: Console) -> int:
    from harness.rig import run_rig_command

    with _stop_on_signals():
        _load_acknowledged(args, console)  # the rig serves the harness's profile: the same acknowledgement
        _compile_kernels(console)
        options = _study_options(args, rate_hz=args.rate)
        console.print(f"virtual rig on {args.interface or 'the profile interface'}:{args.channel or 'the profile channel'}"
                      f"{' (lockstep)' if args.lockstep else ''}; Ctrl-C stops it")
        return run_rig_command(
            args.profile, interface=args.interface, channel=args.channel, lockstep=args.lockstep, options=options,
            seed=args.seed, variant=args.variant, overrides=tuple(args.overrides), parent_pid=args.parent_pid,
        )


def _add_run(sub) -> None:
    parser = sub.add_parser(
        "run",
        help="the real rig: the same loop, no virtual rig",
        description=_wrap(
            "Run the control loop against the real rig on a CAN channel: the same code as a dry run "
            "without the virtual rig. The lab's table controller plays the record; this command runs for "
            "the record's duration (from the profile or --duration). It asks before it arms the actuator "
            "(--yes skips the question). Ctrl-C stops safely (ramp down, drive off); a second Ctrl-C trips."
        ),
        epilog="example:\n  harness run profiles/my_rig.yaml --interface socketcan --channel can0\n\n" + EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    _add_profile_options(parser, "profile YAML of the rig")
    _add_record_options(parser)
    _add_bus_options(parser)
    parser.add_argument("--rate", type=_in(RATE), metavar="HZ",
                        help=f"loop rate (default: the profile's loop.rate_hz), {RATE.describe()}")
    parser.add_argument("--controller", type=_non_empty, metavar="NAME", help="a design of the profile")
    parser.add_argument("--yes", action="store_true", help="do not ask before arming")
    parser.add_argument("--log-dir", type=_output_dir, metavar="DIR", help="where run folders go (default: logs/)")
    parser.add_argument("--quiet", action="store_true", help="no live console")
    parser.set_defaults(handler=_cmd_run)


def _study_options(args: argparse.Namespace, **extra):
    from harness.study import StudyOptions

    return StudyOptions(
        record=args.record, records_dir=args.records_dir, pga_g=args.pga, time_scale=args.time_scale,
        duration_s=args.duration, **extra,
    )


def _print_timing(console: Console, timing: dict, rate_hz: float) -> None:
    if not timing.get("ticks"):
        return
    console.print(
        f"loop at {rate_hz:g} Hz: {timing['ticks']} ticks, lateness median {timing['lateness_median_s'] * 1e6:.1f} us, "
        f"p99 {timing['lateness_p99_s'] * 1e6:.1f} us, max {timing['lateness_max_s'] * 1e6:.0f} us; compute median "
        f"{timing['compute_median_s'] * 1e6:.1f} us, p99 {timing['compute_p99_s'] * 1e6:.1f} us (CPU of the loop thread: median "
        f"{timing['cpu_median_s'] * 1e6:.1f} us); missed periods {timing['overruns']}"
    )
    if "stall_budget_s" in timing and not timing.get("lockstep", False):
        console.print(
            f"stalls ridden through {timing['stalls_ridden_through']}, longest gap between ticks "
            f"{timing['longest_stall_s'] * 1e3:.1f} ms (stall budget {timing['stall_budget_s'] * 1e3:.1f} ms)"
        )


#: Trips that, against a virtual rig in real time, come from host timing rather than the rig.
_HOST_TIMING_ON_A_VIRTUAL_RIG = ("sensor_stale", "actuator_status_stale")


def _load_acknowledged(args: argparse.Namespace, console: Console | None = None):
    """The profile of a command with ``--set``, refused if it weakens safety without ``--allow-weaker-safety``.

    Parameters
    ----------
    args : argparse.Namespace
        With ``profile``, ``variant``, ``overrides`` and ``allow_weaker_safety``.
    console : Console, optional
        Where an accepted weakening is announced (in red) before anything starts.

    Raises
    ------
    ProfileError
        Listing each weakened key with the profile's value and the new one (exit status 2).
    """
    from harness.profile import load_profile
    from harness.safety.weakening import require_acknowledged, summary

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides)
    require_acknowledged(profile.safety_weakened, args.allow_weaker_safety, profile.source_path)
    if profile.safety_weakened and console is not None:
        console.print(f"[bold red]{escape(summary(profile.safety_weakened))}[/]", highlight=False)
    return profile


def _print_outcome(console: Console, session, virtual_rig: bool = False, weakened: tuple = ()) -> None:
    from harness.safety.operator_detectors import HOST_TIMING_REMEDIES
    from harness.safety.weakening import summary

    style = {"completed": "green", "tripped": "bold red", "stopped": "yellow"}.get(session.outcome, "red")
    reason = f" ({escape(session.trip_reason)})" if session.trip_reason else ""
    lost = f", [bold red]but the record is incomplete[/]: {escape(session.record_problem)}; repeat the test for its data" \
        if session.record_problem else ""
    console.print(f"outcome: [{style}]{session.outcome}[/]{reason}{lost}; run folder {session.run_path}")
    if session.loop.trip_detail:
        console.print(f"  {escape(session.loop.trip_detail)}", highlight=False)
    realtime = not session.loop.timing.get("lockstep", False)
    if virtual_rig and realtime and session.trip_reason in _HOST_TIMING_ON_A_VIRTUAL_RIG:
        console.print(
            "  on a virtual rig this is host timing: the rig process was not scheduled in time to publish; "
            + HOST_TIMING_REMEDIES, highlight=False,
        )
    for line in session.loop.realtime_report:
        console.print(f"  {line}")
    if weakened:
        console.print(f"  [bold red]{escape(summary(weakened))}[/]", highlight=False)


def _print_host_timing(console: Console):
    def show(timing) -> None:
        style = {"ok": "green", "marginal": "yellow"}.get(timing.verdict, "bold red")
        console.print(f"pre-flight: {escape(timing.summary()[:-len(timing.verdict)])}[{style}]{timing.verdict}[/]",
                      highlight=False)

    return show


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (also used to render --help in the docs)."""
    parser = argparse.ArgumentParser(
        prog="harness",
        description=_wrap(
            "Hardware-in-the-loop harness for sliding-mode control of sliding-isolated buildings "
            "on a shaking table (Yang, Wu, Reinhorn & Riley 1996)."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    _add_dry_run(sub)
    _add_rig(sub)
    _add_run(sub)
    _add_simulate(sub)
    _add_report(sub)
    _add_records(sub)
    return parser


def _progress(console: Console, enabled: bool):
    return Progress(
        TextColumn("{task.description:<12}"), BarColumn(), TextColumn("{task.percentage:>5.1f} %"),
        TimeRemainingColumn(), console=console, transient=True, disable=not enabled,
    )


def _cmd_simulate(args: argparse.Namespace, console: Console) -> int:
    from harness.peak_table import peak_table
    from harness.profile import load_profile
    from harness.study import StudyOptions, run_study

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides)
    options = StudyOptions(
        record=args.record, records_dir=args.records_dir, pga_g=args.pga, time_scale=args.time_scale,
        duration_s=args.duration, controller=args.controller, rate_hz=args.rate, friction=args.friction,
        transport_delay_s=args.delay, design_stiffness_scale=args.design_stiffness_scale, rig_effects=args.rig_effects,
    )
    with _progress(console, not args.quiet) as progress:
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
    console.print(peak_table(result.cases["passive"].peaks, controlled.peaks if controlled else None, title))
    cost = sum(case.wall_time_s for case in result.cases.values())
    console.print(f"simulated {len(result.cases)} x {motion.duration_s:.1f} s in {cost:.2f} s of wall time")
    if args.json:
        result.write_json(args.json)
        console.print(f"wrote {args.json}")
    if args.out:
        from harness.study_output import write_study_folders

        folder = write_study_folders(result, args.out)
        console.print(f"wrote time series to {folder}")
    return exit_codes.OK


def _compile_kernels(console: Console) -> None:
    """Compile the numba kernels up front, saying so when it takes a while (the first run of a checkout)."""
    from harness.model.warmup import warm_up

    with console.status("compiling the integration kernels (first run of a checkout only, about a minute) ..."):
        warm_up()


def _cmd_dry_run(args: argparse.Namespace, console: Console) -> int:
    from harness.dryrun import DryRunOptions, dry_run
    from harness.peak_table import peak_table
    from harness.peaks import flatten

    profile = _load_acknowledged(args, console)
    options = DryRunOptions(
        study=_study_options(args, controller=args.controller), rate_hz=args.rate, interface=args.interface,
        channel=args.channel, log_dir=args.log_dir, lockstep=args.lockstep, external_rig=args.external_rig,
        show_console=not args.quiet, overrides=tuple(args.overrides),
    )
    _compile_kernels(console)
    result = dry_run(profile, options, console, on_host_timing=_print_host_timing(console))
    session, motion = result.session, result.motion
    if session.record_problem:
        console.print(f"[bold red]the recorder failed[/]: {escape(session.record_problem)}; the peaks below come "
                      "from the rows written before that", highlight=False)
    console.print(
        f"[bold]{profile.name}[/] dry run, record [bold]{motion.name}[/]: PGA {motion.pga_g:.3f} g, "
        f"PGD {motion.pgd_m * 1e3:.1f} mm, time scale {motion.time_scale:g}, {motion.duration_s:.1f} s"
    )
    title = "peak responses: simulated passive reference and the dry run"
    if result.span_s is not None:
        title += f", over the {result.span_s:.2f} s of record that ran before the run ended ({session.outcome})"
    console.print(peak_table(result.passive.peaks, result.peaks, title, labels=("passive (sim.)", "dry run")))
    ours, twin = flatten(result.peaks), flatten(result.twin.peaks)
    worst = max(twin, key=lambda k: abs(ours[k] - twin[k]) / abs(twin[k]) if twin[k] else 0.0)
    difference = abs(ours[worst] - twin[worst]) / abs(twin[worst]) * 100 if twin[worst] else 0.0
    console.print(f"against `harness simulate --rig-effects` (the rig's models offline): largest peak difference "
                  f"{difference:.1f} % ({worst})")
    _print_timing(console, session.loop.timing, options.rate_hz or profile.loop.rate_hz)
    _print_outcome(console, session, virtual_rig=not options.external_rig, weakened=profile.safety_weakened)
    return session.exit_code


#: What ``table.link: none`` means for a run, printed before arming.
NO_TABLE_LINK = (
    "table.link is none: the table controller is not on the CAN bus. The harness will not start or stop the "
    "table: start it yourself once the run is RUNNING; record time follows the harness's clock, not the table's; "
    "a trip cannot stop the table (stop_table trip actions are skipped), stop it at its own console."
)


def _announce_table_link(profile, console: Console):
    """The run's table link (``table.link``): a :class:`CanTableLink`, or None with the consequence printed."""
    from harness.loop.table_link import CanTableLink

    if profile.table is None or profile.table.link == "can":
        console.print("table: RIG_CONTROL start at RUNNING, stop at the end and on a trip; record time counts from the "
                      "table controller's RIG_STATUS table_running (table.link: can)", highlight=False)
        return CanTableLink(lockstep=False)
    console.print(f"[bold yellow]{escape(NO_TABLE_LINK)}[/]", highlight=False)
    return None


def _cmd_run(args: argparse.Namespace, console: Console) -> int:
    from pathlib import Path

    from harness.dryrun import LOG_DIR
    from harness.session import SessionSettings, run_session
    from harness.study import motion_facts, prepare_motion

    profile = _load_acknowledged(args, console)
    motion = prepare_motion(profile, _study_options(args))
    rate = args.rate if args.rate is not None else profile.loop.rate_hz
    can = profile.can_settings(args.interface, args.channel, rate)
    controller = args.controller or profile.control.controller
    table_link = _announce_table_link(profile, console)
    if not args.yes:
        try:
            answer = console.input(
                f"Arm the actuator on {can.interface}:{can.channel} with {controller} for {motion.duration_s:.1f} s "
                f"(max force {profile.safety.force.max_force_N / 1e3:g} kN, hard stroke {profile.safety.stroke.hard_limit_m * 1e3:g} mm)? [y/N] "
            )
        except (EOFError, OSError):  # no terminal to answer from (stdin closed or captured): that is a no
            answer = ""
        if answer.strip().lower() not in ("y", "yes"):
            console.print("not armed")
            return exit_codes.INPUT_ERROR
    settings = SessionSettings(
        kind="run", can=can, rate_hz=rate, duration_s=motion.duration_s, controller=controller,
        log_dir=Path(args.log_dir) if args.log_dir else LOG_DIR, show_console=not args.quiet,
        metadata={"record": motion_facts(motion), "table_link": "can" if table_link is not None else "none"},
    )
    _compile_kernels(console)
    session = run_session(profile, settings, console=console, on_host_timing=_print_host_timing(console),
                          table_link=table_link)
    _print_timing(console, session.loop.timing, rate)
    _print_outcome(console, session, weakened=profile.safety_weakened)
    return session.exit_code


def _cmd_report(args: argparse.Namespace, console: Console) -> int:
    from harness.report import build_report, summary_text

    with _progress(console, not args.quiet) as progress:
        task = progress.add_task("report", total=1.0)

        def report(message: str, done: int, total: int) -> None:
            progress.update(task, description=message[:12], completed=done / max(total, 1))

        result = build_report(args.runs, args.out, progress=report)
    console.print(summary_text(result), highlight=False, markup=False)
    for warning in result.warnings:
        console.print(f"[yellow]warning:[/] {escape(warning)}")
    console.print(f"wrote {len(result.plots)} plots and {result.html_path}")
    return exit_codes.OK


def _cmd_records(args: argparse.Namespace, console: Console) -> int:
    from rich.table import Table

    from harness.profile import load_profile
    from harness.records import list_records, records_dir_from, summarize
    from harness.study import StudyOptions, prepare_motion

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
    options = StudyOptions(record=args.record, records_dir=args.records_dir, pga_g=args.pga,
                           time_scale=args.time_scale, duration_s=args.duration)
    motion = prepare_motion(profile, options)
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


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``harness`` console script."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as done:  # argparse's own exit: --help (0) or a refused option (2, message printed)
        return done.code if isinstance(done.code, int) else exit_codes.INPUT_ERROR
    console = Console(stderr=False)
    if args.command is None:
        parser.print_help()
        return exit_codes.INPUT_ERROR
    handler: Callable[[argparse.Namespace, Console], int] = args.handler
    try:
        return handler(args, console)
    except HarnessError as err:
        Console(stderr=True, soft_wrap=True).print(f"[bold red]error:[/] {escape(str(err))}", highlight=False)
        return exit_codes.INPUT_ERROR
    except KeyboardInterrupt:
        Console(stderr=True).print("interrupted")
        return exit_codes.STOPPED


if __name__ == "__main__":
    sys.exit(main())
