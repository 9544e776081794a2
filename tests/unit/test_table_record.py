"""The table check's verdict logic at and around its bounds, its gate, and the check in the supervisor."""

from __future__ import annotations

import dataclasses
import math
import tracemalloc

import numpy as np
import pytest

from harness.loop.status import TABLE_VERDICT_NAMES
from harness.loop.trip_outputs import TripOutputs
from harness.motions.online_tracking import OnlineTracking
from harness.motions.tracking import tracking
from harness.report.table_check import table_check
from harness.safety.checks import bit
from harness.safety.config import SafetyConfig, SensorConfig, TripActionsConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor
from harness.safety.table_record import (
    EVALUATE_EVERY_S,
    MATCH_AMPLITUDE,
    MATCH_CORRELATION,
    MATCH_DELAY_S,
    MAX_LAG_S,
    MIN_HALF_CYCLES,
    MIN_RECORD_S,
    MISMATCH_AMPLITUDE,
    MISMATCH_CORRELATION,
    VELOCITY_FLOOR_M_S,
    TableRecordCheck,
    TableVerdict,
    gate_index,
    judge,
)

PERIOD_S = 0.002
MATCH, MARGINAL, MISMATCH = TableVerdict.MATCH, TableVerdict.MARGINAL, TableVerdict.MISMATCH
EPS = 1e-6


def _record_velocity(seconds: float = 8.0, seed: int = 3, quiet_s: float = 0.0) -> np.ndarray:
    """A band-limited random table velocity (0.5-4 Hz, ~0.1 m/s RMS) on the tick grid, after ``quiet_s`` at rest."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, PERIOD_S)
    v = sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 6.28)) for f in rng.uniform(0.5, 4.0, 20))
    v = 0.1 * v / np.std(v)
    v[t < quiet_s] *= 1e-3  # a quiet start: a tenth of a mm/s
    return v


# ---------------------------------------------------------------- the verdict at and around its bounds

def test_the_match_band_and_its_edges() -> None:
    assert judge(0.99, 0.008, 1.02, False) is MATCH  # the shipped rig: correlation 1.00, delay 8 ms, ratio 1.02
    assert judge(MATCH_CORRELATION, 0.008, 1.0, False) is MATCH
    assert judge(MATCH_CORRELATION - EPS, 0.008, 1.0, False) is MARGINAL
    assert judge(0.99, MATCH_DELAY_S[0], 1.0, False) is MATCH
    assert judge(0.99, MATCH_DELAY_S[0] - EPS, 1.0, False) is MARGINAL
    assert judge(0.99, MATCH_DELAY_S[1], 1.0, False) is MATCH
    assert judge(0.99, MATCH_DELAY_S[1] + EPS, 1.0, False) is MARGINAL
    assert judge(0.99, 0.008, MATCH_AMPLITUDE[0], False) is MATCH
    assert judge(0.99, 0.008, MATCH_AMPLITUDE[0] - EPS, False) is MARGINAL
    assert judge(0.99, 0.008, MATCH_AMPLITUDE[1], False) is MATCH
    assert judge(0.99, 0.008, MATCH_AMPLITUDE[1] + EPS, False) is MARGINAL


def test_the_mismatch_bounds_and_their_edges() -> None:
    assert judge(MISMATCH_CORRELATION, 0.008, 1.0, False) is MARGINAL
    assert judge(MISMATCH_CORRELATION - EPS, 0.008, 1.0, False) is MISMATCH
    assert judge(0.99, 0.008, MISMATCH_AMPLITUDE[0], False) is MARGINAL
    assert judge(0.99, 0.008, MISMATCH_AMPLITUDE[0] - EPS, False) is MISMATCH
    assert judge(0.99, 0.008, MISMATCH_AMPLITUDE[1], False) is MARGINAL
    assert judge(0.99, 0.008, MISMATCH_AMPLITUDE[1] + EPS, False) is MISMATCH
    assert judge(0.99, MAX_LAG_S, 1.0, True) is MISMATCH  # the peak at the end of the delays searched
    assert judge(0.99, 0.05, 1.0, False) is MARGINAL  # late, but a peak inside the search: marginal
    assert judge(-0.9, 0.008, -1.0, False) is MISMATCH  # a table moving against its record
    assert judge(math.nan, math.nan, math.nan, False) is MISMATCH  # the table did not move at all


# ---------------------------------------------------------------- the online measures are the offline ones

@pytest.mark.parametrize("delay_s", [0.0, 0.0077, -0.004, 0.021])
def test_online_tracking_gives_the_reports_measures(delay_s: float) -> None:
    drive = _record_velocity()
    t = np.arange(drive.size) * PERIOD_S
    achieved = 0.8 * np.interp(t - delay_s, t, drive, left=0.0) + np.random.default_rng(1).normal(0, 2e-4, t.size)
    online = OnlineTracking(drive, PERIOD_S, MAX_LAG_S)
    for value in achieved[:2000]:
        online.add(value)
    online.evaluate()
    offline = tracking(achieved[:2000], drive[:2000], PERIOD_S, MAX_LAG_S)
    assert online.delay_s == pytest.approx(offline.delay_s, abs=0.05 * PERIOD_S)
    assert online.correlation == pytest.approx(offline.correlation, abs=2e-3)
    assert online.amplitude_ratio == pytest.approx(offline.amplitude_ratio, rel=1e-2)
    assert online.delay_s == pytest.approx(delay_s, abs=0.5 * PERIOD_S) and not online.at_edge


def test_online_tracking_stops_at_the_drives_end_and_forgets_on_reset() -> None:
    online = OnlineTracking(np.ones(5), PERIOD_S, 0.004)
    assert [online.add(1.0) for _ in range(6)] == [True] * 5 + [False]
    online.reset()
    assert online.count == 0 and math.isnan(online.correlation)


# ---------------------------------------------------------------- the gate: no verdict on too little motion

def test_the_gate_waits_for_time_motion_and_swings() -> None:
    t = np.arange(0.0, 10.0, PERIOD_S)
    swinging = 0.1 * np.sin(2 * np.pi * 1.0 * t + 0.3)  # a swing starts every half second
    gate = gate_index(swinging, PERIOD_S)
    assert gate is not None
    # swing k starts where |v| passes the floor after the k-th zero crossing, at (k pi - 0.3 + asin(0.1)) / (2 pi) s
    expected_s = (MIN_HALF_CYCLES - 1) * 0.5 + (math.asin(VELOCITY_FLOOR_M_S / 0.1) - 0.3) / (2 * np.pi)
    assert gate * PERIOD_S == pytest.approx(expected_s, abs=PERIOD_S)
    fast = 0.1 * np.sin(2 * np.pi * 10.0 * t)  # eight swings in 0.4 s: the minimum record time decides
    assert gate_index(fast, PERIOD_S) * PERIOD_S == pytest.approx(MIN_RECORD_S, abs=PERIOD_S)
    below_floor = 0.9 * VELOCITY_FLOOR_M_S * np.sin(2 * np.pi * 1.0 * t)
    assert gate_index(below_floor, PERIOD_S) is None  # never loud enough: never judged
    one_way = np.full(t.size, 0.05)
    assert gate_index(one_way, PERIOD_S) is None  # no swings to tell one record from another


def test_a_quiet_start_is_not_judged_whatever_the_table_does() -> None:
    told = _record_velocity(quiet_s=3.0)
    check = TableRecordCheck(0.02)
    check.expect(told, PERIOD_S, 8.0, PERIOD_S)
    assert check.gate_s > 3.0
    noise = np.random.default_rng(9).normal(0, 2e-4, told.size)  # the table at rest: its sensor's noise
    for n in range(int(3.0 / PERIOD_S)):
        assert check.update(n * PERIOD_S, noise[n]) is TableVerdict.WAITING
    assert check.evaluations == 0


# ---------------------------------------------------------------- the check through the supervisor

class Bench:
    """A supervisor told ``told`` (m/s on the tick grid), RUNNING, fed a table velocity tick by tick."""

    def __init__(self, told: np.ndarray) -> None:
        # noise-free measurements repeat to the bit: sensor_stuck is not what these tests are about
        config = dataclasses.replace(SafetyConfig(), sensors=SensorConfig(stuck_samples=10**6))
        self.sup = Supervisor(config, period_s=PERIOD_S)
        self.sup.table_record.expect(told, PERIOD_S, (told.size - 1) * PERIOD_S, PERIOD_S)
        self.health = TickHealth()
        self.events: list[tuple[float, str, str, str]] = []
        self.sup.arm(0.0, self.health)
        self.sup.start(0.0)
        self.k = 0

    def run(self, table_velocity: np.ndarray) -> None:
        displacement = np.cumsum(table_velocity) * PERIOD_S  # consistent with the velocity (sensor_disagree)
        for n, value in enumerate(table_velocity):
            self.k += 1
            self.health.record_time_s = n * PERIOD_S
            self.health.meas.set(float(displacement[n]), float(value), float(displacement[n]), float(value))  # no sliding
            self.health.measured_force_N = self.sup.command.force_N
            self.sup.update(self.k * PERIOD_S, PERIOD_S, self.health, 0.0)
            self.sup.events.drain(lambda *e: self.events.append(e))
            if self.sup.state is State.DONE:
                return


def _delayed(signal: np.ndarray, delay_s: float, gain: float = 1.0) -> np.ndarray:
    t = np.arange(signal.size) * PERIOD_S
    noise = np.random.default_rng(5).normal(0, 2e-4, signal.size)
    return gain * np.interp(t - delay_s, t, signal, left=0.0) + noise


def test_a_table_that_follows_its_record_matches_and_runs_on() -> None:
    told = _record_velocity()
    bench = Bench(told)
    bench.run(_delayed(told, 0.008, 1.02))
    check = bench.sup.table_record
    assert bench.sup.state is State.RUNNING and check.worst is MATCH
    gate_s = check.gate_s
    assert check.evaluations == int((8.0 - PERIOD_S - gate_s) / EVALUATE_EVERY_S) + 1  # every 0.5 s, not every tick
    assert not any(e[2].startswith("table_record") for e in bench.events)


def test_a_table_playing_another_record_is_stopped_safely_at_the_first_evaluation() -> None:
    told = _record_velocity(seed=3)
    bench = Bench(told)
    bench.run(_delayed(_record_velocity(seed=11), 0.008))
    sup, check = bench.sup, bench.sup.table_record
    assert check.worst is MISMATCH and check.evaluations == 1
    assert check.judged_at_s == pytest.approx(check.gate_s, abs=2 * PERIOD_S)  # the bound: the gate
    assert sup.state is State.DONE and sup.command.trip_reason == ""  # a safe stop, not a trip
    assert sup.stop_reason == "table_record_mismatch" and "correlation" in sup.stop_detail
    faults = [e for e in bench.events if e[1] == "fault"]
    assert [e[2] for e in faults] == ["table_record_mismatch"]
    assert any(e[1] == "state" and e[2] == "STOPPING" and "table_record_mismatch" in e[3] for e in bench.events)
    assert sup.act_ticks[bit("table_record_mismatch").bit_length() - 1] > 0


def test_a_table_playing_its_record_at_the_wrong_scale_warns_and_runs_on() -> None:
    told = _record_velocity()
    bench = Bench(told)
    bench.run(_delayed(told, 0.008, gain=0.6))
    check = bench.sup.table_record
    assert bench.sup.state is State.RUNNING and check.worst is MARGINAL
    correlation, delay_s, ratio, _ = check.worst_measures
    assert ratio == pytest.approx(0.6, abs=0.02) and correlation > 0.99
    marginal = [e for e in bench.events if e[2] == "table_record_marginal"]
    assert len(marginal) == 1 and marginal[0][1] == "fault" and "amplitude ratio 0.60" in marginal[0][3]
    assert table_check(check.summary()).flagged and not table_check(check.summary()).withheld


def test_a_table_playing_its_record_too_late_warns() -> None:
    told = _record_velocity()
    bench = Bench(told)
    bench.run(_delayed(told, 0.050))  # 50 ms: later than any healthy table, inside the search
    assert bench.sup.table_record.worst is MARGINAL
    assert bench.sup.table_record.worst_measures[1] == pytest.approx(0.050, abs=PERIOD_S)


def test_ticks_skipped_by_a_stall_are_filled_up_to_the_stall_budget() -> None:
    check = TableRecordCheck(max_stall_s=0.02)
    check.expect(_record_velocity(), PERIOD_S, 8.0, PERIOD_S)
    check.update(0.0, 0.1)
    check.update(5 * PERIOD_S, 0.2)  # four ticks skipped
    assert check.tracking is not None and check.tracking.count == 6
    check.update(100 * PERIOD_S, 0.3)  # beyond the budget (the loop trips loop_stall): at most 11 filled this tick
    assert check.tracking.count == 6 + check.max_catch_up


def test_the_check_allocates_nothing_per_tick_once_running() -> None:
    told = _record_velocity()
    bench = Bench(told)
    table = _delayed(told, 0.008)
    bench.run(table[:500])
    sup, health = bench.sup, bench.health
    displacement = np.cumsum(table) * PERIOD_S
    tracemalloc.start()
    try:
        before = tracemalloc.take_snapshot()
        for n in range(500, 3500):  # six evaluations among them
            health.record_time_s = n * PERIOD_S
            health.meas.set(float(displacement[n]), float(table[n]), float(displacement[n]), float(table[n]))
            sup.update((n + 1) * PERIOD_S, PERIOD_S, health, 0.0)
        after = tracemalloc.take_snapshot()
    finally:
        tracemalloc.stop()
    grown = [s for s in after.compare_to(before, "filename")
             if ("harness/safety" in str(s.traceback) or "harness/motions" in str(s.traceback)) and s.size_diff > 0]
    assert sum(s.size_diff for s in grown) < 2048, grown
    assert sup.table_record.evaluations >= 6


def test_without_a_record_the_check_is_off() -> None:
    sup = Supervisor(SafetyConfig(), period_s=PERIOD_S)
    assert sup.table_record.verdict is TableVerdict.OFF
    sup.table_record.ignore("table.link is none")
    assert sup.table_record.summary() == {"verdict": "off", "signal": "table velocity xdot_0",
                                          "reason": "table.link is none"}


def test_the_console_knows_every_verdict_by_its_code() -> None:
    assert TABLE_VERDICT_NAMES == tuple(verdict.name for verdict in TableVerdict)


class _Writer:
    def estop(self, *args) -> bool:
        return True


def test_a_mismatch_stops_the_table_once() -> None:
    stops: list[float] = []
    outputs = TripOutputs(_Writer(), TripActionsConfig(), 5, stops.append)
    outputs.stop_the_table(1.0)
    outputs.stop_the_table(1.002)
    assert stops == [1.0] and outputs.table_stops == 1
    TripOutputs(_Writer(), TripActionsConfig(), 5, None).stop_the_table(1.0)  # no table link: nothing to send


# ---------------------------------------------------------------- what the verdict does to the printed numbers

def _summary(verdict: TableVerdict, ratio: float) -> dict:
    check = TableRecordCheck(0.02)
    told = _record_velocity()
    check.expect(told, PERIOD_S, 8.0, PERIOD_S)
    table = _delayed(told, 0.008, ratio)
    for n, value in enumerate(table):
        check.update(n * PERIOD_S, float(value))
    assert check.worst is verdict
    return check.summary()


def test_reductions_are_withheld_on_a_mismatch_flagged_when_marginal_and_shown_on_a_match() -> None:
    from harness.report.tables import reduction_table
    from harness.signals.peaks import Peaks

    passive = Peaks(0.02, 3.0, (0.004, 0.003, 0.002), (2.0, 2.5, 3.0), 0.0)
    controlled = Peaks(0.01, 2.0, (0.002, 0.002, 0.001), (1.0, 1.5, 2.0), 10.0)
    for verdict, ratio in ((MATCH, 1.0), (MARGINAL, 0.6), (MISMATCH, 0.3)):
        check = table_check(_summary(verdict, ratio))
        assert check.verdict == verdict.name.lower() and check.line
        table = reduction_table(passive, controlled, "t", withheld=check.withheld, flagged=check.flagged)
        reductions = [row.values[-1] for row in table.rows if row.key.startswith("drift")]
        if verdict is MISMATCH:
            assert reductions == [None, None, None] and "Reductions not shown" in table.note
        else:
            assert all(value is not None and value > 0 for value in reductions)
            assert table.columns[-1].endswith("*") == (verdict is MARGINAL)


def test_no_line_for_a_run_without_a_record_a_reason_for_one_without_a_table_link() -> None:
    assert table_check({"verdict": "off", "reason": "no record to compare the table with"}).line == ""
    assert "table.link is none" in table_check({"verdict": "off", "reason": "table.link is none"}).line
    assert table_check(None).verdict == "unknown" and not table_check(None).withheld  # runs before the check
