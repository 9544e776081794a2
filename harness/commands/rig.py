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
from harness.interrupts import stop_on_signals


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "rig",
        help="serve the virtual rig on a bus (for dry runs across processes)",
        description=wrap(
            "Serve the virtual 4-DOF rig (table, plant on friction bearings, sensors, servo actuator with "
            "its drive watchdog, fault injection) on a CAN channel until Ctrl-C, in real time or in lockstep "
            "(one step per actuator command). The harness side is `harness dry-run --external-rig` on the "
            "same channel. The drive is disabled on the way out."
        ),
        epilog="example:\n  harness rig profiles/nceer_4dof.yaml --interface socketcan --channel vcan0\n\n" + EPILOG,
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
    from harness.runs.rig_service import serve_rig
    from harness.runs.simulate import resolve_profile

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
        console.print(f"virtual rig on interface {can_config.interface!r}, channel {can_config.channel!r}"
                      f"{' (lockstep)' if args.lockstep else ''}; `harness dry-run --external-rig --interface "
                      f"{can_config.interface} --channel {can_config.channel}` reaches it; Ctrl-C stops it", highlight=False)
        truth_note = truth_summary(profile.rig_truth().differences)
        if truth_note:
            console.print(f"[yellow]{escape(truth_note)}[/]", highlight=False)
        return serve_rig(profile, can_config, lockstep=args.lockstep, seed=args.seed, parent_pid=args.parent_pid)
