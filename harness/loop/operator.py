"""Operator requests through signals: Ctrl-C stops safely, a second Ctrl-C or SIGTERM trips.

The handlers only set flags; the loop copies them into the tick's health record, and
the supervisor acts on them in the next tick (ramp down and disable, or trip at once).
The previous handlers are restored when the run ends.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType
from typing import Any, TypeAlias

#: What ``signal.signal`` takes and returns: a handler, ``SIG_DFL``/``SIG_IGN`` (ints), or None
#: (a handler not installed from Python).
SignalHandler: TypeAlias = Callable[[int, FrameType | None], Any] | int | None


class OperatorSignals:
    """Installs SIGINT/SIGTERM handlers for the duration of a run (main thread only).

    Attributes
    ----------
    stop_requested : bool
        First Ctrl-C: ramp the force down and disable the drive (safe stop).
    trip_requested : bool
        Second Ctrl-C or SIGTERM: trip (zero force, drive off, at once).
    """

    def __init__(self) -> None:
        self.stop_requested = False
        self.trip_requested = False
        self.interrupts = 0
        self._previous: dict[int, SignalHandler] = {}

    def _on_interrupt(self, signum: int, frame: FrameType | None) -> None:
        self.interrupts += 1
        if self.interrupts == 1:
            self.stop_requested = True
        else:
            self.trip_requested = True

    def _on_terminate(self, signum: int, frame: FrameType | None) -> None:
        self.trip_requested = True

    def install(self) -> OperatorSignals:
        """Install the handlers if this is the main thread (otherwise signals stay as they are)."""
        if threading.current_thread() is threading.main_thread():
            self._previous[signal.SIGINT] = signal.signal(signal.SIGINT, self._on_interrupt)
            self._previous[signal.SIGTERM] = signal.signal(signal.SIGTERM, self._on_terminate)
        return self

    def restore(self) -> None:
        """Put the previous handlers back."""
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous.clear()

    def __enter__(self) -> OperatorSignals:
        return self.install()

    def __exit__(self, *exc) -> None:
        self.restore()
