"""The ``loop:`` section of a profile: rate, scheduling, run phases and real-time requests."""

from __future__ import annotations

from dataclasses import dataclass, field

from harness.config.schema import quantity
from harness.realtime.host import RealtimeConfig


@dataclass(frozen=True)
class LoopConfig:
    """How the control loop runs a test."""

    rate_hz: float = quantity(500.0, unit="Hz", gt=0, le=5000, doc="tick rate of the loop")
    spin_s: float = quantity(200e-6, unit="s", ge=0, doc="busy-wait before each deadline (at most a tenth of the period)")
    arm_timeout_s: float = quantity(3.0, unit="s", gt=0, doc="how long to wait for every pre-arm check to pass")
    settle_s: float = quantity(0.2, unit="s", ge=0, doc="ARMED time before the table starts")
    tail_s: float = quantity(1.0, unit="s", ge=0, doc="RUNNING time after the record ends")
    after_s: float = quantity(0.1, unit="s", ge=0, doc="ticks kept running after DONE/TRIPPED (zero force, drive off)")
    lockstep_timeout_s: float = quantity(2.0, unit="s", gt=0, doc="longest wait for the rig's step in lockstep")
    realtime: RealtimeConfig = field(default_factory=RealtimeConfig)
