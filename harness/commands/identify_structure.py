"""``harness identify structure RUN [RUN ...]``: fixed-base modes, story stiffness and damping from run folders."""

from __future__ import annotations

import argparse

from rich.console import Console

from harness import exit_codes
from harness.commands.identify_actuator import band
from harness.commands.options import OFFLINE_EXIT_STATUS, add_run_folders, wrap

EXAMPLES = """\
examples:
  harness dry-run --lockstep --record white_noise:0.5-20:0.1 --duration 60     (excite the structure)
  harness identify structure logs/<RUN> --out ident/structure
  harness identify structure logs/<RUN> --out ident/structure --band-hz 1,20 --damping per_story

DIR gets identified.yaml (the determined structure.* values, each with its quality: a profile
overlay), identification.json (the modes with their standard errors, the story values, the runs
with the SHA-256 of their signals.csv, the harness version) and frf.png (each floor's response to
the base mat's acceleration: measured, the story model and the modal fit).
"""


def add_parser(sub) -> None:
    from harness.identification.choices import DAMPING_MODELS

    parser = sub.add_parser(
        "structure",
        help="fixed-base modes, story stiffness and damping from run folders",
        description=wrap(
            "Identify the superstructure from the base mat's acceleration (input) and the floors' (outputs): the "
            "floors feel the base only through the base mat's acceleration, so whatever the bearings, actuator and "
            "table do, this is the fixed-base structure's response. First the modes (frequencies, damping ratios, "
            "participations) by a time-domain fit that uses no masses; then the story stiffness and damping that "
            "reproduce the floors' accelerations with the profile's masses, and how well their modes match. A "
            "low-amplitude white-noise table motion excites every mode at once (harness dry-run --record "
            "white_noise:0.5-20:0.1); any run that moves the base mat will do. A run without the base-mat and floor "
            "accelerations is refused (exit 2)."
        ),
        epilog=EXAMPLES + "\n" + OFFLINE_EXIT_STATUS,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_run_folders(parser, "identified.yaml, identification.json and frf.png")
    parser.add_argument("--band-hz", type=band, default=None, metavar="LOW,HIGH",
                        help="frequency band of the fit (Hz) (default: half the design's first fixed-base frequency to "
                        "1.5 times its last)")
    parser.add_argument("--damping", choices=DAMPING_MODELS, default=None,
                        help="per_story (structure.story_damping_Ns_per_m) or proportional to stiffness "
                        "(structure.first_mode_damping_ratio) (default: the form the run's profile uses)")
    parser.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    from pathlib import Path

    from harness.identification.fit_statistics import interval_95
    from harness.identification.run_signals import IdentificationError
    from harness.identification.structure import identify_structure
    from harness.model.warmup import warm_up

    warm_up()
    result = identify_structure(args.runs, Path(args.out), None if args.band_hz is None else tuple(args.band_hz), args.damping,
                                args.force)
    modal, stories = result.modal, result.stories
    story_hz, story_zeta = stories.modes()
    console.print(f"structure from {len(result.runs)} run(s), band {result.band_hz[0]:.3g}-{result.band_hz[1]:.3g} Hz:",
                  highlight=False)
    for r, determination in enumerate(result.modes):
        mark = "[green]determined[/]" if determination.determined else "[yellow]not determined[/]"
        f_low, f_high = interval_95(float(modal.frequency_hz[r]), float(modal.frequency_se_hz[r]))
        z_low, z_high = interval_95(float(modal.damping_ratio[r]), float(modal.damping_se[r]))
        console.print(f"  mode {r + 1}: {modal.frequency_hz[r]:.4g} Hz (95 % {f_low:.4g}-{f_high:.4g}), damping "
                      f"{modal.damping_ratio[r]:.3g} (95 % {z_low:.3g}-{z_high:.3g}) ({mark}); story model "
                      f"{story_hz[r]:.4g} Hz, {story_zeta[r]:.3g}", highlight=False)
    stiffness = ", ".join(f"{k:.4g}" for k in stories.stiffness_N_per_m)
    design = ", ".join(f"{k:.4g}" for k in result.design.story_stiffness_N_per_m)
    console.print(f"  story stiffness [{stiffness}] N/m (profile [{design}]): "
                  f"{'determined' if result.stiffness.determined else 'not determined'}; {result.stiffness.reason}",
                  highlight=False)
    console.print(f"  damping ({stories.damping_model}): {'determined' if result.damping.determined else 'not determined'}; "
                  f"{result.damping.reason}", highlight=False)
    console.print(f"overlay: {result.overlay_path}; record: {result.record_path}; plot: {result.plot_path}", highlight=False)
    if not result.stiffness.determined and not result.damping.determined:
        raise IdentificationError(
            f"the runs {', '.join(str(r.path) for r in result.runs)} determine neither the story stiffness nor the damping "
            f"({result.stiffness.reason}); expected runs whose base mat moves across the band (a white-noise dry run)"
        )
    return exit_codes.OK
