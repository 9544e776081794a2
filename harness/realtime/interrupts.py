"""Ctrl-C and SIGTERM, for every process of the harness.

- :class:`OperatorSignals`: handlers that only set flags (the operator's stop and trip requests), for
  the command line from its first line and for the loop (:mod:`harness.loop.operator` says how they
  are used); a set installed over another takes its pending requests over and hands them back.
- :func:`stop_on_signals`: Ctrl-C and SIGTERM as a clean stop (KeyboardInterrupt), for the processes
  that run until stopped (the virtual rig).
"""

from __future__ import annotations

import contextlib
import signal
import threading
from collections.abc import Callable, Iterator
from types import FrameType
from typing import Any, TypeAlias

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



@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Ctrl-C and SIGTERM raise KeyboardInterrupt (a clean stop), even if the shell started
    this process with SIGINT ignored, as it does for background jobs; the handlers before
    are put back afterwards (``main`` may run in a longer-lived process).

    A request the command line's handlers hold already (a Ctrl-C during the imports,
    :mod:`harness.loop.operator`) stops at once: it is never forgotten.
    """
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    early = installed_signals()
    before = signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)
    signal.signal(signal.SIGINT, interrupt)
    signal.signal(signal.SIGTERM, interrupt)
    try:
        if early is not None and early.requested:
            raise KeyboardInterrupt
        yield
    finally:
        signal.signal(signal.SIGINT, before[0])
        signal.signal(signal.SIGTERM, before[1])
