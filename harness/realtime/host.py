"""Ask the operating system for real-time treatment: SCHED_FIFO, CPU affinity, locked memory.

Each request is tried only when the profile asks for it, and each result says plainly
whether it was granted and, if not, why (for example "SCHED_FIFO refused: operation
not permitted; run as root or grant CAP_SYS_NICE / an rtprio limit"). The garbage
collector is frozen and disabled for the run (its pauses show as 10-20 ms spikes:
benchmarks/README.md, "Timing facts the loop is built on") and restored afterwards.

SCHED_FIFO (``loop.realtime.fifo_priority``) is ``auto`` by default: the loop's thread takes
priority :data:`~harness.realtime.config.AUTO_LOOP_PRIORITY` and the virtual rig's serving thread
:data:`~harness.realtime.config.AUTO_RIG_PRIORITY`
where the process may (root, CAP_SYS_NICE or an rtprio limit), and runs as before where it may
not, with one line saying how to permit it. The policy is per thread (Linux); the process's other
threads (the recorder, the rig's journal), which share the interpreter's lock, go to
:data:`LOCK_SHARER_PRIORITY` so that ordinary load cannot preempt them while they hold it. All is
given back when the run ends (:func:`restore_scheduling`), so what follows (the reference
simulation, the report) never runs at real-time priority. docs/SAFETY.md, "Real-time priority and the host", says what
keeps a real-time loop from starving the machine.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import os
import threading
from dataclasses import dataclass, field

from harness.realtime.config import AUTO, AUTO_LOOP_PRIORITY, RealtimeConfig

_MCL_CURRENT, _MCL_FUTURE = 1, 2


#: The other threads of a process whose thread takes SCHED_FIFO: they share its interpreter lock,
#: and one that ordinary load preempts while it holds the lock stalls the real-time thread for a
#: time slice (priority inversion through the lock: 6-23 ms gaps on a machine with every core busy,
#: benchmarks/README.md). At the lowest real-time priority ordinary load cannot preempt them, and
#: the real-time thread still can.
LOCK_SHARER_PRIORITY = 1
#: How to permit SCHED_FIFO, for the line said when it was not permitted.
HOW_TO_PERMIT = (
    "to permit it: run as root, or give the interpreter CAP_SYS_NICE (sudo setcap cap_sys_nice+ep "
    "$(readlink -f .venv/bin/python)), or an rtprio limit (a line '<user> - rtprio 90' in "
    "/etc/security/limits.conf, then log in again)"
)


@dataclass
class Scheduling:
    """What SCHED_FIFO request was made for this thread and what it got.

    Attributes
    ----------
    asked : int or "auto"
        ``fifo_priority`` as the profile gives it.
    priority : int
        The priority tried (0: none was).
    granted : bool
    line : str
        One line for the console and ``metadata.json``; "" when nothing was asked.
    previous : tuple of (int, int)
        The thread's policy and priority before, given back by :func:`restore_scheduling`.
    sharers : list of (int, int, int)
        The process's other threads raised to :data:`LOCK_SHARER_PRIORITY`: native id, policy and
        priority before.
    """

    asked: int | str = 0
    priority: int = 0
    granted: bool = False
    line: str = ""
    previous: tuple[int, int] = (0, 0)
    sharers: list[tuple[int, int, int]] = field(default_factory=list)

    def as_dict(self) -> dict:
        """For ``metadata.json``: asked, the policy in effect and its priority."""
        return {"asked": self.asked, "policy": "SCHED_FIFO" if self.granted else "normal",
                "priority": self.priority if self.granted else 0}


def request_fifo(asked: int | str, auto_priority: int = AUTO_LOOP_PRIORITY, what: str = "the loop") -> Scheduling:
    """Ask SCHED_FIFO for the calling thread; never raises for a refusal, says it instead.

    Parameters
    ----------
    asked : int or "auto"
        A priority (1-99), 0 (ask nothing) or ``auto`` (``auto_priority`` where permitted).
    auto_priority : int
        The priority ``auto`` stands for.
    what : str
        Whose priority it is, for the line (``the loop``, ``the virtual rig``).
    """
    previous = (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority)
    if asked == 0:
        return Scheduling(asked, 0, False, "", previous)
    priority = auto_priority if asked == AUTO else int(asked)
    label = f"SCHED_FIFO priority {priority} for {what}" + (" (auto)" if asked == AUTO else "")
    try:  # reset on fork: a process started from this thread (the live console's) starts with normal scheduling
        os.sched_setscheduler(0, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(priority))
    except OSError as err:
        reason = err.strerror or str(err)
        if asked == AUTO:
            line = f"{label}: not permitted here ({reason}); running with normal scheduling; {HOW_TO_PERMIT}"
        else:
            line = (f"{label}: refused ({reason}); run as root or grant CAP_SYS_NICE or an rtprio limit "
                    "(/etc/security/limits.conf); running with normal scheduling")
        return Scheduling(asked, priority, False, line, previous)
    sharers = _raise_lock_sharers()
    note = f"; {len(sharers)} other thread(s) of the process at priority {LOCK_SHARER_PRIORITY}" if sharers else ""
    return Scheduling(asked, priority, True, f"{label}: granted{note}", previous, sharers)


def _raise_lock_sharers() -> list[tuple[int, int, int]]:
    """Put the process's other normal threads at :data:`LOCK_SHARER_PRIORITY`; what they had before."""
    me = threading.get_native_id()
    raised = []
    for thread in threading.enumerate():
        tid = thread.native_id
        if tid is None or tid == me:
            continue
        try:
            policy = os.sched_getscheduler(tid)
            if policy & ~os.SCHED_RESET_ON_FORK in (os.SCHED_FIFO, os.SCHED_RR):
                continue  # a real-time thread of its own (the in-process rig's): leave it
            before = os.sched_getparam(tid).sched_priority
            os.sched_setscheduler(tid, os.SCHED_FIFO | os.SCHED_RESET_ON_FORK, os.sched_param(LOCK_SHARER_PRIORITY))
        except OSError:
            continue  # gone, or not ours to change: it keeps what it had
        raised.append((tid, policy, before))
    return raised


def restore_scheduling(scheduling: Scheduling) -> None:
    """Give the calling thread, and the threads raised with it, back the policy they had before :func:`request_fifo`."""
    if scheduling.granted:
        policy, priority = scheduling.previous
        os.sched_setscheduler(0, policy, os.sched_param(priority))
        for tid, sharer_policy, sharer_priority in scheduling.sharers:
            try:
                os.sched_setscheduler(tid, sharer_policy, os.sched_param(sharer_priority))
            except OSError:
                pass  # the thread has ended
        scheduling.sharers.clear()
        scheduling.granted = False


@dataclass
class RealtimeReport:
    """What was asked and what was granted, one line each."""

    lines: list[str] = field(default_factory=list)
    gc_was_enabled: bool = True
    scheduling: Scheduling = field(default_factory=Scheduling)
    #: True when :func:`apply_realtime` made the request itself (and :func:`restore_realtime` gives it back).
    owns_scheduling: bool = False


def _affinity(cpus: tuple[int, ...], report: RealtimeReport) -> None:
    try:
        os.sched_setaffinity(0, set(cpus))
        report.lines.append(f"CPU affinity {sorted(cpus)}: granted")
    except (OSError, ValueError) as err:
        report.lines.append(f"CPU affinity {sorted(cpus)}: refused ({err}); available CPUs {sorted(os.sched_getaffinity(0))}")


def _lock_memory(report: RealtimeReport) -> None:
    libc_name = ctypes.util.find_library("c")
    try:
        libc = ctypes.CDLL(libc_name, use_errno=True)
        if libc.mlockall(_MCL_CURRENT | _MCL_FUTURE) != 0:
            errno = ctypes.get_errno()
            raise OSError(errno, os.strerror(errno))
        report.lines.append("locked memory (mlockall): granted")
    except (OSError, AttributeError) as err:
        report.lines.append(f"locked memory (mlockall): refused ({err}); raise the memlock limit (ulimit -l) or run as root")


def freeze_garbage() -> None:
    """Collect once, then move every object alive into the collector's permanent generation.

    Full collections then scan only what was made since, not the start-up's hundreds of thousands of
    objects: a rig process before it serves (collector left on), the loop for a run (then disabled too).
    """
    gc.collect()
    gc.freeze()


def apply_realtime(config: RealtimeConfig, scheduling: Scheduling | None = None) -> RealtimeReport:
    """Apply what ``config`` asks for; never raises for a refusal, reports it instead.

    ``scheduling``: a request already made (the session makes it before its pre-flight check,
    so that the check measures the scheduling the run gets); None makes it here.
    """
    owns = scheduling is None
    scheduling = request_fifo(config.fifo_priority) if scheduling is None else scheduling
    report = RealtimeReport(gc_was_enabled=gc.isenabled(), scheduling=scheduling, owns_scheduling=owns)
    if scheduling.line:
        report.lines.append(scheduling.line)
    if config.cpu_affinity:
        _affinity(config.cpu_affinity, report)
    if config.lock_memory:
        _lock_memory(report)
    if config.disable_gc:
        freeze_garbage()
        gc.disable()
        report.lines.append("garbage collector: frozen and disabled for the run")
    return report


def restore_realtime(report: RealtimeReport) -> None:
    """Undo the garbage-collector change, and the scheduling if :func:`apply_realtime` asked for it."""
    gc.unfreeze()
    if report.gc_was_enabled:
        gc.enable()
    if report.owns_scheduling:
        restore_scheduling(report.scheduling)
