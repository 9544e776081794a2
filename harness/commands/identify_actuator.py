"""``harness identify actuator``: the actuator's command-to-force frequency response (H1, Bode plot)."""

from __future__ import annotations

import argparse
from collections.abc import Callable

from rich.console import Console
from rich.markup import escape

from harness.commands.options import (
    EXIT_STATUS,
    PROFILES_HELP,
    SEED,
    add_bus_options,
    add_profile_options,
    add_result_folder,
    load_acknowledged,
    number_in,
    wrap,
)
from harness.commands.output import compile_kernels, print_host_timing, print_outcome, print_timing
from harness.config import input_limits as limits
from harness.errors import ProfileError

#: Peak force of the excitation (N): up to the largest rig actuator's rating (``rig.actuator.force_limit_N``
#: <= 30 kN); the profile's ``safety.force.max_force_N`` then refuses anything above its own limit.
AMPLITUDE = limits.NumberRange(0.0, 30_000.0, "N")
#: Length of the excitation (s): the runs' bound (harness/config/input_limits.py).
EXCITATION_DURATION = limits.NumberRange(0.0, limits.MAX_DURATION_S, "s")
#: Resolution of the estimate (Hz): 0.01 Hz is a Welch segment of 100 s, 10 Hz one of a tenth of a second.
RESOLUTION = limits.NumberRange(0.01, 10.0, "Hz", low_open=False)
#: Frequencies of the band (Hz): the loop's rate bounds what it can play (its Nyquist frequency is checked later).
BAND_FREQUENCY = limits.NumberRange(0.0, limits.MAX_RATE_HZ / 2, "Hz")

EXAMPLES = """\
examples:
  harness identify actuator --out frf/ --duration 20              (virtual rig, free, lockstep)
  harness identify actuator --out frf_both/ --both --amplitude-N 1500 --band-hz 0.5,40
  harness identify actuator nceer_4dof --out frf_random/ --signal random --seed 3 --duration 60
  harness identify actuator profiles/my_rig.yaml --interface socketcan --channel can0 --blocked --out frf_rig/

DIR gets frf.csv (free) and frf_blocked.csv (blocked): freq_hz,magnitude,phase_deg,coherence
within the band, frf_velocity.csv (free: command to sliding velocity), frf.png (the Bode plot
of every condition in DIR), excitation.json and one run folder per condition. Then the SPEC 7a
model is fitted to every response in DIR: identified.yaml (an --overlay with the values the
data determine: force loop bandwidth, valve bandwidth, with a free condition the bulk modulus,
with a band reaching half the valve's frequency the delay), identification.json (values,
standard errors, fit error in % and deg, what was held and why) and actuator_fit.png.
Both conditions and a band past the force loop give the most: --both --band-hz 1,80 --amplitude-N 700.
A DIR that holds an earlier identification's results is refused before anything moves (exit 2)
unless --force, which removes them first: every response in DIR, and in the fit, is this run's.
"""


def band(text: str) -> tuple[float, float]:
    """An argparse ``type=`` for ``LOW,HIGH`` in Hz, ``0 < LOW < HIGH``."""
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"found {text!r}, expected LOW,HIGH in Hz, e.g. 1,30")
    try:
        low, high = (float(BAND_FREQUENCY.check(part)) for part in parts)
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"{err} (LOW,HIGH)") from None
    if not low < high:
        raise argparse.ArgumentTypeError(f"found {low:g},{high:g}, expected LOW < HIGH (Hz)")
    return low, high


def add_parser(sub) -> None:
    from harness.identification.excitation_settings import SIGNALS, Excitation

    default = Excitation()
    parser = sub.add_parser(
        "actuator",
        help="the actuator's command-to-force frequency response (H1, Bode plot)",
        description=wrap(
            "Excite the control actuator with a chirp or band-limited random force and estimate the frequency "
            "response from the supervised force command to the load cell's force (H1 = Pxy/Pxx, Welch averaging), "
            "with its coherence. The excitation goes through the loop's supervisor like a controller's force, with "
            "every interlock active; it is refused before anything moves if its peak exceeds "
            "safety.force.max_force_N or its peak rate 2 pi f_high A exceeds safety.force.max_force_rate_N_per_s. "
            "The table is not started: it holds still. Conditions: free (default: the structure on its bearings), "
            "--blocked (the base mat held to the table: on the virtual rig the profile's rig.base_pinned; on a real "
            "rig the lab clamps it and the run records it), or --both one after the other. The virtual rig runs in "
            "its own process, in lockstep unless --realtime; --interface/--channel run on the rig serving that bus "
            "(a real rig), in real time."
        ),
        epilog=EXAMPLES + "\n" + EXIT_STATUS + "\n" + PROFILES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_profile_options(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    add_result_folder(parser, "the estimate, the plot, excitation.json, the fit and the run folders")
    signal = parser.add_argument_group("excitation")
    signal.add_argument("--signal", choices=SIGNALS, default=default.signal,
                        help=f"logarithmic chirp or band-limited Gaussian noise (default: {default.signal})")
    signal.add_argument("--amplitude-N", dest="amplitude_N", type=number_in(AMPLITUDE), default=default.amplitude_N,
                        metavar="N", help=f"peak force (N), {AMPLITUDE.describe()} (default: {default.amplitude_N:g})")
    signal.add_argument("--band-hz", type=band, default=default.band_hz, metavar="LOW,HIGH",
                        help=f"frequency band (Hz) (default: {default.low_hz:g},{default.high_hz:g})")
    signal.add_argument("--duration", type=number_in(EXCITATION_DURATION), default=default.duration_s, metavar="S",
                        help=f"length of the excitation (s), {EXCITATION_DURATION.describe()} (default: {default.duration_s:g})")
    signal.add_argument("--seed", type=number_in(SEED), default=default.seed, metavar="N",
                        help=f"seed of the random signal (default: {default.seed})")
    signal.add_argument("--resolution-hz", type=number_in(RESOLUTION), default=default.resolution_hz, metavar="HZ",
                        help=f"frequency resolution of the estimate (Hz), {RESOLUTION.describe()} "
                        f"(default: {default.resolution_hz:g})")
    condition = parser.add_argument_group("condition").add_mutually_exclusive_group()
    condition.add_argument("--blocked", action="store_true", help="the base mat held to the table (blocked actuator)")
    condition.add_argument("--both", action="store_true", help="free, then blocked (DIR/frf.csv and DIR/frf_blocked.csv)")
    add_bus_options(parser)
    rig = parser.add_argument_group("rig")
    rig.add_argument("--realtime", action="store_true", help="run the virtual rig in real time (default: lockstep)")
    rig.add_argument("--yes", action="store_true", help="on a real rig, do not ask before arming each condition")
    rig.add_argument("--quiet", action="store_true", help="print each condition's outcome line only (no live console)")
    parser.set_defaults(handler=run, safe_points=True)  # moves the rig: Ctrl-C is a flag (harness/cli.py)


def _confirm(console: Console, can_text: str, excitation) -> Callable[[str], bool]:
    """The question asked before each condition on a real rig: the operator sets the base mat up, then arms."""
    instructions = {"free": "the base mat free on its bearings (unclamped)", "blocked": "the base mat clamped to the table"}

    def ask(condition: str) -> bool:
        try:
            answer = console.input(
                f"Condition [bold]{condition}[/]: {instructions[condition]}. Arm the actuator on {escape(can_text)} and play "
                f"the {excitation.signal} ({excitation.amplitude_N:g} N, {excitation.low_hz:g}-{excitation.high_hz:g} Hz, "
                f"{excitation.duration_s:g} s)? [y/N] "
            )
        except (EOFError, OSError):  # no terminal to answer from: that is a no
            answer = ""
        return answer.strip().lower() in ("y", "yes")

    return ask


def run(args: argparse.Namespace, console: Console) -> int:
    from pathlib import Path

    from harness.identification.excitation_settings import Excitation
    from harness.runs.identify import CONDITION_LABELS, Condition, IdentifyOptions, identify_actuator, summary

    external = bool(args.interface or args.channel)
    if args.both and external and args.yes:
        raise ProfileError("on a real rig the lab clamps the base mat between the two conditions; drop --yes to be asked "
                           "before each (or run --blocked and the free condition one at a time, each into its own --out)",
                           key_path="--both")
    profile = load_acknowledged(args, console)
    excitation = Excitation(args.signal, args.amplitude_N, tuple(args.band_hz), args.duration, args.seed, args.resolution_hz)
    conditions: tuple[Condition, ...] = ("free", "blocked") if args.both else ("blocked",) if args.blocked else ("free",)
    options = IdentifyOptions(
        excitation=excitation, out_dir=Path(args.out), conditions=conditions, interface=args.interface,
        channel=args.channel, external_rig=external, lockstep=not args.realtime, show_console=not args.quiet,
        force=args.force,
    )
    compile_kernels(console)
    can = profile.can_settings(args.interface, args.channel)
    confirm = None if args.yes or not external else _confirm(console, f"{can.interface}:{can.channel}", excitation)
    result = identify_actuator(profile, options, console, on_host_timing=print_host_timing(console), confirm=confirm)
    for done in result.conditions:
        session = done.session
        console.print(f"[bold]{profile.name}[/] actuator identification, {CONDITION_LABELS[done.condition]}:", highlight=False)
        print_timing(console, session.loop.timing, profile.control.rate_hz)
        print_outcome(console, session, virtual_rig=not external, weakened=profile.safety_weakened)
        if done.response is not None and len(done.response.freq_hz):
            console.print(f"  {summary(done.response)}; {done.frf_path}", highlight=False)
    if result.declined:
        console.print(f"not armed for the {result.declined} condition")
    if result.plot_path is not None:
        console.print(f"Bode plot: {result.plot_path}; excitation: {result.excitation_path}", highlight=False)
    if result.fit is not None:
        from harness.identification.actuator import summary_lines

        console.print("[bold]SPEC 7a model fitted[/] to every response in DIR:")
        for line in summary_lines(result.fit):
            console.print(f"  {escape(line)}", highlight=False)
        console.print(f"overlay: {result.fit.overlay_path}; record: {result.fit.record_path}; plot: {result.fit.plot_path}",
                      highlight=False)
    return result.exit_code

