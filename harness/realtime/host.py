"""Ask the operating system for real-time treatment: SCHED_FIFO, CPU affinity, locked memory.

Each request is tried only when the profile asks for it, and each result says plainly
whether it was granted and, if not, why (for example "SCHED_FIFO refused: operation
not permitted; run as root or grant CAP_SYS_NICE / an rtprio limit"). The garbage
collector is frozen and disabled for the run (its pauses show as 10-20 ms spikes:
benchmarks/README.md, "Timing facts the loop is built on") and restored afterwards.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
import os
from dataclasses import dataclass, field

from harness.config.schema import quantity

_MCL_CURRENT, _MCL_FUTURE = 1, 2


@dataclass(frozen=True)
class RealtimeConfig:
    """Real-time requests of the loop (profile section ``loop.realtime``)."""

    fifo_priority: int = quantity(0, ge=0, le=99, doc="SCHED_FIFO priority; 0 = do not ask")
    cpu_affinity: tuple[int, ...] = quantity((), ge=0, doc="CPUs to pin the loop to; empty = do not pin")
    lock_memory: bool = field(default=False, metadata={"doc": "mlockall(MCL_CURRENT | MCL_FUTURE)"})
    disable_gc: bool = field(default=True, metadata={"doc": "freeze and disable the garbage collector during a run"})


@dataclass
class RealtimeReport:
    """What was asked and what was granted, one line each."""

    lines: list[str] = field(default_factory=list)
    gc_was_enabled: bool = True


def _fifo(priority: int, report: RealtimeReport) -> None:
    try:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
        report.lines.append(f"SCHED_FIFO priority {priority}: granted")
    except (PermissionError, OSError) as err:
        report.lines.append(
            f"SCHED_FIFO priority {priority}: refused ({err.strerror or err}); run as root or grant CAP_SYS_NICE "
            "or an rtprio limit (/etc/security/limits.conf); running with normal scheduling"
        )


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


def apply_realtime(config: RealtimeConfig) -> RealtimeReport:
    """Apply what ``config`` asks for; never raises for a refusal, reports it instead."""
    report = RealtimeReport(gc_was_enabled=gc.isenabled())
    if config.fifo_priority:
        _fifo(config.fifo_priority, report)
    if config.cpu_affinity:
        _affinity(config.cpu_affinity, report)
    if config.lock_memory:
        _lock_memory(report)
    if config.disable_gc:
        gc.collect()
        gc.freeze()
        gc.disable()
        report.lines.append("garbage collector: frozen and disabled for the run")
    return report


def restore_realtime(report: RealtimeReport) -> None:
    """Undo the garbage-collector change (scheduling ends with the process)."""
    gc.unfreeze()
    if report.gc_was_enabled:
        gc.enable()
