"""Operator requests through signals: Ctrl-C stops safely, a second Ctrl-C or SIGTERM trips.

The handlers only set flags: no exception is ever raised inside whatever the process happens
to run when the signal arrives (a compiler library's callback swallowed a KeyboardInterrupt
raised there, and the test ran anyway: issue 30). The command line installs a set of them as
the very first thing it does (:func:`harness.cli.main`; the class is
:class:`harness.realtime.interrupts.OperatorSignals`); the phases before the loop look at
it at safe points (:func:`stop_if_requested`, which ends the command "stopped by the operator
before anything moved"); the loop installs its own set, which takes over a request already
pending (a stop pending at arming refuses to arm), copies the flags into the tick's health
record, and hands them back when the run ends, so a request made after the run counts too.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from harness.errors import StoppedByOperator
from harness.realtime.interrupts import OperatorSignals, installed_signals

__all__ = ["OperatorSignals", "installed_signals", "interruptible", "request_pending", "stop_if_requested"]


def request_pending() -> bool:
    """True if the installed :class:`OperatorSignals` holds an operator's request."""
    signals = installed_signals()
    return signals is not None and signals.requested


def stop_if_requested(where: str) -> None:
    """A safe point before the loop: end the command if the operator asked to stop.

    Parameters
    ----------
    where : str
        What the command was doing, e.g. ``"while starting the virtual rig"`` (for the outcome line).

    Raises
    ------
    StoppedByOperator
        When a Ctrl-C or SIGTERM is pending: nothing has moved yet; the caller's cleanup runs as
        the exception passes, and the command line ends with exit status 4 and its outcome line.
    """
    signals = installed_signals()
    if signals is not None and signals.requested:
        raise StoppedByOperator(where, signals.what)


@contextmanager
def interruptible(where: str) -> Iterator[None]:
    """A block that waits in pure Python (a question at the terminal): a Ctrl-C ends it at once.

    Flags alone would leave ``input()`` waiting (it resumes after a handler that returns). A
    request already pending ends the command before the block starts.

    Raises
    ------
    StoppedByOperator
        On a Ctrl-C or SIGTERM pending before or received during the block.
    """
    signals = installed_signals()
    if signals is None:
        yield
        return
    stop_if_requested(where)
    raising, signals.raise_interrupt = signals.raise_interrupt, True
    try:
        yield
    except KeyboardInterrupt as err:
        if isinstance(err, StoppedByOperator):
            raise
        raise StoppedByOperator(where, signals.what) from None
    finally:
        signals.raise_interrupt = raising
