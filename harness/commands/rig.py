"""``harness rig``: serve the virtual rig on a bus."""

from __future__ import annotations

import argparse

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands.options import (
    EPILOG,
    PID,
    RATE,
    SEED,
    add_bus_options,
    add_profile_options,
    add_record_options,
    load_acknowledged,
    number_in,
    study_options,
    wrap,
)
from harness.commands.output import compile_kernels
from harness.realtime.interrupts import stop_on_signals


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "rig",
        help="serve the virtual rig on a bus (for dry runs across processes)",
        description=wrap(
            "Serve the virtual 4-DOF rig (table, plant on friction bearings, sensors, servo actuator with "
            "its drive watchdog, fault injection) on a CAN channel until Ctrl-C, in real time or in lockstep "
            "(one step per actuator command). The harness side is `harness dry-run --external-rig` on the "
            "same channel; the banner prints that command. The rig serves run after run: when a run's harness "
            "disconnects, the drive's heartbeat watchdog latches a fault, as a real servo drive does, and the next "
            "run resets it with --reset-drive. The terminal prints each change of the drive, the harness's run and "
            "the table, one line each. The drive is disabled on the way out."
        ),
        epilog=(
            "examples:\n  harness rig                                   (seqpacket channel 'harness': no set-up)\n"
            "  harness rig --lockstep\n"
            "  harness rig profiles/nceer_4dof.yaml --interface socketcan --channel vcan0\n\n" + EPILOG
        ),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_profile_options(parser, "profile YAML (default: profiles/nceer_4dof.yaml)")
    add_record_options(parser)
    add_bus_options(parser)
    parser.add_argument("--rate", type=number_in(RATE), metavar="HZ",
                        help=f"the harness's loop rate: the rig's step period is 1/HZ, {RATE.describe()}")
    parser.add_argument("--lockstep", action="store_true", help="advance one step per actuator command")
    parser.add_argument("--seed", type=number_in(SEED), help=f"noise seed (default: rig.seed of the profile), {SEED.describe()}")
    parser.add_argument("--parent-pid", type=number_in(PID), metavar="PID",
                        help="stop serving (drive disabled) when process PID is gone; `harness dry-run` sets it")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from harness.rig.truth import truth_summary
    from harness.runs.options import resolve_profile
    from harness.runs.rig_service import serve_rig

    with stop_on_signals():
        profile = load_acknowledged(args, console)  # the rig serves the harness's profile: the same acknowledgement
        profile = resolve_profile(profile, study_options(args, rate_hz=args.rate))
        can_config = profile.can_settings(args.interface, args.channel)
        if can_config.interface == "virtual":  # python-can's virtual bus lives inside one process
            console.print("[bold red]error:[/] python-can's 'virtual' interface is a bus inside one process: no other "
                          "process could reach this rig. Serve it on a bus other processes share: --interface seqpacket "
                          "(a Unix socket, no set-up) or --interface socketcan --channel vcan0", highlight=False)
            return exit_codes.INPUT_ERROR
        compile_kernels(console)
        # soft wrap: the command line stays on one line, to be copied as it is
        console.print(escape(banner(can_config.interface, can_config.channel, args.lockstep)), highlight=False,
                      soft_wrap=True)
        truth_note = truth_summary(profile.rig_truth().differences)
        if truth_note:
            console.print(f"[yellow]{escape(truth_note)}[/]", highlight=False)
        status = serve_rig(profile, can_config, lockstep=args.lockstep, seed=args.seed, parent_pid=args.parent_pid,
                           on_journal=lambda wall_time_s, line: print_journal_line(console, wall_time_s, line),
                           on_ready=lambda rig: console.print(SERVING, highlight=False))
        console.print(stopped_line(status), highlight=False, soft_wrap=True)
        return status


#: Printed once the rig serves the bus (a harness may connect from then on).
SERVING = "virtual rig serving: waiting for a harness"


def stopped_line(status: int) -> str:
    """The rig's last line: why it stopped serving and its exit status (a stop is never silent)."""
    why = "stopped by the operator (Ctrl-C)" if status == exit_codes.STOPPED else "stopped serving"
    return f"virtual rig {why}: drive disabled, bus closed (exit status {status})"


def harness_command(interface: str, channel: str, lockstep: bool) -> str:
    """The ``harness dry-run`` command line that reaches a rig serving ``interface``/``channel``."""
    return (f"harness dry-run --external-rig --interface {interface} --channel {channel}"
            + (" --lockstep" if lockstep else ""))


def banner(interface: str, channel: str, lockstep: bool) -> str:
    """The rig's first lines: where it serves, the command that reaches it (on a line of its own), what later runs need."""
    command = harness_command(interface, channel, lockstep)
    return (f"virtual rig on interface {interface!r}, channel {channel!r}{' (lockstep)' if lockstep else ''}; "
            f"from another terminal, with the record options given to this rig:\n  {command}\n"
            "every later run adds --reset-drive (the drive latches its heartbeat watchdog when a run ends); "
            "Ctrl-C stops the rig")


def print_journal_line(console: Console, wall_time_s: float, line: str) -> None:
    """One journal line of the rig, stamped with the local wall-clock time."""
    import time

    stamp = time.strftime("%H:%M:%S", time.localtime(wall_time_s))
    console.print(f"{stamp} {escape(line)}", highlight=False, soft_wrap=True)
