"""``harness identify``: identify the rig's dynamics from measured responses; one module per kind.

Each kind is a module with the same ``add_parser(subparsers)`` and ``run(args, console)`` as a
command, listed in :data:`KINDS`: ``actuator`` (:mod:`harness.commands.identify_actuator`) runs
its own excitation; ``bearing`` (:mod:`harness.commands.identify_bearing`) and ``structure``
(:mod:`harness.commands.identify_structure`) read run folders.
"""

from __future__ import annotations

import argparse

from rich.console import Console

import harness.commands.identify_actuator as identify_actuator  # not from the package: it imports this module
import harness.commands.identify_bearing as identify_bearing
import harness.commands.identify_structure as identify_structure
from harness import exit_codes
from harness.commands.options import EXIT_STATUS, PROFILES_HELP, wrap

#: The kinds of identification, in the order ``harness identify --help`` lists them.
KINDS = (identify_actuator, identify_bearing, identify_structure)


def add_parser(sub) -> None:
    parser = sub.add_parser(
        "identify",
        help="measure the rig's dynamics: the actuator's frequency response, the bearing's friction, the structure",
        description=wrap(
            "Identify part of the rig from a measured response, on the virtual rig (default) or a real one "
            "(--interface, --channel). Every identification is a run like any other: the same loop, the "
            "supervisor with every interlock active, a run folder with the whole record. The bearing and the "
            "structure are identified from run folders (dry runs or real runs) afterwards."
        ),
        epilog="examples:\n  harness identify actuator --out frf/ --duration 20\n"
               "  harness identify bearing logs/<RUN> --out ident/bearing\n"
               "  harness identify structure logs/<RUN> --out ident/structure\n\n" + EXIT_STATUS + "\n" + PROFILES_HELP,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    kinds = parser.add_subparsers(dest="kind", metavar="KIND")
    for kind in KINDS:
        kind.add_parser(kinds)

    def without_kind(args: argparse.Namespace, console: Console) -> int:
        parser.print_help()
        return exit_codes.INPUT_ERROR

    parser.set_defaults(handler=without_kind)
