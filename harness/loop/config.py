"""The ``loop:`` section of a profile: scheduling, run phases and real-time requests (the rate is ``control.rate_hz``)."""

from __future__ import annotations

from dataclasses import dataclass, field

from harness.config.schema import quantity
from harness.realtime.config import RealtimeConfig


@dataclass(frozen=True)
class LoopConfig:
    """How the control loop runs a test.

    The loop ticks at ``control.rate_hz`` (:class:`harness.control.config.ControlConfig`), the one
    rate of a profile: the controller samples once per tick and the actuator command goes once per
    tick, so the rate is set in one place and the others derive from it.
    """

    spin_s: float = quantity(200e-6, unit="s", ge=0, doc="busy-wait before each deadline (at most a tenth of the period)")
    arm_timeout_s: float = quantity(3.0, unit="s", gt=0, doc="how long to wait for every pre-arm check to pass")
    settle_s: float = quantity(0.2, unit="s", ge=0, doc="ARMED time before the table starts")
    tail_s: float = quantity(1.0, unit="s", ge=0, doc="RUNNING time after the record ends")
    after_s: float = quantity(0.1, unit="s", ge=0, doc="ticks kept running after DONE/TRIPPED (zero force, drive off)")
    lockstep_timeout_s: float = quantity(2.0, unit="s", gt=0, doc="longest wait for the rig's step in lockstep")
    realtime: RealtimeConfig = field(default_factory=RealtimeConfig)
