"""The ``harness`` command line: the top-level parser, and errors mapped to exit statuses.

Each command lives in its own module of :mod:`harness.commands`.

:func:`main` first installs the operator's signal handlers (:mod:`harness.loop.operator`),
before any heavy import: from then on a Ctrl-C or SIGTERM only sets a flag, never raises
inside a library's callback, and is never lost. The commands that move the rig (``dry-run``,
``run``, ``identify actuator``: they set ``safe_points``) look at it at safe points and hand it to
the loop; every other command gets a Ctrl-C as KeyboardInterrupt once its options are parsed,
and the flag still says it came. An operator's request at any moment ends the command with an
outcome line and exit status 4 (3 for a trip or a lost record), never 0 and never a traceback.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence
from typing import TYPE_CHECKING

from harness import exit_codes
from harness.errors import StoppedByOperator
from harness.loop.operator import OperatorSignals

if TYPE_CHECKING:
    import argparse

    from rich.console import Console


def build_parser() -> argparse.ArgumentParser:
    """The full argument parser (also used to render --help in the docs)."""
    import argparse

    from harness.commands import COMMANDS
    from harness.commands.options import EPILOG, wrap

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
    """Entry point of the ``harness`` console script.

    Parameters
    ----------
    argv : sequence of str, optional
        The arguments; None: the process's own (``main`` is then the process's entry, and the flag
        handlers stay until it ends: a Ctrl-C in the interpreter's teardown, after the outcome line,
        changes nothing and prints no traceback). Given (tests, a longer-lived process), the handlers
        the process had are put back before ``main`` returns.
    """
    signals = OperatorSignals().install()  # first of all: a Ctrl-C from here on is a flag, never lost
    try:
        code = _command(argv, signals)
    finally:
        if argv is not None:
            signals.restore()
    if code == exit_codes.OK and signals.requested:  # came after the command's last look (its work was done)
        sys.stdout.write(f"stopped by the operator ({signals.what}) as the command ended; exit status 4\n")
        code = exit_codes.STOPPED
    return code


def _command(argv: Sequence[str] | None, signals: OperatorSignals) -> int:
    """Parse, run the command, map its errors to exit statuses; ``signals`` hold the operator's requests."""
    console: Console | None = None
    try:
        from harness.commands.output import command_console

        parser = build_parser()
        try:
            args = parser.parse_args(argv)
        except SystemExit as done:  # argparse's own exit: --help (0) or a refused option (2, message printed)
            return done.code if isinstance(done.code, int) else exit_codes.INPUT_ERROR
        console = command_console(quiet=getattr(args, "quiet", False))
        if args.command is None:
            parser.print_help()
            return exit_codes.INPUT_ERROR
        if signals.requested:
            raise StoppedByOperator("while starting", signals.what)
        signals.raise_interrupt = not getattr(args, "safe_points", False)  # nothing moves: Ctrl-C interrupts at once
        code = _handle(args, console)
        signals.raise_interrupt = False
        if code == exit_codes.OK and signals.requested:
            if getattr(args, "safe_points", False):  # came after the loop: nothing was moving
                return _stopped(console, f"stopped by the operator ({signals.what}) after the run had ended; exit status 4")
            return _stopped(console, "interrupted by the operator while the command ran; exit status 4")  # swallowed
        return code
    except StoppedByOperator as stop:
        signals.raise_interrupt = False
        folder = f"run folder {stop.run_path} (marked stopped)" if stop.run_path else "no run folder was made"
        return _stopped(console, f"outcome: [yellow]stopped by the operator[/] ({stop.request}) before anything "
                        f"moved, {stop.where}; {folder}")
    except KeyboardInterrupt:
        signals.raise_interrupt = False
        return _stopped(console, "interrupted by the operator; exit status 4")


def _handle(args: argparse.Namespace, console: Console) -> int:
    """Run the parsed command; an expected error is a refusal (exit status 2)."""
    from rich.console import Console
    from rich.markup import escape

    from harness.errors import EXPECTED_ERRORS

    try:
        return args.handler(args, console)
    except EXPECTED_ERRORS as err:
        Console(stderr=True, soft_wrap=True).print(f"[bold red]error:[/] {escape(str(err))}", highlight=False)
        return exit_codes.INPUT_ERROR


def _stopped(console: Console | None, line: str) -> int:
    """Print the outcome of an operator's stop (even under ``--quiet``); exit status 4."""
    if console is None:
        from rich.markup import render

        sys.stdout.write(render(line).plain + "\n")
    else:
        from harness.commands.output import print_always

        print_always(console, line, highlight=False)
    return exit_codes.STOPPED


if __name__ == "__main__":
    sys.exit(main())
