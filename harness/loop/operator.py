"""Operator requests through signals: Ctrl-C stops safely, a second Ctrl-C or SIGTERM trips.

The handlers only set flags: no exception is ever raised inside whatever the process happens
to run when the signal arrives (a compiler library's callback swallowed a KeyboardInterrupt
raised there, and the test ran anyway: issue 30). The command line installs a set of them as
the very first thing it does (:func:`harness.cli.main`); the phases before the loop look at
it at safe points (:func:`stop_if_requested`, which ends the command "stopped by the operator
before anything moved"); the loop installs its own set, which takes over a request already
pending (a stop pending at arming refuses to arm), copies the flags into the tick's health
record, and hands them back when the run ends, so a request made after the run counts too.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any, TypeAlias

from harness.errors import StoppedByOperator

#: What ``signal.signal`` takes and returns: a handler, ``SIG_DFL``/``SIG_IGN`` (ints), or None
#: (a handler not installed from Python).
SignalHandler: TypeAlias = Callable[[int, FrameType | None], Any] | int | None


class OperatorSignals:
    """Installs SIGINT/SIGTERM handlers that set flags (main thread only); restores the previous ones.

    Handlers are installed even where the process started with SIGINT ignored (a shell does
    that to its background jobs): ``kill -INT`` from the operator must count.

    Attributes
    ----------
    stop_requested : bool
        First Ctrl-C: ramp the force down and disable the drive (safe stop).
    trip_requested : bool
        Second Ctrl-C or SIGTERM: trip (zero force, drive off, at once).
    interrupts : int
        Ctrl-C received so far.
    raise_interrupt : bool
        Also raise KeyboardInterrupt (after setting the flags): only where the process waits in
        pure Python, never in foreign code (:func:`interruptible`).
    """

    def __init__(self) -> None:
        self.stop_requested = False
        self.trip_requested = False
        self.interrupts = 0
        self.raise_interrupt = False
        self._previous: dict[int, SignalHandler] = {}

    @property
    def requested(self) -> bool:
        """True once the operator asked to stop or trip (or SIGTERM came)."""
        return self.stop_requested or self.trip_requested

    @property
    def what(self) -> str:
        """The request, for a message: ``Ctrl-C``, ``a second Ctrl-C`` or ``SIGTERM``."""
        if self.trip_requested and self.interrupts < 2:
            return "SIGTERM"
        return "a second Ctrl-C" if self.interrupts >= 2 else "Ctrl-C"

    def _on_interrupt(self, signum: int, frame: FrameType | None) -> None:
        self.interrupts += 1
        if self.interrupts == 1:
            self.stop_requested = True
        else:
            self.trip_requested = True
        if self.raise_interrupt:
            raise KeyboardInterrupt

    def _on_terminate(self, signum: int, frame: FrameType | None) -> None:
        self.trip_requested = True
        if self.raise_interrupt:
            raise KeyboardInterrupt

    def take_over(self, other: OperatorSignals | None) -> None:
        """Add the requests ``other`` holds to this one's (a request is never forgotten)."""
        if other is None or other is self:
            return
        self.interrupts = max(self.interrupts, other.interrupts)
        self.stop_requested |= other.stop_requested
        self.trip_requested |= other.trip_requested

    def install(self) -> OperatorSignals:
        """Install the handlers if this is the main thread (otherwise signals stay as they are).

        Requests pending in the handlers replaced (an earlier :class:`OperatorSignals`) are taken over.
        """
        if threading.current_thread() is threading.main_thread():
            self._previous[signal.SIGINT] = signal.signal(signal.SIGINT, self._on_interrupt)
            self._previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, self._on_terminate)
            for handler in self._previous.values():
                self.take_over(owner_of(handler))
        return self

    def restore(self) -> None:
        """Put the previous handlers back, handing them this one's requests."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
            owner = owner_of(handler)
            if owner is not None:
                owner.take_over(self)
        self._previous.clear()

    def __enter__(self) -> OperatorSignals:
        return self.install()

    def __exit__(self, *exc) -> None:
        self.restore()


def owner_of(handler: SignalHandler) -> OperatorSignals | None:
    """The :class:`OperatorSignals` whose handler ``handler`` is, if it is one."""
    owner = getattr(handler, "__self__", None)
    return owner if isinstance(owner, OperatorSignals) else None


def installed_signals() -> OperatorSignals | None:
    """The :class:`OperatorSignals` whose SIGINT handler is installed now, if any."""
    return owner_of(signal.getsignal(signal.SIGINT))


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
