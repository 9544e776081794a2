"""The stall budget on a fake clock, through the real loop, tick, drivers and virtual rig.

The loop runs its real-time path (scheduler, poll, ages, supervisor) against a clock
that moves only when the loop sleeps or a test stalls it; the virtual rig is serviced
at every moment the clock moves to, as a rig in another process would keep running
while the loop is away. A stall is injected inside one tick, after the controller ran,
so the command that follows the stall is the first one the loop writes afterwards.
What reaches the bus is taken from the writer's calls (the frames that were sent).
"""

from __future__ import annotations

import dataclasses
import itertools
import re
import uuid

import pytest

from harness.canbus.link import open_harness, open_rig
from harness.control.factory import build_controller_for_rig, make_friction_estimator
from harness.loop.runner import ControlLoop
from harness.loop.tick import ControlTick
from harness.profile import load_profile
from harness.rig.parts import RigParts
from harness.rig.virtual_rig import VirtualRig
from harness.runs.options import StudyOptions, prepare_motion
from harness.safety.supervisor import Supervisor

RATE_HZ = 500.0
PERIOD_S = 1.0 / RATE_HZ
STALL_AT_RUN_S = 0.5  # record time at which the loop stalls


class FakeClock:
    """Moves on sleep and on stalls; every read advances it by 1 us, so a spin ends."""

    def __init__(self, on_move) -> None:
        self.now = 100.0
        self.on_move = on_move

    def __call__(self) -> float:
        self.now += 1e-6
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += max(0.0, seconds)
        self.on_move(self.now)


class StallingController:
    """Wraps the rig's controller: at ``stall_at`` the tick stalls for ``stall_s``, then the demand steps."""

    def __init__(self, inner, clock: FakeClock, stall_at: float, stall_s: float, step_N: float) -> None:
        self.inner, self.clock = inner, clock
        self.stall_at, self.stall_s, self.step_N = stall_at, stall_s, step_N
        self.stalled_at: float | None = None

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def update(self, t, dt, meas, friction, state):
        force = self.inner.update(t, dt, meas, friction, state)
        if self.stalled_at is None and t >= self.stall_at:
            self.stalled_at = t
            self.clock.sleep(self.stall_s)  # the host took the CPU in the middle of this tick
        if self.stalled_at is not None and self.stalled_at < t <= self.stalled_at + self.stall_s + 0.01:
            force += self.step_N  # the demand after the stall differs by a step the rate limit must spread
        return force


def _run(stall_s: float, step_N: float = 0.0):
    profile = load_profile(None, overrides=[f"control.rate_hz={RATE_HZ}"])
    profile = dataclasses.replace(profile, can=dataclasses.replace(profile.can, interface="virtual"))
    motion = prepare_motion(profile, StudyOptions(duration_s=1.0))
    can = profile.can_settings("virtual", f"stall-{uuid.uuid4().hex[:8]}")
    rig_link, link = open_rig(can), open_harness(can)
    rig = None

    def service(now: float) -> None:
        if rig is not None:
            rig.service(now)

    clock = FakeClock(service)
    try:
        rig = VirtualRig(RigParts.from_profile(profile), motion, rig_link, step_period_s=PERIOD_S, lockstep=False, clock=clock,
                         can_config=can)
        supervisor = Supervisor(profile.safety, period_s=PERIOD_S)
        settle = profile.loop.settle_s
        controller = StallingController(build_controller_for_rig(profile, "phi"), clock, settle + STALL_AT_RUN_S, stall_s, step_N)
        estimator = make_friction_estimator(profile)
        tick = ControlTick(link, controller, estimator, supervisor, None, heartbeat_every=5)
        sent: list[tuple[float, float, bool]] = []
        command = tick.writer.command

        def spy(force_N, enable, now):
            sent.append((controller.stalled_at, force_N, enable))
            return command(force_N, enable, now)

        tick.writer.command = spy
        events: list[tuple[str, str]] = []
        tick._sink = lambda t, kind, name, detail: events.append((name, detail))
        rig.on_start = None
        loop = ControlLoop(tick, profile.loop, RATE_HZ, motion.duration_s, on_start=lambda t: _start_table(rig, t),
                           clock=clock, sleep=clock.sleep)
        result = loop.run()
    finally:
        link.close()
        rig_link.close()
    return result, loop, controller, sent, events, profile


def _start_table(rig: VirtualRig, t: float) -> None:
    rig.table.start()
    rig.faults.reset_schedule()


def _commands_around_the_stall(sent, controller):
    before = [(f, e) for stalled, f, e in sent if stalled is None]
    after = [(f, e) for stalled, f, e in sent if stalled is not None]
    return before, after


def test_a_stall_inside_the_budget_is_ridden_through_with_no_force_step_beyond_the_rate_limit():
    stall_s = 0.015  # 7 missed periods, inside the 20 ms budget
    result, loop, controller, sent, events, profile = _run(stall_s, step_N=5_000.0)
    assert result.outcome == "completed", result.trip_reason
    assert loop.stalls_ridden_through == loop.counts.stalls == 1
    assert stall_s <= loop.longest_stall_s <= stall_s + 2 * PERIOD_S
    ridden = [detail for name, detail in events if name == "stall_ridden_through"]
    assert len(ridden) == 1 and "missed periods" in ridden[0]
    before, after = _commands_around_the_stall(sent, controller)
    # the command the tick that stalled wrote, then the first command after the stall
    last_before, first_after = after[0][0], after[1][0]
    max_step = profile.safety.force.max_force_rate_N_per_s * PERIOD_S
    assert abs(first_after - last_before) <= max_step * (1 + 1e-9)
    assert abs(first_after - last_before) == pytest.approx(max_step, rel=1e-6)  # the step demand was limited, not passed
    steps = [abs(b[0] - a[0]) for a, b in itertools.pairwise(after) if a[1] and b[1]]
    assert max(steps) <= max_step * (1 + 1e-9)


def test_a_stall_beyond_the_budget_trips_on_the_first_tick_after_it():
    stall_s = 0.045  # 22 missed periods: beyond the 20 ms budget, inside the 50 ms drive watchdog
    result, loop, controller, sent, events, profile = _run(stall_s)
    assert result.outcome == "tripped" and result.trip_reason == "loop_stall"
    before, after = _commands_around_the_stall(sent, controller)
    assert after[0][1]  # the tick that stalled had written its command before the stall
    assert after[1] == (0.0, False)  # the first tick after the stall: zero force, drive disabled
    detail = [d for name, d in events if name == "loop_stall"][0]
    missed = int(re.search(r"\((\d+) missed periods\)", detail).group(1))
    assert missed in (21, 22) and "45.0 ms" in detail and "host" in detail  # counted by missed time, not one overrun


def test_a_stall_longer_than_the_drive_watchdog_trips_loop_stall_not_drive_fault_and_logs_the_gap():
    """Issue 30: a 101 ms stall let the drive's 50 ms heartbeat watchdog fire; the trip names the stall, with its gap."""
    stall_s = 0.101
    result, loop, controller, sent, events, profile = _run(stall_s)
    assert stall_s > profile.rig.drive.watchdog_timeout_s
    assert result.outcome == "tripped" and result.trip_reason == "loop_stall", (result.trip_reason, result.trip_detail)
    assert "101.0 ms without a command" in result.trip_detail or "101.1 ms without a command" in result.trip_detail
    assert "(HEARTBEAT_WATCHDOG) after it, a consequence of the stall" in result.trip_detail  # the drive did fault
    gaps = [detail for name, detail in events if name == "stall_past_budget"]
    assert len(gaps) == 1 and loop.gaps_past_budget == 1
    start, end = (float(x) for x in re.search(r"from (\S+) s to (\S+) s \(loop time\)", gaps[0]).groups())
    assert end - start == pytest.approx(loop.longest_stall_s, abs=1e-4)  # the console's "longest" is this logged gap
    assert start == pytest.approx(controller.stalled_at, abs=1e-3)  # the tick whose controller stalled began it
    assert "begun in RUNNING" in gaps[0]
    assert "the loop was the estimator, the controller and the compensation for 101.0 ms (control;" in gaps[0]
    assert result.timing["gaps_past_budget"] == 1
