"""The real-time tests' shared runner (tests/realtime_runs.py): a refused run is run again, counted, and fails clearly.

No run and no wall clock here: the attempts are made-up finished processes and the quiet second is injected.
"""

from __future__ import annotations

import functools
import os
import subprocess
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from harness import exit_codes
from harness.loop.preflight import MIN_IDLE_CORES, HostTiming, HostTimingRefused
from harness.loop.runner import ArmTimeout, ControlLoop
from harness.realtime.host import Scheduling
from tests import realtime_runs
from tests.realtime_runs import QuietWait, refused_by_preflight, run_real_time, summary_line, wait_for_quiet_second

RATE_HZ, BUDGET_S = 500.0, 0.02


def _timing(max_s: float, idle: float | None = 1.5) -> HostTiming:
    return HostTiming(RATE_HZ, 500, 1e-5, 1e-4, max_s, BUDGET_S, idle_cores=idle)


def _refusal_text() -> str:
    """What the harness prints when its pre-flight refuses: the message of HostTiming.check, as the CLI shows it."""
    with pytest.raises(HostTimingRefused) as refused:
        _timing(0.074).check()
    return f"error: {refused.value}\n"


def _done(status: int, err: str = "", out: str = "") -> subprocess.CompletedProcess:
    return subprocess.CompletedProcess(["harness"], status, out, err)


def _quiet(_rate_hz: float, _budget_s: float) -> QuietWait:
    return QuietWait(True, 1.0, _timing(0.001))


class Attempts:
    """Finished processes handed out in order; each makes a run folder in ``log_dir`` as a real run does."""

    def __init__(self, log_dir: Path, *done: subprocess.CompletedProcess) -> None:
        self.log_dir, self.done, self.made = log_dir, list(done), 0

    def __call__(self) -> subprocess.CompletedProcess:
        self.made += 1
        (self.log_dir / f"run{self.made}").mkdir(parents=True)
        return self.done.pop(0)


def test_the_refusal_words_are_the_preflights_own():
    text = _refusal_text()
    assert realtime_runs.REFUSAL in text
    assert refused_by_preflight(_done(exit_codes.INPUT_ERROR, err=text))
    assert realtime_runs.FIGURES.search(text).group(0).startswith("host timing at 500 Hz")


@pytest.mark.parametrize(("status", "err"), [
    (exit_codes.INPUT_ERROR, "error: --rate: found 10 Hz, expected at least 100 Hz"),  # another refusal: the test's to judge
    (exit_codes.TRIPPED, "outcome: tripped (loop_stall)"),
    (exit_codes.OK, ""),
])
def test_only_the_preflights_refusal_counts_as_refused(status, err):
    assert not refused_by_preflight(_done(status, err=err))


def _arm_refusal_text(gap_s: float | None) -> str:
    """What the harness prints when it could not arm: ArmTimeout with the loop's own stall note (none if ``gap_s`` is None)."""
    loop = SimpleNamespace(gaps_past_budget=0 if gap_s is None else 1, last_gap_past_budget_s=gap_s or 0.0,
                           last_gap_past_budget_end_s=0.37, max_stall_s=0.08)
    failed = "arm refused: expected every pre-arm check to pass, failed: actuator_ready: drive ready=False, fault=True"
    return f"error: {ArmTimeout(failed + ControlLoop._stall_note(loop), 3.0)}\n"


def test_a_refusal_to_arm_after_the_loops_own_stall_counts_as_refused():
    """The host stopped the loop while it armed (CI: 126 ms inside User-Mode Linux): nothing moved, run again."""
    text = _arm_refusal_text(0.126)
    assert refused_by_preflight(_done(exit_codes.INPUT_ERROR, err=text))
    assert realtime_runs.FIGURES.search(text).group(0) == (
        "the loop itself stalled 126.0 ms up to t = 0.370 s, past its 80.0 ms stall budget "
        "(a drive's watchdog fault after it is the stall's)")


def test_a_refusal_to_arm_for_any_other_cause_is_the_tests_to_judge():
    assert not refused_by_preflight(_done(exit_codes.INPUT_ERROR, err=_arm_refusal_text(None)))


def test_a_refused_run_is_run_again_and_its_folder_set_aside(tmp_path, capsys):
    records: list[realtime_runs.RealTimeRecord] = []  # made-up runs: kept out of the stage's summary
    log_dir = tmp_path / "logs"
    attempts = Attempts(log_dir, _done(exit_codes.INPUT_ERROR, err=_refusal_text()), _done(exit_codes.OK, out="completed"))
    done = run_real_time(attempts, log_dir=log_dir, rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run", wait=_quiet,
                         records=records)
    assert done.stdout == "completed"
    assert [p.name for p in log_dir.iterdir()] == ["run2"]  # the test sees only the run that went on
    assert [p.name for p in (tmp_path / "logs-refused").iterdir()] == ["run1"]
    record = records[-1]
    assert (record.runs, len(record.refusals), record.waited_s) == (2, 1, 2.0)
    assert "lateness" in record.refusals[0] and "74.00 ms" in record.refusals[0]
    assert "run 1 refused by the pre-flight" in capsys.readouterr().out


def test_a_run_that_fails_past_the_preflight_is_never_run_again(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []  # made-up runs: kept out of the stage's summary
    attempts = Attempts(tmp_path, _done(exit_codes.TRIPPED, out="tripped (loop_stall)"), _done(exit_codes.OK))
    done = run_real_time(attempts, log_dir=tmp_path, rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run", wait=_quiet,
                         records=records)
    assert done.returncode == exit_codes.TRIPPED and attempts.made == 1
    assert records[-1].refusals == []


def test_a_host_never_quiet_enough_fails_with_every_refusals_figures(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []  # made-up runs: kept out of the stage's summary
    refusals = [_done(exit_codes.INPUT_ERROR, err=_refusal_text()) for _ in range(realtime_runs.MAX_RUNS + 1)]
    attempts = Attempts(tmp_path, *refusals)
    with pytest.raises(pytest.fail.Exception) as failed:
        run_real_time(attempts, log_dir=tmp_path, rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run", wait=_quiet,
                      records=records)
    message = str(failed.value)
    assert attempts.made == realtime_runs.MAX_RUNS
    assert f"refused all {realtime_runs.MAX_RUNS} runs" in message and "never quiet enough" in message
    assert message.count("max 74.00 ms against a stall budget of 20.0 ms") == realtime_runs.MAX_RUNS


def _normal() -> Scheduling:
    return Scheduling("auto", 80, False)  # not permitted: normal scheduling, the idle CPU judged


def test_the_quiet_second_is_the_first_the_preflights_measurement_calls_ok():
    seconds = iter([_timing(0.015), _timing(0.001, idle=MIN_IDLE_CORES / 2), _timing(0.001)])  # marginal, busy, quiet
    judged: list[bool] = []

    def measure(*_args, judge_idle: bool, **_kwargs) -> HostTiming:
        judged.append(judge_idle)
        return next(seconds)

    clock = iter(range(100))
    wait = wait_for_quiet_second(RATE_HZ, BUDGET_S, 30.0, measure=measure, clock=lambda: next(clock), scheduling=_normal)
    assert wait.quiet and wait.last.verdict == "ok" and wait.waited_s == 3
    assert judged == [True] * 3  # without real-time priority the machine's idle CPU counts, as in the pre-flight


def test_with_real_time_priority_the_quiet_second_does_not_judge_the_idle_cpu():
    judged: list[bool] = []

    def measure(*_args, judge_idle: bool, **_kwargs) -> HostTiming:
        judged.append(judge_idle)
        return _timing(0.001, idle=None)

    clock = iter(range(100))
    taken: list[Scheduling] = []

    def fifo() -> Scheduling:  # as granted; restore_scheduling gives back normal scheduling, which this process has
        taken.append(Scheduling("auto", 80, granted=True, previous=(os.SCHED_OTHER, 0)))
        return taken[-1]

    wait = wait_for_quiet_second(RATE_HZ, BUDGET_S, 30.0, measure=measure, clock=lambda: next(clock), scheduling=fifo)
    assert wait.quiet and judged == [False]
    assert not taken[0].granted  # given back after the second


def test_the_wait_for_a_quiet_second_gives_up_after_its_limit_and_the_run_starts_anyway():
    clock = iter(range(0, 1000, 10))
    wait = wait_for_quiet_second(RATE_HZ, BUDGET_S, 30.0, measure=lambda *a, **k: _timing(0.015), clock=lambda: next(clock),
                                 scheduling=_normal)
    assert not wait.quiet and wait.waited_s == 30 and wait.last.verdict == "marginal"


def test_the_summary_line_adds_up_every_tests_runs():
    records = [{"what": "a", "runs": 1, "refusals": [], "waited_s": 1.0, "never_quiet": 0},
               {"what": "b", "runs": 3, "refusals": ["x", "y"], "waited_s": 40.0, "never_quiet": 1}]
    line = summary_line(records)
    assert line.startswith("real-time runs: 2 asked for, 4 started, 2 refused by the pre-flight")
    assert "41 s spent waiting for a quiet second (1 runs started without one)" in line


class StallingAttempts(Attempts):
    """As :class:`Attempts`; a run that tripped ``loop_stall`` writes the stall's event into its folder."""

    def __init__(self, log_dir: Path, stall_detail: str, *done: subprocess.CompletedProcess) -> None:
        super().__init__(log_dir, *done)
        self.stall_detail = stall_detail

    def __call__(self) -> subprocess.CompletedProcess:
        done = super().__call__()
        if done.returncode == exit_codes.TRIPPED:
            (self.log_dir / f"run{self.made}" / "events.jsonl").write_text(
                '{"kind": "timing", "name": "stall_past_budget", "detail": "' + self.stall_detail + '"}\n')
        return done


WAITED = ("80.9 ms between two ticks (7 missed periods), past the 80.0 ms stall budget: begun in RUNNING; "
          "the loop was waiting for the next deadline (sleep and spin) for 79.1 ms")
WORKED = ("80.9 ms between two ticks (7 missed periods), past the 80.0 ms stall budget: begun in RUNNING; "
          "the loop was in its own work (control) for 79.1 ms")


def test_a_host_stall_trip_is_run_again_only_where_the_test_asks_and_is_counted(tmp_path, capsys):
    records: list[realtime_runs.RealTimeRecord] = []  # made-up runs: kept out of the stage's summary
    log_dir = tmp_path / "logs"
    attempts = StallingAttempts(log_dir, WAITED, _done(exit_codes.TRIPPED, out="outcome: tripped (loop_stall)"),
                                _done(exit_codes.OK, out="completed"))
    done = run_real_time(attempts, log_dir=log_dir, rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run", wait=_quiet,
                         records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.OK and attempts.made == 2
    assert [p.name for p in log_dir.iterdir()] == ["run2"]
    assert len(records[-1].host_stalls) == 1 and "waiting for the next deadline" in records[-1].host_stalls[0]
    assert "1 tripped on a stall the host made" in summary_line([records[-1].as_dict()])
    assert "run 1 tripped on a stall the host made" in capsys.readouterr().out
    # not asked for: the trip is the test's to judge
    plain = StallingAttempts(tmp_path / "plain", WAITED, _done(exit_codes.TRIPPED, out="outcome: tripped (loop_stall)"),
                             _done(exit_codes.OK))
    done = run_real_time(plain, log_dir=tmp_path / "plain", rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run",
                         wait=_quiet, records=records)
    assert done.returncode == exit_codes.TRIPPED and plain.made == 1


def test_a_stall_in_the_loops_own_work_or_another_trip_is_never_run_again(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []
    worked = StallingAttempts(tmp_path / "a", WORKED, _done(exit_codes.TRIPPED, out="outcome: tripped (loop_stall)"),
                              _done(exit_codes.OK))
    done = run_real_time(worked, log_dir=tmp_path / "a", rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run",
                         wait=_quiet, records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.TRIPPED and worked.made == 1  # the loop's own work stalled: a finding
    other = StallingAttempts(tmp_path / "b", WAITED, _done(exit_codes.TRIPPED, out="outcome: tripped (sensor_stale)"),
                             _done(exit_codes.OK))
    done = run_real_time(other, log_dir=tmp_path / "b", rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run",
                         wait=_quiet, records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.TRIPPED and other.made == 1


def _can_log(folder: Path, sensor_times_s, command_times_s) -> None:
    """A candump ``can.log`` with the rig's table sensor frames (received) and the loop's commands (sent)."""
    lines = [(t, "030#0000000000000000 R") for t in sensor_times_s] + [(t, "020#00000000 T") for t in command_times_s]
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "can.log").write_text("".join(f"({1000.0 + t:.6f}) vcan0 {frame}\n" for t, frame in sorted(lines)))


STALE = _done(exit_codes.TRIPPED, out="outcome: tripped (sensor_stale), with a warning")
TICKS = np.arange(0.0, 1.0, 0.01)


def test_a_sensor_stale_trip_is_the_rigs_stall_only_when_its_frames_stopped_and_the_commands_did_not(tmp_path):
    """CI in User-Mode Linux: the rig's frames stopped 159 ms while the loop sent a command every 10 ms."""
    rig_stopped = tmp_path / "rig"
    _can_log(rig_stopped, TICKS[(TICKS < 0.4) | (TICKS > 0.55)], TICKS)
    found = realtime_runs.rig_stall_trip(STALE, [rig_stopped], 0.08)
    assert found is not None and "stopped 170.0 ms" in found and "sent 16 commands" in found
    assert "none more than 10.0 ms apart" in found
    both_stopped = tmp_path / "both"  # the loop stalled too: the stall is not the rig's alone
    _can_log(both_stopped, TICKS[(TICKS < 0.4) | (TICKS > 0.55)], TICKS[(TICKS < 0.42) | (TICKS > 0.53)])
    assert realtime_runs.rig_stall_trip(STALE, [both_stopped], 0.08) is None
    short = tmp_path / "short"  # a gap within the limit explains no trip
    _can_log(short, TICKS[(TICKS < 0.4) | (TICKS > 0.44)], TICKS)  # 60 ms
    assert realtime_runs.rig_stall_trip(STALE, [short], 0.08) is None
    other_trip = _done(exit_codes.TRIPPED, out="outcome: tripped (stroke_limit)")
    assert realtime_runs.rig_stall_trip(other_trip, [rig_stopped], 0.08) is None
    assert realtime_runs.rig_stall_trip(_done(exit_codes.OK, out="completed"), [rig_stopped], 0.08) is None


class LoggingAttempts(Attempts):
    """As :class:`Attempts`; a run that ends with ``status`` gets a ``can.log`` from ``write(folder)``."""

    def __init__(self, log_dir: Path, status: int, write, *done: subprocess.CompletedProcess) -> None:
        super().__init__(log_dir, *done)
        self.status, self.write = status, write

    def __call__(self) -> subprocess.CompletedProcess:
        done = super().__call__()
        if done.returncode == self.status:
            self.write(self.log_dir / f"run{self.made}")
        return done


def _rig_stopped(folder: Path) -> None:
    _can_log(folder, TICKS[(TICKS < 0.4) | (TICKS > 0.55)], TICKS)


def test_a_rig_stall_trip_is_run_again_where_the_test_asks(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []
    attempts = LoggingAttempts(tmp_path / "logs", exit_codes.TRIPPED, _rig_stopped, STALE,
                               _done(exit_codes.OK, out="completed"))
    done = run_real_time(attempts, log_dir=tmp_path / "logs", rate_hz=100.0, stall_budget_s=0.08, what="a run",
                         wait=_quiet, records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.OK and attempts.made == 2
    assert "the rig's sensor frames stopped" in records[-1].host_stalls[0]


def test_a_host_that_stalls_every_run_fails_after_the_most_runs(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []
    tripped = [_done(exit_codes.TRIPPED, out="outcome: tripped (loop_stall)") for _ in range(realtime_runs.MAX_RUNS)]
    attempts = StallingAttempts(tmp_path, WAITED, *tripped)
    done = run_real_time(attempts, log_dir=tmp_path, rate_hz=RATE_HZ, stall_budget_s=BUDGET_S, what="a run", wait=_quiet,
                         records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.TRIPPED and attempts.made == realtime_runs.MAX_RUNS  # the last is the test's
    assert len(records[-1].host_stalls) == realtime_runs.MAX_RUNS - 1


def _heartbeat_log(folder: Path, heartbeat_times_s) -> None:
    """A candump ``can.log`` with the loop's HEARTBEAT frames (sent)."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "can.log").write_text("".join(f"({1000.0 + t:.6f}) vcan0 050#0000 T\n" for t in heartbeat_times_s))


WATCHDOG_REFUSAL = _done(
    exit_codes.INPUT_ERROR,
    err="error: could not arm within 3 s: arm refused: expected every pre-arm check to pass, failed: actuator_ready: "
        "drive ready=False, fault=True, expected ready without fault; the drive reports a latched FAULT HEARTBEAT_WATCHDOG",
)


def test_a_watchdog_refusal_to_arm_is_the_emulators_only_when_the_heartbeats_never_stopped(tmp_path):
    """CI in User-Mode Linux: refused at arming on HEARTBEAT_WATCHDOG while the loop sent a heartbeat every 10 ms."""
    steady = tmp_path / "steady"
    _heartbeat_log(steady, TICKS)
    found = realtime_runs.watchdog_arm_refusal(WATCHDOG_REFUSAL, [steady], 0.5)
    assert found is not None and "sent 100 heartbeats" in found and "none more than 10.0 ms apart" in found
    silent = tmp_path / "silent"  # the loop's heartbeats stopped as long as the watchdog: a finding
    _heartbeat_log(silent, np.concatenate([TICKS[TICKS < 0.2], TICKS[TICKS >= 0.2] + 0.5]))
    assert realtime_runs.watchdog_arm_refusal(WATCHDOG_REFUSAL, [silent], 0.5) is None
    other = _done(exit_codes.INPUT_ERROR, err="error: could not arm within 3 s: arm refused: stroke_centred")
    assert realtime_runs.watchdog_arm_refusal(other, [steady], 0.5) is None
    assert realtime_runs.watchdog_arm_refusal(_done(exit_codes.TRIPPED, out="HEARTBEAT_WATCHDOG"), [steady], 0.5) is None


def test_a_watchdog_refusal_to_arm_is_run_again_only_where_the_test_gives_the_watchdog(tmp_path):
    records: list[realtime_runs.RealTimeRecord] = []
    steady = functools.partial(_heartbeat_log, heartbeat_times_s=TICKS)
    attempts = LoggingAttempts(tmp_path / "logs", exit_codes.INPUT_ERROR, steady, WATCHDOG_REFUSAL,
                               _done(exit_codes.OK, out="completed"))
    done = run_real_time(attempts, log_dir=tmp_path / "logs", rate_hz=100.0, stall_budget_s=0.08, what="a run",
                         wait=_quiet, records=records, retry_host_stalls=True, drive_watchdog_s=0.5)
    assert done.returncode == exit_codes.OK and attempts.made == 2
    assert "latched HEARTBEAT_WATCHDOG before arming" in records[-1].host_stalls[0]
    plain = LoggingAttempts(tmp_path / "plain", exit_codes.INPUT_ERROR, steady, WATCHDOG_REFUSAL,
                            _done(exit_codes.OK, out="completed"))
    done = run_real_time(plain, log_dir=tmp_path / "plain", rate_hz=100.0, stall_budget_s=0.08, what="a run",
                         wait=_quiet, records=records, retry_host_stalls=True)
    assert done.returncode == exit_codes.INPUT_ERROR and plain.made == 1  # no watchdog given: the test's to judge
