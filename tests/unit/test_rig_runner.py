"""The real-time service loop on an injected clock: the rig follows the clock, nothing sleeps."""

from __future__ import annotations

import threading
import uuid

import can
import pytest

from harness.canbus.config import CanConfig
from harness.profile import load_profile
from harness.rig.parts import RigParts
from harness.rig.runner import serve
from harness.rig.virtual_rig import VirtualRig
from harness.runs.options import StudyOptions, prepare_motion
from tests.conftest import PROFILES


class FakeClock:
    """A clock that only moves when the loop sleeps; stops the loop after ``until_s``."""

    def __init__(self, stop: threading.Event, until_s: float):
        self.t = 100.0
        self.stop = stop
        self.until = self.t + until_s
        self.sleeps = 0

    def __call__(self) -> float:
        return self.t

    def sleep(self, seconds: float) -> None:
        self.sleeps += 1
        self.t += seconds
        if self.t >= self.until:
            self.stop.set()


def test_real_time_loop_advances_with_the_clock_and_publishes_at_the_rates():
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    motion = prepare_motion(profile, StudyOptions(record="synthetic", duration_s=2.0))
    channel = f"runner-{uuid.uuid4().hex[:8]}"
    stop = threading.Event()
    clock = FakeClock(stop, 0.2)
    with can.Bus(interface="virtual", channel=channel) as rig_bus, can.Bus(interface="virtual", channel=channel) as listener:
        rig = VirtualRig(RigParts.from_profile(profile), motion, rig_bus, step_period_s=0.002, lockstep=False, clock=clock,
                         can_config=CanConfig(channel=channel))
        serve(rig, stop, sleep=clock.sleep)
        frames = []
        while (msg := listener.recv(timeout=0)) is not None:
            frames.append(msg.arbitration_id)
    assert clock.sleeps >= 99, "one wait per 2 ms tick"
    assert rig.rig_time_s == pytest.approx(0.2, abs=0.0021), "the plant followed the injected clock"
    assert frames.count(0x30) == pytest.approx(100, abs=2)  # 500 Hz for 0.2 s
    assert frames.count(0x200) == pytest.approx(50, abs=2)  # 250 Hz
    assert frames.count(0x40) == pytest.approx(50, abs=2)  # 250 Hz
    assert frames.count(0x301) == pytest.approx(10, abs=1)  # 50 Hz


def test_freezing_the_garbage_moves_what_is_alive_out_of_the_collectors_reach():
    """A rig process's full collections then scan only what was made after its start-up (harness.rig.runner)."""
    import gc

    from harness.realtime.host import freeze_garbage

    alive = [object() for _ in range(1000)]
    before = gc.get_freeze_count()
    try:
        freeze_garbage()
        assert gc.get_freeze_count() >= before + len(alive)
        assert gc.isenabled(), "the collector stays on: the rig serves for as long as it is left running"
    finally:
        gc.unfreeze()
