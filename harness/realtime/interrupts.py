"""Ctrl-C and SIGTERM as a clean stop, for every process of the harness that runs until stopped."""

from __future__ import annotations

import contextlib
import signal
from collections.abc import Iterator


@contextlib.contextmanager
def stop_on_signals() -> Iterator[None]:
    """Ctrl-C and SIGTERM raise KeyboardInterrupt (a clean stop), even if the shell started
    this process with SIGINT ignored, as it does for background jobs; the handlers before
    are put back afterwards (``main`` may run in a longer-lived process).

    A request the command line's handlers hold already (a Ctrl-C during the imports,
    :mod:`harness.loop.operator`) stops at once: it is never forgotten.
    """
    from harness.loop.operator import installed_signals

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
