"""Reliability of the real-time dry run: N back-to-back runs, as a user runs them (issue 10).

Each run is the command a user types, `harness dry-run` (real time, rig in its own
process on the private bus), started as a fresh process one after the other. The
script reports:

- the completion rate and the trip reasons;
- the stall histogram over all runs: gaps between the starts of consecutive ticks, from
  each run's ``signals.csv`` (``t_s + lateness_s``), in bins up to and beyond the budget;
- the loop thread's CPU per tick (median of the runs' medians and p99s);
- the bare-loop baseline measured in the same session: the loop's own scheduler
  (sleep, then spin) run empty at the same rate, on this machine, just before the runs,
  which is what the host alone allows.

With ``--load N`` it first starts N busy processes (a CPU-bound Python loop each, as a laptop
building software while a dry run runs) and keeps them running through every run; ``--set``
passes profile overrides to every run (``--set loop.realtime.fifo_priority=0``: without
real-time priority). A run the pre-flight check refuses (outcome ``refused``, nothing moved) is
counted apart from a trip.

Usage::

    python benchmarks/bench_reliability.py --runs 20
    python benchmarks/bench_reliability.py --runs 10 --load 2                                  # every core busy
    python benchmarks/bench_reliability.py --runs 10 --load 2 --set loop.realtime.fifo_priority=0
    python benchmarks/bench_reliability.py --runs 10 --record el_centro --pga 0.34 --time-scale 2 \\
        --records-dir ../shared/data/ground_motions

Prints a markdown table for benchmarks/README.md and writes the raw figures as JSON.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.loop.preflight import measure_host_timing  # noqa: E402

#: Upper edges of the stall-histogram bins (ms); the last bin is everything beyond the budget.
GAP_EDGES_MS = (3.0, 5.0, 10.0, 15.0, 20.0)


def bare_loop_baseline(rate_hz: float, duration_s: float, budget_s: float) -> dict:
    """The loop's scheduler run empty: what the host alone allows (lateness in us)."""
    timing = measure_host_timing(rate_hz, budget_s, spin_s=200e-6, duration_s=duration_s)
    return {"wakeups": timing.wakeups, "p50_us": timing.p50_s * 1e6, "p99_us": timing.p99_s * 1e6,
            "max_us": timing.max_s * 1e6}


def _gaps_ms(folder: Path) -> np.ndarray:
    with open(folder / "signals.csv", encoding="utf-8") as handle:
        header = handle.readline().strip().split(",")
    t_col, late_col = header.index("t_s"), header.index("lateness_s")
    data = np.loadtxt(folder / "signals.csv", delimiter=",", skiprows=1, usecols=(t_col, late_col), ndmin=2)
    starts = data[:, 0] + data[:, 1]
    return np.diff(starts) * 1e3


def one_run(args: argparse.Namespace, log_dir: Path) -> dict:
    """One `harness dry-run` as a fresh process; its outcome and timing from the run folder."""
    command = [sys.executable, "-m", "harness.cli", "dry-run", "--quiet", "--log-dir", str(log_dir)]
    for flag, value in (("--duration", args.duration), ("--record", args.record), ("--pga", args.pga),
                        ("--time-scale", args.time_scale), ("--records-dir", args.records_dir), ("--rate", args.rate)):
        if value is not None:
            command += [flag, str(value)]
    for setting in args.set:
        command += ["--set", setting]
    started = time.monotonic()
    done = subprocess.run(command, capture_output=True, text=True, cwd=REPO)
    wall_s = time.monotonic() - started
    folders = sorted(p for p in log_dir.iterdir() if p.is_dir())
    if not folders:
        return {"exit": done.returncode, "outcome": "no run folder", "trip_reason": done.stderr.strip()[-300:],
                "wall_s": wall_s}
    folder = folders[-1]
    metadata = json.loads((folder / "metadata.json").read_text())
    summary = metadata.get("summary") or {}
    timing = summary.get("timing") or {}
    result = {
        "exit": done.returncode, "outcome": metadata.get("outcome"), "trip_reason": metadata.get("trip_reason"),
        "wall_s": wall_s, "cpu_median_us": timing.get("cpu_median_s", float("nan")) * 1e6,
        "cpu_p99_us": timing.get("cpu_p99_s", float("nan")) * 1e6,
        "stalls_ridden_through": timing.get("stalls_ridden_through"), "longest_stall_ms": timing.get("longest_stall_s", 0) * 1e3,
        "host_timing": (summary.get("host_timing") or {}).get("verdict"),
        "scheduling": (summary.get("scheduling") or {}).get("policy"),
        "recorder_longest_hold_us": ((metadata.get("recorder") or {}).get("longest_hold_s") or 0.0) * 1e6,
        "threads": timing.get("threads"),
    }
    if (folder / "signals.csv").is_file() and metadata.get("outcome") != "refused":  # a refused run has no rows
        gaps = _gaps_ms(folder)
        edges = (0.0, *GAP_EDGES_MS, np.inf)
        result["gap_histogram"] = np.histogram(gaps, bins=edges)[0].tolist()
    return result


def table(results: list[dict], baseline: dict, args: argparse.Namespace) -> str:
    """The markdown summary."""
    completed = sum(r["outcome"] == "completed" for r in results)
    refused = sum(r["outcome"] == "refused" for r in results)
    reasons = collections.Counter(r["trip_reason"] or r["outcome"] for r in results
                                  if r["outcome"] not in ("completed", "refused"))
    policies = sorted({str(r.get("scheduling")) for r in results})
    hist = np.sum([r.get("gap_histogram", [0] * (len(GAP_EDGES_MS) + 1)) for r in results], axis=0)
    labels = (
        [f"< {GAP_EDGES_MS[0]:g}"]
        + [f"{a:g}-{b:g}" for a, b in itertools.pairwise(GAP_EDGES_MS)]
        + [f"> {GAP_EDGES_MS[-1]:g}"]
    )
    cpu_med = np.nanmedian([r.get("cpu_median_us", np.nan) for r in results])
    cpu_p99 = np.nanmedian([r.get("cpu_p99_us", np.nan) for r in results])
    longest = max((r.get("longest_stall_ms") or 0.0) for r in results)
    hold = max((r.get("recorder_longest_hold_us") or 0.0) for r in results)
    case = f"{args.record or 'synthetic (default)'}" + (f", {args.pga} g" if args.pga else "") + (
        f", time scale {args.time_scale}" if args.time_scale else "") + f", {args.duration or 'profile'} s"
    case += f", {args.load} busy processes" if args.load else ""
    case += "".join(f", --set {setting}" for setting in args.set)
    lines = [
        "| case | scheduling | runs completed | refused by the pre-flight | trips | loop CPU per tick median / p99 "
        "(us, median of runs) | longest gap (ms) | recorder's longest lock hold (us) | bare loop p50 / p99 / max (us) |",
        "|---|---|---|---|---|---|---|---|---|",
        f"| {case} | {', '.join(policies)} | {completed} / {len(results)} | {refused} | {dict(reasons) or 'none'} | "
        f"{cpu_med:.0f} / {cpu_p99:.0f} | {longest:.1f} | {hold:.0f} | "
        f"{baseline['p50_us']:.1f} / {baseline['p99_us']:.0f} / {baseline['max_us']:.0f} |",
        "",
        "Gaps between tick starts, all runs (ms): "
        + ", ".join(f"{label}: {int(n)}" for label, n in zip(labels, hist, strict=True)),
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=20, help="back-to-back dry runs (default 20)")
    parser.add_argument("--duration", type=float, help="seconds of record per run (default: the profile's, 30 s)")
    parser.add_argument("--record")
    parser.add_argument("--records-dir")
    parser.add_argument("--pga", type=float)
    parser.add_argument("--time-scale", type=float)
    parser.add_argument("--rate", type=float)
    parser.add_argument("--baseline-s", type=float, default=10.0, help="seconds of bare-loop baseline (default 10)")
    parser.add_argument("--load", type=int, default=0, help="busy CPU-bound processes kept running throughout (default 0)")
    parser.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE", help="profile override for every run")
    parser.add_argument("--json", type=Path, default=REPO / "benchmarks" / "results" / "reliability.json")
    args = parser.parse_args(argv)
    rate = args.rate or 500.0
    hogs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.load)]
    try:
        return _measure(args, rate)
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()


def _measure(args: argparse.Namespace, rate: float) -> int:
    baseline = bare_loop_baseline(rate, args.baseline_s, 0.02)
    print(f"bare loop at {rate:g} Hz for {args.baseline_s:g} s: p50 {baseline['p50_us']:.1f} us, "
          f"p99 {baseline['p99_us']:.0f} us, max {baseline['max_us']:.0f} us", flush=True)
    results = []
    with tempfile.TemporaryDirectory(prefix="reliability-") as tmp:
        for k in range(args.runs):
            log_dir = Path(tmp) / f"run{k:03d}"
            log_dir.mkdir()
            result = one_run(args, log_dir)
            results.append(result)
            print(f"run {k + 1:3d}/{args.runs}: {result['outcome']}"
                  f"{' (' + str(result['trip_reason']) + ')' if result['outcome'] != 'completed' else ''}, "
                  f"stalls {result.get('stalls_ridden_through')}, longest {result.get('longest_stall_ms', 0):.1f} ms, "
                  f"CPU median {result.get('cpu_median_us', float('nan')):.0f} us, {result['wall_s']:.0f} s", flush=True)
    print()
    print(table(results, baseline, args))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"baseline": baseline, "runs": results, "args": {k: v for k, v in vars(args).items()
                                                                                   if k != "json"}}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
