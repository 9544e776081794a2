"""The ``harness`` command line: the top-level parser, and errors mapped to exit statuses.

Each command lives in its own module of :mod:`harness.commands`.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable, Sequence

from rich.console import Console
from rich.markup import escape

from harness import exit_codes
from harness.commands import COMMANDS
from harness.commands.options import EPILOG, wrap
from harness.commands.output import command_console
from harness.errors import EXPECTED_ERRORS


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (also used to render --help in the docs)."""
    parser = argparse.ArgumentParser(
        prog="harness",
        description=wrap(
            "Hardware-in-the-loop harness for sliding-mode control of sliding-isolated buildings "
            "on a shaking table (Yang, Wu, Reinhorn & Riley 1996)."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``harness`` console script."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as done:  # argparse's own exit: --help (0) or a refused option (2, message printed)
        return done.code if isinstance(done.code, int) else exit_codes.INPUT_ERROR
    console = command_console(quiet=getattr(args, "quiet", False))
    if args.command is None:
        parser.print_help()
        return exit_codes.INPUT_ERROR
    handler: Callable[[argparse.Namespace, Console], int] = args.handler
    try:
        return handler(args, console)
    except EXPECTED_ERRORS as err:
        Console(stderr=True, soft_wrap=True).print(f"[bold red]error:[/] {escape(str(err))}", highlight=False)
        return exit_codes.INPUT_ERROR
    except KeyboardInterrupt:
        Console(stderr=True).print("interrupted")
        return exit_codes.STOPPED


if __name__ == "__main__":
    sys.exit(main())
