"""Is a stall the loop's or the machine's? Watch the host with an independent sleeper during dry runs (issue 32).

A sleeper process at normal priority wakes every 10 ms and records when it woke. A gap in its
wake-ups is a time the whole machine did not run it: on a shared VM, the hypervisor stopping
the guest. Each run is the command a user types (``harness dry-run``, real time, the rig in its
own process), one after the other; afterwards every stall the run logged (its ``events.jsonl``:
``stall_ridden_through`` above ``--min-ms``, ``loop_stall``, ``sensor_stale``) is matched with
the sleeper's gaps within 50 ms of the stall's end. A stall the sleeper shared is the machine's:
no code in the loop can ride through a frozen guest, and the stall budget (docs/SAFETY.md) stays
what the rig's physics allows. ``--idle S`` first watches the idle machine for S seconds.

Usage::

    python benchmarks/host_freezes.py --runs 5 --idle 30

Prints one line per run and a markdown table for benchmarks/README.md.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
#: The sleeper's period (s) and the gap (s) that counts as the machine stopping it.
PERIOD_S, FROZEN_S = 0.010, 0.015
#: How near a sleeper's gap must end to a stall's end to share it (s).
NEAR_S = 0.05
SLEEPER = f"""
import sys, time
end = time.time() + float(sys.argv[1])
with open(sys.argv[2], "w", buffering=1) as out:  # a line at a time: the sleeper is stopped with SIGTERM
    while time.time() < end:
        out.write(f"{{time.time():.4f}}\\n")
        time.sleep({PERIOD_S})
"""


def watch(seconds: float, path: Path) -> subprocess.Popen:
    """Start the sleeper for ``seconds`` (s), writing its wake-up times to ``path``."""
    return subprocess.Popen([sys.executable, "-c", SLEEPER, str(seconds), str(path)])


def gaps(path: Path) -> list[tuple[float, float]]:
    """``(end wall time, length s)`` of each gap in the sleeper's wake-ups longer than :data:`FROZEN_S`."""
    times = [float(line) for line in path.read_text().split()]
    return [(b, b - a) for a, b in zip(times, times[1:], strict=False) if b - a > FROZEN_S]


def stalls(run_folder: Path, min_s: float) -> list[tuple[float, float, str]]:
    """``(wall time, length s, event name)`` of each stall the run logged at or above ``min_s``."""
    found = []
    for line in (run_folder / "events.jsonl").read_text().splitlines():
        event = json.loads(line)
        name, detail = event["name"], event["detail"]
        if name == "stall_ridden_through":
            length = float(detail.split()[0]) / 1e3
        elif name == "loop_stall":
            length = float(detail.split("went ")[1].split()[0]) / 1e3
        elif name == "sensor_stale":
            length = float(detail.split("age ")[1].split()[0]) / 1e3
        else:
            continue
        if length >= min_s:
            found.append((event["wall_time"], length, name))
    return found


def one_run(k: int, folder: Path, min_s: float, extra: list[str]) -> dict:
    """One dry run watched by the sleeper; its outcome, stalls and the machine's gaps during it."""
    logs, trace = folder / f"run{k}", folder / f"sleeper{k}.txt"
    sleeper = watch(90.0, trace)
    time.sleep(0.2)
    done = subprocess.run([str(Path(sys.executable).with_name("harness")), "dry-run", "--quiet", "--log-dir", str(logs), *extra],
                          cwd=REPO, capture_output=True, text=True)
    sleeper.terminate()
    sleeper.wait()
    outcome = next((line for line in done.stdout.splitlines() if line.startswith("outcome:")), "outcome: ?")
    folders = [p for p in logs.iterdir() if (p / "events.jsonl").is_file()] if logs.is_dir() else []
    if len(folders) != 1:
        raise SystemExit(f"run {k}: expected one run folder in {logs}; harness dry-run said:\n{done.stdout}{done.stderr}")
    (run,) = folders
    frozen = gaps(trace)
    logged = stalls(run, min_s)
    shared = [s for s in logged if any(abs(end - s[0]) <= NEAR_S for end, _ in frozen)]
    return {"exit": done.returncode, "outcome": outcome.split(";")[0].removeprefix("outcome: "),
            "stalls": len(logged), "shared": len(shared), "longest_stall_ms": 1e3 * max((s[1] for s in logged), default=0.0),
            "host_gaps": len(frozen), "longest_host_gap_ms": 1e3 * max((g for _, g in frozen), default=0.0)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5, help="dry runs, one after the other (default 5)")
    parser.add_argument("--idle", type=float, default=30.0, help="seconds to watch the idle machine first (default 30)")
    parser.add_argument("--min-ms", type=float, default=12.0, help="stalls at or above this are matched (ms, default 12)")
    parser.add_argument("extra", nargs="*", help="options passed on to harness dry-run (after --)")
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="host-freezes-"))
    if args.idle > 0:
        idle = folder / "idle.txt"
        watch(args.idle, idle).wait()
        frozen = gaps(idle)
        print(f"idle machine, {args.idle:g} s: {len(frozen)} gaps over {FROZEN_S * 1e3:g} ms, longest "
              f"{1e3 * max((g for _, g in frozen), default=0.0):.1f} ms", flush=True)
    rows = []
    for k in range(1, args.runs + 1):
        row = one_run(k, folder, args.min_ms / 1e3, args.extra)
        rows.append(row)
        print(f"run {k}: {row['outcome']}; stalls >= {args.min_ms:g} ms {row['stalls']}, shared with the sleeper "
              f"{row['shared']}; the sleeper's gaps {row['host_gaps']}, longest {row['longest_host_gap_ms']:.1f} ms", flush=True)
    print(f"\n| run | outcome | loop stalls >= {args.min_ms:g} ms | of them the machine's (the sleeper stopped too) | "
          "longest stall (ms) | the sleeper's gaps > 15 ms | its longest (ms) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for k, r in enumerate(rows, 1):
        print(f"| {k} | {r['outcome']} | {r['stalls']} | {r['shared']} | {r['longest_stall_ms']:.1f} | {r['host_gaps']} | "
              f"{r['longest_host_gap_ms']:.1f} |")
    (folder / "host_freezes.json").write_text(json.dumps(rows, indent=1))
    print(f"\nraw figures: {folder / 'host_freezes.json'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
