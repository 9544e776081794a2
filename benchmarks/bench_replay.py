"""How long ``harness replay`` takes on a 30 s run, against the run's own duration (issue 34, item 1; target: a tenth).

Makes one dry run (the default profile and record, 30 s of record, lockstep unless ``--realtime``),
then replays it ``--repeats`` times in this process and reports, side by side in one run: the
replay's wall time (median and each), split into reading the run folder and running the ticks;
the run's loop time (first tick to last) and its wall-clock duration (metadata start to end); the
ratios; the replay's CPU time (the process's, less sensitive to a loaded machine than its wall
time); the replay's time per tick beside the run's own tick compute time (the ``compute_s``
column, median). Each replay must give every tick back identical, or the script says so.

    .venv/bin/python benchmarks/bench_replay.py                 # 30 s lockstep dry run, 3 replays
    .venv/bin/python benchmarks/bench_replay.py --run logs/<RUN>     # replay an existing run folder
"""

from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from datetime import datetime
from pathlib import Path

import numpy as np

RESULTS = Path(__file__).parent / "results" / "replay.json"


def make_run(log_dir: Path, duration_s: float, realtime: bool) -> Path:
    from harness.cli import main

    args = ["dry-run", "--quiet", "--duration", str(duration_s), "--log-dir", str(log_dir)]
    status = main(args if realtime else [*args, "--lockstep"])
    (folder,) = [p for p in log_dir.iterdir() if p.is_dir()]
    print(f"dry run: exit status {status}, {folder}")
    return folder


def time_replay(folder: Path) -> dict:
    """One replay: reading the folder, building and running the loop, comparing; each timed (s)."""
    from harness.replay.compare import exact_report
    from harness.replay.engine import replay_profile, run_replay
    from harness.replay.recorded import load_recorded

    started, cpu_started = time.perf_counter(), time.process_time()
    recorded = load_recorded(folder)
    read = time.perf_counter()
    result = run_replay(recorded, replay_profile(recorded))
    ran = time.perf_counter()
    report = exact_report(recorded, result)
    done, cpu_done = time.perf_counter(), time.process_time()
    return {"read_s": read - started, "run_s": ran - read, "compare_s": done - ran, "total_s": done - started,
            "cpu_s": cpu_done - cpu_started,
            "ticks": len(result.ticks), "identical": report.identical_run}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", type=Path, help="replay this run folder instead of making one")
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of record of the dry run made")
    parser.add_argument("--realtime", action="store_true", help="make a real-time dry run (default lockstep)")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--keep", type=Path, help="make the dry run's folder in this (empty) folder and keep it")
    args = parser.parse_args()
    from harness.model.warmup import warm_up

    warm_up()  # the compiled kernels are loaded once per process, as for any command
    with tempfile.TemporaryDirectory() as scratch:
        folder = args.run or make_run(Path(args.keep) if args.keep else Path(scratch), args.duration, args.realtime)
        metadata = json.loads((folder / "metadata.json").read_text())
        ticks = np.fromfile(folder / "ticks.bin", "<f8").reshape(-1, len(metadata["tick_columns"]))[1:]
        loop_span_s = float(ticks[-1, 0] - ticks[0, 0])
        wall_s = (datetime.fromisoformat(metadata["end_time"]) - datetime.fromisoformat(metadata["start_time"])).total_seconds()
        from harness.recording import load_run

        compute_s = float(np.median(load_run(folder)["compute_s"]))
        runs = [time_replay(folder) for _ in range(args.repeats)]
    total = statistics.median(r["total_s"] for r in runs)
    loop = statistics.median(r["run_s"] for r in runs)
    n = runs[0]["ticks"]
    summary = {
        "run": str(folder), "lockstep": metadata.get("lockstep"), "ticks": n, "loop_span_s": loop_span_s,
        "run_wall_s": wall_s, "replay_total_s_median": total, "replay_loop_s_median": loop,
        "replay_total_s": [r["total_s"] for r in runs], "read_s_median": statistics.median(r["read_s"] for r in runs),
        "replay_cpu_s_median": statistics.median(r["cpu_s"] for r in runs),
        "replay_over_loop_span": total / loop_span_s,
        "replay_cpu_over_loop_span": statistics.median(r["cpu_s"] for r in runs) / loop_span_s,
        "replay_over_run_wall": total / wall_s,
        "replay_per_tick_us": loop / n * 1e6, "run_compute_per_tick_us_median": compute_s * 1e6,
        "all_identical": all(r["identical"] for r in runs),
    }
    print(json.dumps(summary, indent=2))
    RESULTS.parent.mkdir(exist_ok=True)
    RESULTS.write_text(json.dumps(summary, indent=2) + "\n")


if __name__ == "__main__":
    main()
