"""One way for every real-time test to start its run: wait for a quiet second, retry a run the pre-flight refused.

A real-time dry run measures the host before it arms (harness/loop/preflight.py): one second of the
loop's scheduler running empty, the rig's frames watched. A second in which this host would have
tripped refuses the run, exit status 2, before anything moved, with ``this host cannot run the loop
within its stall budget`` and the figures. That refusal is the pre-flight doing its job on a busy
machine (a CI runner where another job just woke up), not a failure of the path under test, so a
real-time test may run again after it. The pre-flight's bounds are never loosened here: the test
waits, then asks again.

:func:`run_real_time`, for each run:

1. waits, at most :data:`QUIET_WAIT_S`, for a quiet second: the pre-flight's own measurement
   (:func:`~harness.loop.preflight.measure_host_timing`, without the rig) at the run's rate and
   stall budget, with the scheduling the run's loop takes (the shipped ``fifo_priority: auto``:
   SCHED_FIFO where permitted, and the machine's idle CPU judged where not, as the pre-flight
   does), gives ``ok``, the verdict with margin. A host that never gets quiet within that time
   still runs: the pre-flight of the run judges it;
2. runs the test's command; a run refused by the pre-flight moves its run folder aside (into
   ``<log_dir>-refused``, so the test sees only the run that went on) and is run again, up to
   :data:`MAX_RUNS` runs in all;
3. returns the first run the pre-flight let through, whatever its outcome: a trip or any other
   failure is the test's to judge, never retried; the one exception, asked for by a test whose host is
   an emulator or a machine shared with other work (``retry_host_stalls``: the vcan stage in User-Mode
   Linux, the host's real-time dry runs on a 2-vCPU CI runner), is a trip on a stall the host made, as the
   run's own record shows it: ``loop_stall`` on a stall the loop spent waiting for its deadline
   (:func:`host_stall_trip`), or ``sensor_stale`` where the run's ``can.log`` shows the rig's frames stopped
   longer than the limit while the loop's commands had no gap that long (:func:`rig_stall_trip`), or, where the
   test gives the drive's watchdog, a refusal to arm on its HEARTBEAT_WATCHDOG while the loop's heartbeats had
   no gap that long (:func:`watchdog_arm_refusal`);
4. fails the test with every refusal's figures when all :data:`MAX_RUNS` were refused: this host is
   too noisy to run the test at all, and says so.

Every call is counted (:data:`RECORDS`): tests/conftest.py attaches the counts to the test's report
and prints one summary line at the end of the stage, so retries are seen even where every test passed.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import signal
import subprocess
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest

from drivers.protocol.codec import load_protocol
from harness import exit_codes
from harness.loop.preflight import HostTiming, measure_host_timing
from harness.loop.timing import GAP_PART_WORDS
from harness.realtime.host import AUTO, Scheduling, request_fifo, restore_scheduling
from harness.replay.canlog import LoggedFrame, read_can_log

#: Runs of one test at most: the first and the retries of runs the pre-flight refused.
MAX_RUNS = 5
#: Longest wait for a quiet second before each run (s); then the run starts anyway.
QUIET_WAIT_S = 30.0
#: The words of the pre-flight's refusal (HostTiming.check); tests/unit/test_realtime_runs.py holds them to it.
REFUSAL = "this host cannot run the loop within its stall budget"
#: The words of a refusal to arm because the loop itself stalled past its budget while arming (runner's ArmTimeout
#: with its stall note): the host stopped the loop after the pre-flight passed, nothing moved; the drive's watchdog
#: latched a fault. The same host noise as the pre-flight's refusal, caught a moment later.
ARM_STALL = "the loop itself stalled"
#: The words that open every refusal to arm (harness/loop/runner.py ArmTimeout).
ARM_REFUSAL = "could not arm within"
#: The pre-flight's figures in a refusal: from "host timing at" to the verdict; or the arming stall's figures.
FIGURES = re.compile(r"host timing at .*?: refused|the loop itself stalled [^:]*")
#: The words of a trip for a stall past the budget, and of a stall the loop spent waiting for its deadline:
#: the loop had nothing to do and was not run (the host, or an emulator's virtual CPU, stopped it).
STALL_TRIP = "tripped (loop_stall)"
WAITING_STALL = f"the loop was {GAP_PART_WORDS['wait']}"
#: The words of a trip for sensor frames older than their limit.
STALE_TRIP = "tripped (sensor_stale)"
#: The words of a refusal to arm on the drive's latched heartbeat watchdog (the pre-arm check's detail).
WATCHDOG_FAULT = "HEARTBEAT_WATCHDOG"
#: The name of the counts in a test report's user_properties.
PROPERTY = "real_time_runs"


@dataclass
class RealTimeRecord:
    """What :func:`run_real_time` did for one test: runs, refusals with their figures, seconds waited."""

    what: str
    runs: int = 0
    refusals: list[str] = field(default_factory=list)
    waited_s: float = 0.0
    never_quiet: int = 0
    host_stalls: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        """Plain data for a test report's user_properties (crosses from an xdist worker)."""
        return {"what": self.what, "runs": self.runs, "refusals": list(self.refusals), "waited_s": self.waited_s,
                "never_quiet": self.never_quiet, "host_stalls": list(self.host_stalls)}


#: Records made since conftest last collected them (it drains them into the running test's report).
RECORDS: list[RealTimeRecord] = []


@dataclass(frozen=True)
class QuietWait:
    """The outcome of :func:`wait_for_quiet_second`."""

    quiet: bool
    waited_s: float
    last: HostTiming


def _as_the_loop() -> Scheduling:
    """The scheduling the run's loop takes with the shipped ``loop.realtime.fifo_priority: auto``."""
    return request_fifo(AUTO, what="the quiet-second check")


def wait_for_quiet_second(
    rate_hz: float, stall_budget_s: float, limit_s: float = QUIET_WAIT_S,
    measure: Callable[..., HostTiming] = measure_host_timing, clock: Callable[[], float] = time.monotonic,
    scheduling: Callable[[], Scheduling] = _as_the_loop,
) -> QuietWait:
    """Measure one second at a time until the pre-flight's measurement says ``ok``, for at most ``limit_s``.

    Parameters
    ----------
    rate_hz : float
        The run's loop rate (Hz).
    stall_budget_s : float
        The run's stall budget (s), ``safety.run.max_stall_s``.
    limit_s : float
        Longest wait (s); the last measurement is returned with ``quiet`` False after it.
    measure, clock : callable
        :func:`~harness.loop.preflight.measure_host_timing` and the wall clock, injectable for tests.
    scheduling : callable
        Takes the loop's scheduling for the measuring thread (given back after each second); the idle CPU
        is judged where it got no real-time priority, as the pre-flight judges it.
    """
    started = clock()
    while True:
        taken = scheduling()
        try:
            timing = measure(rate_hz, stall_budget_s, 0.0, duration_s=1.0, judge_idle=not taken.granted)
        finally:
            restore_scheduling(taken)
        waited_s = clock() - started
        if timing.verdict == "ok" or waited_s >= limit_s:
            return QuietWait(timing.verdict == "ok", waited_s, timing)


def refused_by_preflight(done: subprocess.CompletedProcess) -> bool:
    """True when ``done`` is a run refused for the host's timing before anything moved: exit status 2 with the words.

    Either the pre-flight's refusal, or a refusal to arm that names the loop's own stall past its budget as
    the cause (the host stopped the loop while arming, after the pre-flight passed). A refusal to arm for
    any other reason is the test's to judge.
    """
    if done.returncode != exit_codes.INPUT_ERROR:
        return False
    output = _output(done)
    return REFUSAL in output or (ARM_REFUSAL in output and ARM_STALL in output)


def host_stall_trip(done: subprocess.CompletedProcess, folders: list[Path]) -> str | None:
    """The stall's event when ``done`` tripped ``loop_stall`` on a stall the loop spent waiting for its deadline; else None.

    Such a stall is the host not running a loop that had nothing left to do (inside User-Mode Linux, its one
    virtual CPU stopped for tens of milliseconds); the trip is the supervisor doing its job, and the run says
    nothing about the path under test. A stall the loop spent in its own work is never this.
    """
    if done.returncode != exit_codes.TRIPPED or STALL_TRIP not in _output(done):
        return None
    for folder in folders:
        events = folder / "events.jsonl"
        for line in events.read_text().splitlines() if events.is_file() else ():
            if '"stall_past_budget"' in line and WAITING_STALL in line:
                return line
    return None


def rig_stall_trip(done: subprocess.CompletedProcess, folders: list[Path], limit_s: float) -> str | None:
    """What ``can.log`` shows when ``done`` tripped ``sensor_stale`` because the rig's process stopped sending; else None.

    Inside User-Mode Linux the rig's process, on the same one virtual CPU as the loop, is now and then not
    run for 0.1-0.2 s while the loop goes on; on a shared machine both are stopped at once now and then, the
    loop within its stall budget and the rig a frame period longer. Either way its sensor frames age past the
    limit and the loop trips, as it must. The run's ``can.log`` tells that from a fault of the path: the rig's
    table sensor frames (received) stop for longer than ``limit_s`` while the loop's commands (sent) have no gap
    that long in the same stretch. A loop that stalled past the limit itself is never this.
    """
    if done.returncode != exit_codes.TRIPPED or STALE_TRIP not in _output(done):
        return None
    protocol = load_protocol(fd=True)  # the FD protocol names both the classic table frame and the FD sensor set
    sensor_ids = {protocol[name].frame_id for name in ("TABLE_SENSORS", "SENSOR_SET")}
    command_id = protocol["ACTUATOR_CMD"].frame_id
    for frames in _run_frames(folders):
        received = np.array([f.timestamp for f in frames if f.rx and f.arbitration_id in sensor_ids])
        sent = np.array([f.timestamp for f in frames if not f.rx and f.arbitration_id == command_id])
        if len(received) < 2 or len(sent) < 2:
            continue
        gaps = np.diff(received)
        for k in np.flatnonzero(gaps > limit_s):
            start, end = received[k], received[k + 1]
            inside = np.diff(np.concatenate([[start], sent[(sent > start) & (sent < end)], [end]]))
            if inside.max() < limit_s:
                return (f"the rig's sensor frames stopped {gaps[k] * 1e3:.1f} ms (limit {limit_s * 1e3:.0f} ms) while "
                        f"the loop sent {len(inside) - 1} commands, none more than {inside.max() * 1e3:.1f} ms apart")
    return None


def watchdog_arm_refusal(done: subprocess.CompletedProcess, folders: list[Path], watchdog_s: float) -> str | None:
    """What ``can.log`` shows when ``done`` was refused at arming on the drive's heartbeat watchdog, which the
    loop's heartbeats never gave cause for; else None.

    Inside User-Mode Linux the loop and the rig run at SCHED_FIFO on one virtual CPU, and the kernel's network
    work (ksoftirqd, normal scheduling) waits while they run: a run here saw the harness's heartbeats reach the
    rig's socket 0.3-0.7 s after they were sent, every 10 ms, and the virtual drive, seeing none for longer than
    its watchdog, latched HEARTBEAT_WATCHDOG before arming (the rig's own log, 29 Nov 2026). The drive did its
    job on what reached it; the run says nothing about the path under test. The run's ``can.log`` tells that from
    a harness that went silent: the heartbeats it sent have no gap as long as ``watchdog_s``.
    """
    output = _output(done)
    if done.returncode != exit_codes.INPUT_ERROR or ARM_REFUSAL not in output or WATCHDOG_FAULT not in output:
        return None
    heartbeat_id = load_protocol()["HEARTBEAT"].frame_id
    for frames in _run_frames(folders):
        sent = np.array([f.timestamp for f in frames if not f.rx and f.arbitration_id == heartbeat_id])
        longest_s = float(np.diff(sent).max()) if len(sent) >= 2 else math.inf
        if longest_s < watchdog_s:
            return (f"the drive latched {WATCHDOG_FAULT} before arming while the loop sent {len(sent)} heartbeats, "
                    f"none more than {longest_s * 1e3:.1f} ms apart (watchdog {watchdog_s * 1e3:.0f} ms)")
    return None


def _run_frames(folders: list[Path]) -> Iterator[list[LoggedFrame]]:
    """The frames of each run folder's ``can.log``, for the folders that have one."""
    for folder in folders:
        log = folder / "can.log"
        if log.is_file():
            yield read_can_log(log)


def _output(done: subprocess.CompletedProcess) -> str:
    return f"{done.stdout or ''}{done.stderr or ''}"


def _emulator_stall(
    done: subprocess.CompletedProcess, folders: list[Path], limit_s: float, watchdog_s: float | None,
) -> str | None:
    """A trip or a refusal to arm the emulator's stall made (:func:`host_stall_trip`, :func:`rig_stall_trip`,
    :func:`watchdog_arm_refusal` where the test gives the drive's watchdog), described; else None."""
    return (host_stall_trip(done, folders) or rig_stall_trip(done, folders, limit_s)
            or (watchdog_arm_refusal(done, folders, watchdog_s) if watchdog_s is not None else None))


def _set_aside(log_dir: Path, before: set[Path]) -> None:
    """Move the run folders a refused run made in ``log_dir`` into ``<log_dir>-refused``."""
    if not log_dir.is_dir():
        return
    aside = log_dir.with_name(log_dir.name + "-refused")
    for folder in sorted(set(log_dir.iterdir()) - before):
        aside.mkdir(exist_ok=True)
        shutil.move(folder, aside / folder.name)


def run_real_time(
    attempt: Callable[[], subprocess.CompletedProcess], *, log_dir: Path, rate_hz: float, stall_budget_s: float,
    what: str, wait: Callable[[float, float], QuietWait] = wait_for_quiet_second, records: list[RealTimeRecord] = RECORDS,
    retry_host_stalls: bool = False, max_runs: int = MAX_RUNS, drive_watchdog_s: float | None = None,
) -> subprocess.CompletedProcess:
    """Run ``attempt`` after a quiet second; run it again while the pre-flight refuses it (module docstring).

    Parameters
    ----------
    attempt : callable
        Starts the real-time run and returns its finished process (text output).
    log_dir : Path
        The run's ``--log-dir``: a refused run's folder is moved out of it.
    rate_hz, stall_budget_s : float
        The run's loop rate (Hz) and stall budget (s), for the quiet second.
    what : str
        The run, for the report.
    wait : callable
        :func:`wait_for_quiet_second`, injectable for tests.
    records : list
        Where the run's :class:`RealTimeRecord` goes: :data:`RECORDS`, or a test's own list.
    retry_host_stalls : bool
        Also run again a run that tripped on a stall the host made: ``loop_stall`` on a stall the loop spent
        waiting for its deadline (:func:`host_stall_trip`), or ``sensor_stale`` while the rig's frames stopped
        longer than ``stall_budget_s`` and the loop's commands did not (:func:`rig_stall_trip`): for a test whose
        host is an emulator (User-Mode Linux) or a shared machine, where such stalls are the host's; counted and
        reported like the refusals, within the same ``max_runs``.
    max_runs : int
        Runs at most: :data:`MAX_RUNS`, or more for a test whose host stalls more often (an emulator).
    drive_watchdog_s : float, optional
        The virtual drive's watchdog (s), given by a test in an emulator: with ``retry_host_stalls``, a refusal to
        arm on its HEARTBEAT_WATCHDOG while the loop's heartbeats had no gap that long is run again too
        (:func:`watchdog_arm_refusal`).

    Returns
    -------
    subprocess.CompletedProcess
        The first run the pre-flight did not refuse.
    """
    record = RealTimeRecord(what)
    records.append(record)
    while True:
        quiet = wait(rate_hz, stall_budget_s)
        record.waited_s += quiet.waited_s
        record.never_quiet += not quiet.quiet
        before = set(log_dir.iterdir()) if log_dir.is_dir() else set()
        done = attempt()
        record.runs += 1
        stall = _emulator_stall(done, sorted(set(log_dir.iterdir()) - before), stall_budget_s, drive_watchdog_s) \
            if retry_host_stalls and log_dir.is_dir() else None
        if stall is not None and record.runs < max_runs:
            record.host_stalls.append(stall[-300:])
            print(f"{what}: run {record.runs} tripped on a stall the host made: {stall[-300:]}")
            _set_aside(log_dir, before)
            continue
        if not refused_by_preflight(done):
            print(f"{what}: run {record.runs} went past the pre-flight ({len(record.refusals)} refused before it, "
                  f"{len(record.host_stalls)} tripped on the host's stalls)")
            return done
        figures = FIGURES.search(_output(done))
        record.refusals.append(figures.group(0) if figures else _output(done)[-500:])
        print(f"{what}: run {record.runs} refused by the pre-flight: {record.refusals[-1]}")
        _set_aside(log_dir, before)
        if record.runs >= max_runs:
            pytest.fail(
                f"{what}: the pre-flight refused all {record.runs} runs, so this host was never quiet enough to run "
                f"this real-time test ({record.waited_s:.0f} s spent waiting for a quiet second, none found before "
                f"{record.never_quiet} of the runs; last quiet check: {quiet.last.summary()}). The pre-flight's "
                "figures of each run:\n  " + "\n  ".join(record.refusals),
                pytrace=False,
            )


def summary_line(records: list[dict]) -> str:
    """The stage's one line on its real-time runs (from :meth:`RealTimeRecord.as_dict` of each test)."""
    runs = sum(r["runs"] for r in records)
    refused = sum(len(r["refusals"]) for r in records)
    waited = sum(r["waited_s"] for r in records)
    never = sum(r["never_quiet"] for r in records)
    stalls = sum(len(r.get("host_stalls", ())) for r in records)
    return (f"real-time runs: {len(records)} asked for, {runs} started, {refused} refused by the pre-flight "
            f"(run again, up to {MAX_RUNS} runs a test or as many as it asks), {stalls} tripped on a stall the host "
            f"made (the loop waiting, or the rig's frames stopped: run again where the test allows), "
            f"{waited:.0f} s spent waiting for a quiet second ({never} runs started without one)")


def running_folder(log_dir: Path, process: subprocess.Popen, timeout_s: float = 120.0) -> Path | None:
    """The run folder once its events say RUNNING (None if the process ended first)."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline and process.poll() is None:
        for folder in log_dir.iterdir():
            events = folder / "events.jsonl"
            if events.exists() and '"RUNNING"' in events.read_text():
                return folder
        time.sleep(0.05)
    return None


def pause(process: subprocess.Popen, stop_s: float, after_s: float) -> None:
    """After ``after_s``, stop ``process`` (SIGSTOP) for ``stop_s`` and let it go on (SIGCONT): a stall it must ride."""
    time.sleep(after_s)
    os.kill(process.pid, signal.SIGSTOP)
    time.sleep(stop_s)
    os.kill(process.pid, signal.SIGCONT)


def end(process: subprocess.Popen) -> None:
    """Kill ``process`` if it still runs (continued first, in case it was left stopped) and reap it."""
    if process.poll() is None:
        os.kill(process.pid, signal.SIGCONT)
        process.kill()
        process.wait()
