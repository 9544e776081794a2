"""The pre-flight timing check on a fake clock: verdicts, the refusal and its message."""

from __future__ import annotations

import pytest

from harness.loop.preflight import HostTiming, HostTimingRefused, measure_host_timing

RATE_HZ = 500.0
BUDGET_S = 0.02


class LateClock:
    """A clock whose sleeps overshoot: by ``late_s`` on every ``every``-th sleep, else by 10 us."""

    def __init__(self, late_s: float, every: int) -> None:
        self.now = 0.0
        self.late_s, self.every, self.sleeps = late_s, every, 0

    def __call__(self) -> float:
        self.now += 1e-7
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps += 1
        self.now += seconds + (self.late_s if self.sleeps % self.every == 0 else 1e-5)


def _measure(late_s: float, every: int) -> HostTiming:
    clock = LateClock(late_s, every)
    return measure_host_timing(RATE_HZ, BUDGET_S, spin_s=0.0, duration_s=1.0, clock=clock, sleep=clock.sleep)


def test_a_quiet_host_is_ok_and_polls_at_every_wakeup():
    clock = LateClock(0.0, 10**9)
    polls = []
    timing = measure_host_timing(RATE_HZ, BUDGET_S, 0.0, 1.0, clock, clock.sleep, poll=lambda: polls.append(1))
    assert timing.wakeups == 500 and len(polls) == 500
    assert timing.verdict == "ok" and timing.p99_s < 1e-4
    timing.check()  # does not raise


def test_rare_stalls_beyond_half_the_budget_are_marginal_not_refused():
    timing = _measure(0.015, every=250)  # two 15 ms stalls in a second
    assert timing.max_s == pytest.approx(0.015, abs=0.002)
    assert timing.verdict == "marginal"
    timing.check()


def test_a_host_that_misses_the_budget_often_is_refused_with_the_remedies():
    timing = _measure(0.03, every=20)  # 5 % of the wake-ups 30 ms late
    assert timing.p99_s > BUDGET_S and timing.verdict == "refused"
    with pytest.raises(HostTimingRefused) as err:
        timing.check()
    text = str(err.value)
    assert "p99" in text and "20.0 ms" in text and "nothing was moved" in text
    assert "--rate" in text and "--lockstep" in text and "priority" in text


def test_summary_and_metadata_carry_the_figures():
    timing = HostTiming(500.0, 500, 1e-6, 3e-4, 4e-3, 0.02)
    assert timing.as_dict()["verdict"] == "ok" and timing.as_dict()["lateness_p99_s"] == 3e-4
    assert "p99 300 us" in timing.summary() and "max 4.00 ms" in timing.summary()


class Rig:
    """Frame counts of the two control measurement messages: one frame per ``period_s`` of the clock,
    except during ``silent`` spans (start, end) of the clock's time."""

    def __init__(self, clock: LateClock, period_s: float = 0.002, silent=()):
        self.clock, self.period_s, self.silent = clock, period_s, silent
        self.sent, self.next_s = 0, 0.0

    def counts(self) -> tuple[int, int]:
        while self.next_s <= self.clock.now:
            if not any(a <= self.next_s < b for a, b in self.silent):
                self.sent += 1
            self.next_s += self.period_s
        return (self.sent, self.sent)


def _watch(rig: Rig, clock: LateClock) -> HostTiming:
    return measure_host_timing(RATE_HZ, BUDGET_S, 0.0, 1.0, clock, clock.sleep, frame_counts=rig.counts,
                               max_sensor_age_s=0.02)


def test_a_rig_that_sends_steadily_leaves_the_verdict_to_the_loop():
    clock = LateClock(0.0, 10**9)
    timing = _watch(Rig(clock), clock)
    assert timing.verdict == "ok" and timing.rig_age_max_s is not None and timing.rig_age_max_s < 0.005
    assert "the rig's sensor frames: age p99" in timing.summary()
    assert timing.as_dict()["rig_frame_age_max_s"] == timing.rig_age_max_s


def test_a_rig_not_scheduled_for_22_ms_is_refused_though_the_loop_is_on_time():
    """The issue's case: that gap would have tripped sensor_stale; a 30 s run holds thirty such seconds."""
    clock = LateClock(0.0, 10**9)  # the loop itself is on time: its own verdict would be ok
    timing = _watch(Rig(clock, silent=[(0.5, 0.522)]), clock)
    assert timing.p99_s < 1e-4
    assert timing.rig_age_max_s == pytest.approx(0.024, abs=0.003)
    assert timing.verdict == "refused"


def test_a_rig_gap_between_half_the_limit_and_the_limit_is_marginal():
    clock = LateClock(0.0, 10**9)
    timing = _watch(Rig(clock, silent=[(0.5, 0.512)]), clock)  # ages up to 14 ms against 20 ms
    assert 0.01 < timing.rig_age_max_s < 0.02
    assert timing.verdict == "marginal"
    timing.check()


def test_one_wakeup_later_than_the_budget_is_refused():
    timing = _measure(0.025, every=400)  # one 25 ms stall in the second: the run would trip there
    assert timing.p99_s < BUDGET_S < timing.max_s
    assert timing.verdict == "refused"


def test_a_rig_that_is_often_late_is_refused_before_anything_moves():
    clock = LateClock(0.0, 10**9)
    gaps = [(0.1 * k, 0.1 * k + 0.03) for k in range(10)]  # a 30 ms gap every 100 ms: about 10 % of the ticks too old
    timing = _watch(Rig(clock, silent=gaps), clock)
    assert timing.rig_age_p99_s is not None and timing.rig_age_p99_s > 0.02
    assert timing.verdict == "refused"
    with pytest.raises(HostTimingRefused, match="the rig's sensor frames"):
        timing.check()


def test_a_silent_rig_is_refused_naming_it():
    clock = LateClock(0.0, 10**9)
    timing = _watch(Rig(clock, silent=[(0.0, 10.0)]), clock)
    assert timing.verdict == "refused"
    assert "none arrived" in timing.summary()
    with pytest.raises(HostTimingRefused, match="none arrived"):
        timing.check()


def _cpu(idle_share: float):
    """/proc/stat readings: 1000 jiffies per call, ``idle_share`` of them idle."""
    state = {"idle": 0, "total": 0}

    def read() -> tuple[int, int]:
        reading = (state["idle"], state["total"])
        state["idle"] += int(1000 * idle_share)
        state["total"] += 1000
        return reading

    return read


@pytest.mark.parametrize(("idle_share", "verdict"), [(0.0, "refused"), (0.1, "refused"), (0.5, "ok"), (0.9, "ok")])
def test_without_real_time_priority_a_machine_with_no_core_to_spare_is_refused(idle_share, verdict, monkeypatch):
    monkeypatch.setattr("harness.loop.preflight.os.cpu_count", lambda: 2)
    clock = LateClock(0.0, 10**9)  # a clean second: only the idle CPU can refuse it
    timing = measure_host_timing(RATE_HZ, BUDGET_S, 0.0, 1.0, clock, clock.sleep, judge_idle=True,
                                 read_cpu_times=_cpu(idle_share))
    assert timing.idle_cores == pytest.approx(2 * idle_share)
    assert timing.verdict == verdict
    if verdict == "refused":
        with pytest.raises(HostTimingRefused, match="idle CPU 0.[0-9]+ cores at normal scheduling"):
            timing.check()


def test_at_real_time_priority_the_machine_s_load_is_not_judged():
    clock = LateClock(0.0, 10**9)
    timing = measure_host_timing(RATE_HZ, BUDGET_S, 0.0, 1.0, clock, clock.sleep, judge_idle=False,
                                 read_cpu_times=_cpu(0.0))
    assert timing.idle_cores is None and timing.verdict == "ok"


def test_an_unreadable_proc_stat_judges_nothing():
    from harness.loop.preflight import idle_cores

    assert idle_cores(None, (1, 2), 2) is None and idle_cores((5, 10), (5, 10), 2) is None
    assert idle_cores((0, 0), (250, 1000), 4) == pytest.approx(1.0)
