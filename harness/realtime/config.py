"""The ``loop.realtime`` section of a profile: what the loop asks of the host's scheduler and memory.

Settings only; :mod:`harness.realtime.host` applies them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Final, Literal

from harness.config.schema import quantity

#: ``fifo_priority: auto``: use SCHED_FIFO where the process may, else normal scheduling.
AUTO: Final = "auto"
#: The loop's priority under ``auto``: above the kernel's threaded interrupt handlers (50) and
#: below its watchdog and migration threads (99), as real-time control loops usually take.
AUTO_LOOP_PRIORITY = 80
#: The virtual rig's process under ``auto``: one below the loop, which wins a shared core.
AUTO_RIG_PRIORITY = 79


@dataclass(frozen=True)
class RealtimeConfig:
    """Real-time requests of the loop (profile section ``loop.realtime``)."""

    fifo_priority: int | Literal["auto"] = quantity(
        AUTO, ge=0, le=99,
        doc="SCHED_FIFO priority; auto = 80 for the loop (79 for the virtual rig) where permitted, else normal; 0 = do not ask",
    )
    cpu_affinity: tuple[int, ...] = quantity((), ge=0, doc="CPUs to pin the loop to; empty = do not pin")
    lock_memory: bool = field(default=False, metadata={"doc": "mlockall(MCL_CURRENT | MCL_FUTURE)"})
    disable_gc: bool = field(default=True, metadata={"doc": "freeze and disable the garbage collector during a run"})
