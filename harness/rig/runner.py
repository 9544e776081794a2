"""The rig's service loop: wall-clock ticks in real time, frame-driven in lockstep.

Real time: a :class:`~harness.realtime.scheduler.FixedRateScheduler` wakes the rig at
the sensor rate against absolute deadlines, without the busy-wait spin (the rig
shares two cores with the harness loop; a tick's lateness only delays frames, the
physics stays on the sub-step grid). Lockstep: the loop blocks on the bus for up
to ``poll_timeout_s``, so it steps as soon as a command arrives and still runs the
drive watchdog every ``poll_timeout_s`` when commands stop. The mode may change at
any time through RIG_CONTROL; the loop follows. An exception ends the loop and is
kept in ``rig.error`` for the owner (a thread cannot raise to it).

A rig process freezes its garbage collector before it serves (:func:`harness.realtime.host.freeze_garbage`, called
by :func:`harness.runs.rig_service.serve_rig`): the rig emulates devices that never pause, and a
full collection over everything its start-up built (compiled kernels, the DBC, the record)
stopped it 33-78 ms inside User-Mode Linux, long enough for its sensor frames to age past a
loop's limit.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

from harness.realtime.config import AUTO_RIG_PRIORITY
from harness.realtime.host import Scheduling, request_fifo, restore_scheduling
from harness.realtime.scheduler import FixedRateScheduler


def serve(
    rig, stop: threading.Event, poll_timeout_s: float = 0.002, sleep: Callable[[float], None] | None = None,
    fifo_priority: int | str = 0,
) -> None:
    """Serve ``rig`` (a :class:`~harness.rig.virtual_rig.VirtualRig`) until ``stop`` is set.

    Parameters
    ----------
    rig : VirtualRig
    stop : threading.Event
    poll_timeout_s : float
        Longest blocking wait for a frame in lockstep (s).
    sleep : callable, optional
        Sleep function of the real-time scheduler (default ``time.sleep``).
    fifo_priority : int or "auto"
        ``loop.realtime.fifo_priority``: SCHED_FIFO for this thread while it serves in real time
        (``auto``: :data:`~harness.realtime.config.AUTO_RIG_PRIORITY`, one below the loop, where
        permitted); normal scheduling in lockstep, where the rig runs flat out.
    """
    try:
        _loop(rig, stop, poll_timeout_s, sleep, fifo_priority)
    except Exception as err:  # noqa: BLE001 - a thread cannot raise to its owner: keep it for VirtualRig.error
        rig.error = err


def _loop(
    rig, stop: threading.Event, poll_timeout_s: float, sleep: Callable[[float], None] | None, fifo_priority: int | str,
) -> None:
    kwargs = {"sleep": sleep} if sleep is not None else {}
    scheduler = FixedRateScheduler(rig.schedule.sensor_period_s, spin_s=0.0, clock=rig.clock, **kwargs)
    started = False
    scheduling: Scheduling | None = None
    try:
        while not stop.is_set():
            if rig.lockstep:
                if scheduling is not None:
                    restore_scheduling(scheduling)
                    scheduling = None
                started = False
                rig.service(rig.clock(), wait_s=poll_timeout_s)
                continue
            if not started:
                scheduling = request_fifo(fifo_priority, AUTO_RIG_PRIORITY, "the virtual rig")
                if scheduling.line:
                    rig.journal.note(scheduling.line)  # the rig's terminal prints it, as it prints its other changes
                scheduler.start()
                started = True
            scheduler.wait()
            rig.service(rig.clock())
    finally:
        if scheduling is not None:
            restore_scheduling(scheduling)
