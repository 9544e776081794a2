"""Where the real-time tick's CPU goes, and what the compiled receive path saves (issue 25, item 4).

Two measurements on the default real-time dry run (500 Hz, the virtual rig in its own process
on the ``seqpacket`` bus, recorder thread, console off), both in the loop thread's own CPU
time (``time.thread_time``), the figure of the compute budget:

``--paths`` (default)
    One run whose tick alternates every ``--block`` ticks between the reader and writer's
    direct ``seqpacket`` path (datagrams taken off the socket and decoded in one compiled call,
    frames sent as preallocated datagrams) and python-can's Message path (``bus.recv`` and
    ``bus.send`` of a :class:`can.Message` per frame, each decoded alone), so both are measured
    side by side on the same machine state. Prints each path's median and p99 CPU per tick and
    their ratio, per run.
``--parts``
    One run with the tick cut into its phases (poll, read, estimator, controller, compensation,
    supervisor, write, events, row, recorder, status): each phase's method wrapped in a timer
    (``time.thread_time_ns``, about 0.8 us a call, a system call), 11 per tick, and the tick's own
    CPU measurement beside them ("total", which includes the timers): read the phases as shares.

Usage: python benchmarks/bench_tick.py [--paths | --parts] [--duration S] [--runs N] [--block N]
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.loop import step as step_module  # noqa: E402 - the control step calls the compensation
from harness.loop.tick import ControlTick  # noqa: E402
from harness.profile import load_profile  # noqa: E402
from harness.runs.dry_run import DryRunOptions, dry_run  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402

PHASES = ("poll", "read", "estimator", "controller", "compensation", "supervisor", "write", "events", "row", "recorder",
          "status", "total")


#: The tick's own ``run``, which the measurements below wrap.
_TICK_RUN = ControlTick.run


def _run_with(run: Callable[..., object], duration_s: float) -> str:
    """One default dry run with ``run`` in place of ``ControlTick.run``; its outcome."""
    ControlTick.run = run  # type: ignore[method-assign,assignment]
    try:
        return _run(duration_s)
    finally:
        ControlTick.run = _TICK_RUN  # type: ignore[method-assign]


def _run(duration_s: float) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        profile = load_profile(REPO / "profiles" / "nceer_4dof.yaml")
        result = dry_run(profile, DryRunOptions(study=StudyOptions(duration_s=duration_s), log_dir=tmp, show_console=False))
    session = result.session
    return session.outcome if session.outcome != "tripped" else f"tripped ({session.trip_reason})"


def paths(duration_s: float, block: int) -> tuple[str, np.ndarray, np.ndarray]:
    """One dry run alternating the two paths every ``block`` ticks; (outcome, direct CPU, message CPU) per tick (us)."""
    direct: list[float] = []
    message: list[float] = []
    saved: dict[str, object] = {}

    def run(self: ControlTick, *args: object, **kwargs: object) -> object:
        reader, writer = self.reader, self.writer
        if not saved:
            saved["reader"], saved["writer"] = reader._datagrams, writer._datagrams  # the buses, when seqpacket
        use_direct = (self.ticks // block) % 2 == 0
        reader._datagrams = saved["reader"] if use_direct else None  # type: ignore[assignment]
        writer._datagrams = saved["writer"] if use_direct else None  # type: ignore[assignment]
        command = _TICK_RUN(self, *args, **kwargs)  # type: ignore[arg-type]
        (direct if use_direct else message).append(self.cpu_s * 1e6)
        return command

    outcome = _run_with(run, duration_s)
    warm = 2 * block  # the first blocks include the start
    return outcome, np.array(direct[warm:]), np.array(message[warm:])


def _timed(function: Callable[..., object], totals: dict[str, int], name: str) -> Callable[..., object]:
    """``function`` that adds its own thread CPU time (ns) to ``totals[name]``."""
    clock = time.thread_time_ns

    def timed(*args: object, **kwargs: object) -> object:
        started = clock()
        try:
            return function(*args, **kwargs)
        finally:
            totals[name] += clock() - started

    return timed


def parts(duration_s: float) -> tuple[str, np.ndarray]:
    """One dry run with the tick's phases timed; (outcome, array ticks x phases in us).

    Each phase's method is wrapped on its object on the first tick (the tick's own code runs
    unchanged); the last column is the tick's own CPU measurement (``ControlTick.cpu_s``).
    """
    totals = dict.fromkeys(PHASES[:-1], 0)
    rows: list[list[float]] = []
    restore: list[tuple[object, str, object]] = [(step_module, "compensate", step_module.compensate)]

    def wrap(tick: ControlTick) -> None:
        for owner, method, phase in (
            (tick.reader, "poll", "poll"), (tick, "read", "read"), (tick.estimator, "update", "estimator"),
            (tick.controller, "update", "controller"), (tick.supervisor, "update", "supervisor"), (tick, "write", "write"),
            (tick.supervisor.events, "drain", "events"), (tick, "_fill_row", "row"), (tick.recorder, "record_row", "recorder"),
            (tick, "publish", "status"),
        ):
            if owner is not None:  # on the class: the safety objects have __slots__
                kind = type(owner)
                restore.append((kind, method, kind.__dict__.get(method)))
                setattr(kind, method, _timed(getattr(kind, method), totals, phase))
        step_module.compensate = _timed(step_module.compensate, totals, "compensation")  # type: ignore[assignment]

    def run(self: ControlTick, *args: object, **kwargs: object) -> object:
        if len(restore) == 1:
            wrap(self)
        for phase in totals:
            totals[phase] = 0
        command = _TICK_RUN(self, *args, **kwargs)  # type: ignore[arg-type]
        totals["read"] -= totals["poll"]  # the tick's read polls the bus first: the poll is its own column
        rows.append([*(totals[phase] / 1e3 for phase in PHASES[:-1]), self.cpu_s * 1e6])
        return command

    try:
        outcome = _run_with(run, duration_s)
    finally:
        for owner, method, before in reversed(restore):
            if before is None:
                delattr(owner, method)
            else:
                setattr(owner, method, before)
    return outcome, np.array(rows[500:])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--paths", action="store_true",
                      help="the direct seqpacket path against python-can's Message path (default)")
    mode.add_argument("--parts", action="store_true", help="the tick's phases, each timed")
    parser.add_argument("--duration", type=float, default=20.0, help="seconds of record per run (default 20)")
    parser.add_argument("--runs", type=int, default=3, help="runs (default 3)")
    parser.add_argument("--block", type=int, default=250, help="ticks per block before the path alternates (default 250)")
    args = parser.parse_args()
    if args.parts:
        print("| run | outcome | " + " | ".join(PHASES) + " |")
        print("|---|---|" + "---|" * len(PHASES))
        for k in range(1, args.runs + 1):
            outcome, table = parts(args.duration)
            medians = " | ".join(f"{np.median(table[:, j]):.1f}" for j in range(len(PHASES)))
            print(f"| {k} | {outcome} | {medians} |", flush=True)
        print("\nmedians per tick (us) of the loop thread's CPU; the timers add about 1 us each, 11 per tick")
        return 0
    print("| run | outcome | direct path median / p99 (us) | Message path median / p99 (us) | ratio of medians |")
    print("|---|---|---|---|---|")
    ratios = []
    for k in range(1, args.runs + 1):
        outcome, direct, message = paths(args.duration, args.block)
        ratio = float(np.median(direct) / np.median(message)) if len(message) else math.nan
        ratios.append(ratio)
        print(f"| {k} | {outcome} | {np.median(direct):.1f} / {np.percentile(direct, 99):.1f} | "
              f"{np.median(message):.1f} / {np.percentile(message, 99):.1f} | {ratio:.2f} |", flush=True)
    print(f"\nmedian ratio over the runs: {np.median(ratios):.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
