"""SCHED_FIFO where the process may have it: the decision, the line said either way, the priority given back."""

from __future__ import annotations

import os

import pytest

from harness.profile import load_profile
from harness.realtime import host
from harness.realtime.config import AUTO, AUTO_LOOP_PRIORITY, AUTO_RIG_PRIORITY, RealtimeConfig
from harness.realtime.host import (
    apply_realtime,
    request_fifo,
    restore_realtime,
    restore_scheduling,
)
from harness.rig.journal import RigJournal


class FakeScheduler:
    """os.sched_* for one thread: records what was set, refuses SCHED_FIFO unless permitted."""

    def __init__(self, permitted: bool):
        self.permitted = permitted
        self.policy, self.priority = os.SCHED_OTHER, 0
        self.calls: list[tuple[int, int]] = []
        self.others: dict[int, tuple[int, int]] = {}

    def setscheduler(self, pid: int, policy: int, param) -> None:
        policy &= ~os.SCHED_RESET_ON_FORK  # the flag rides along; what was set is the policy
        if policy == os.SCHED_FIFO and not self.permitted:
            raise PermissionError(1, "Operation not permitted")
        if pid != 0:  # another thread of the process (a lock sharer)
            self.others[pid] = (policy, param.sched_priority)
            return
        self.calls.append((policy, param.sched_priority))
        self.policy, self.priority = policy, param.sched_priority

    def getscheduler(self, pid: int) -> int:
        return self.others.get(pid, (os.SCHED_OTHER, 0))[0] if pid else self.policy

    def getparam(self, pid: int):
        return os.sched_param(self.others.get(pid, (os.SCHED_OTHER, 0))[1] if pid else self.priority)


@pytest.fixture
def fake(monkeypatch):
    def install(permitted: bool) -> FakeScheduler:
        scheduler = FakeScheduler(permitted)
        monkeypatch.setattr(host.os, "sched_setscheduler", scheduler.setscheduler)
        monkeypatch.setattr(host.os, "sched_getscheduler", scheduler.getscheduler)
        monkeypatch.setattr(host.os, "sched_getparam", scheduler.getparam)
        return scheduler

    return install


def test_auto_is_the_default_of_the_schema_and_of_the_shipped_profile():
    assert RealtimeConfig().fifo_priority == AUTO
    assert load_profile().loop.realtime.fifo_priority == AUTO


def test_auto_takes_fifo_where_permitted_and_gives_it_back(fake):
    scheduler = fake(permitted=True)
    scheduling = request_fifo(AUTO)
    assert scheduling.granted and scheduling.priority == AUTO_LOOP_PRIORITY
    assert (scheduler.policy, scheduler.priority) == (os.SCHED_FIFO, AUTO_LOOP_PRIORITY)
    assert scheduling.line.startswith(f"SCHED_FIFO priority {AUTO_LOOP_PRIORITY} for the loop (auto): granted")
    assert scheduling.as_dict() == {"asked": "auto", "policy": "SCHED_FIFO", "priority": AUTO_LOOP_PRIORITY}
    restore_scheduling(scheduling)
    assert (scheduler.policy, scheduler.priority) == (os.SCHED_OTHER, 0)
    restore_scheduling(scheduling)  # once only
    assert scheduler.calls == [(os.SCHED_FIFO, AUTO_LOOP_PRIORITY), (os.SCHED_OTHER, 0)]


def test_auto_where_not_permitted_runs_as_before_and_says_how_to_permit(fake):
    scheduler = fake(permitted=False)
    scheduling = request_fifo(AUTO, AUTO_RIG_PRIORITY, "the virtual rig")
    assert not scheduling.granted and scheduler.policy == os.SCHED_OTHER
    assert scheduling.line.startswith(f"SCHED_FIFO priority {AUTO_RIG_PRIORITY} for the virtual rig (auto): not permitted")
    assert "normal scheduling" in scheduling.line
    for remedy in ("root", "setcap cap_sys_nice+ep", "rtprio", "limits.conf"):
        assert remedy in scheduling.line
    assert scheduling.as_dict() == {"asked": "auto", "policy": "normal", "priority": 0}
    restore_scheduling(scheduling)
    assert scheduler.calls == []  # nothing was granted, nothing to give back


def test_an_explicit_priority_refused_is_said_politely(fake):
    fake(permitted=False)
    scheduling = request_fifo(70)
    assert not scheduling.granted and "SCHED_FIFO priority 70 for the loop: refused" in scheduling.line
    assert "CAP_SYS_NICE" in scheduling.line and "running with normal scheduling" in scheduling.line


def test_zero_asks_nothing_and_says_nothing(fake):
    scheduler = fake(permitted=True)
    scheduling = request_fifo(0)
    assert scheduling.line == "" and not scheduling.granted and scheduler.calls == []


def test_apply_realtime_gives_back_only_what_it_asked_for(fake):
    scheduler = fake(permitted=True)
    report = apply_realtime(RealtimeConfig(fifo_priority=AUTO, disable_gc=False))
    assert report.lines[0].startswith(f"SCHED_FIFO priority {AUTO_LOOP_PRIORITY} for the loop (auto): granted")
    restore_realtime(report)
    assert scheduler.policy == os.SCHED_OTHER
    made_before = request_fifo(AUTO)  # the session asks before its pre-flight check, and gives it back itself
    report = apply_realtime(RealtimeConfig(fifo_priority=AUTO, disable_gc=False), made_before)
    assert report.lines == [made_before.line]
    restore_realtime(report)
    assert scheduler.policy == os.SCHED_FIFO  # still the session's to give back
    restore_scheduling(made_before)
    assert scheduler.policy == os.SCHED_OTHER


def test_the_profile_refuses_a_priority_out_of_range_naming_both_forms():
    from harness.errors import ProfileError

    with pytest.raises(ProfileError, match=r"expected a value >= 0 and <= 99 or one of 'auto'"):
        load_profile(overrides=["loop.realtime.fifo_priority=100"])
    with pytest.raises(ProfileError, match=r"expected a whole number or one of 'auto'"):
        load_profile(overrides=["loop.realtime.fifo_priority=high"])


class _Rig:
    """Enough of a VirtualRig for the serving loop: it switches to lockstep after some real-time ticks."""

    def __init__(self, stop, switch_after: int):
        self.schedule = type("S", (), {"sensor_period_s": 0.001})()
        self.lockstep = False
        self.journal = RigJournal(clock=lambda: 0.0)
        self.ticks = 0
        self.stop = stop
        self.switch_after = switch_after
        self.time = 0.0
        self.seen: list[tuple[bool, int]] = []

    def clock(self) -> float:
        self.time += 0.0005
        return self.time

    def service(self, now: float, wait_s: float = 0.0) -> int:
        self.seen.append((self.lockstep, host.os.sched_getscheduler(0)))
        self.ticks += 1
        if self.ticks == self.switch_after:
            self.lockstep = True
        if self.ticks >= 2 * self.switch_after:
            self.stop.set()
        return 0


def test_the_rig_thread_runs_fifo_in_real_time_and_normal_in_lockstep(fake):
    import threading

    from harness.rig.runner import serve

    scheduler = fake(permitted=True)
    stop = threading.Event()
    rig = _Rig(stop, switch_after=5)
    serve(rig, stop, poll_timeout_s=0.0, sleep=lambda s: None, fifo_priority=AUTO)
    assert not hasattr(rig, "error"), rig.error
    real_time = [policy for lockstep, policy in rig.seen if not lockstep]
    lockstep = [policy for lockstep, policy in rig.seen if lockstep]
    assert real_time and set(real_time) == {os.SCHED_FIFO}
    assert lockstep and set(lockstep) == {os.SCHED_OTHER}
    (line,) = [line for _, line in rig.journal.drain()]  # one line, in the rig's journal
    assert "(auto): granted" in line and f"priority {AUTO_RIG_PRIORITY}" in line
    assert scheduler.policy == os.SCHED_OTHER  # given back when the thread ends


def test_the_other_threads_of_the_process_go_to_the_lowest_real_time_priority_and_come_back(fake):
    """They share the interpreter's lock: preempted by ordinary load while holding it, they would stall the loop."""
    import threading

    from harness.realtime.host import LOCK_SHARER_PRIORITY

    scheduler = fake(permitted=True)
    release = threading.Event()
    sharer = threading.Thread(target=release.wait, name="recorder-like", daemon=True)
    sharer.start()
    try:
        scheduling = request_fifo(AUTO)
        assert scheduler.others[sharer.native_id] == (os.SCHED_FIFO, LOCK_SHARER_PRIORITY)
        assert "other thread(s) of the process at priority 1" in scheduling.line
        restore_scheduling(scheduling)
        assert scheduler.others[sharer.native_id] == (os.SCHED_OTHER, 0)
    finally:
        release.set()
        sharer.join()


def test_a_process_started_while_the_loop_holds_fifo_starts_with_normal_scheduling():
    """The live console's process is started after the request: SCHED_RESET_ON_FORK keeps it ordinary."""
    import subprocess
    import sys

    scheduling = request_fifo(AUTO)
    try:
        if not scheduling.granted:
            pytest.skip("SCHED_FIFO is not permitted here: " + scheduling.line)
        child = subprocess.run([sys.executable, "-c", "import os; print(os.sched_getscheduler(0))"],
                               capture_output=True, text=True, check=True)
        assert int(child.stdout) == os.SCHED_OTHER
        assert os.sched_getscheduler(0) & ~os.SCHED_RESET_ON_FORK == os.SCHED_FIFO
    finally:
        restore_scheduling(scheduling)
    assert os.sched_getscheduler(0) == os.SCHED_OTHER
