"""The commands of ``harness``, one module each, as cantools keeps its subparsers.

Each command module has ``add_parser(subparsers)``, which declares its options, and
``run(args, console) -> int``, which does the command and returns its exit status; a
reader finds a command's whole path, from its options to its output, in its own file.
:mod:`harness.commands.options` holds the argument types and option groups they share,
:mod:`harness.commands.output` the console output they share; :mod:`harness.cli` builds
the parser from them and maps errors to exit statuses.
"""

from harness.commands import dry_run, identify, records, replay, report, rig, run, simulate, sweep

#: The commands in the order ``harness --help`` lists them.
COMMANDS = (dry_run, rig, run, replay, identify, simulate, sweep, report, records)
