"""Soak run: a long real-time dry run at 500 Hz with the rig's noise on (issue 6, item 4).

Runs the default profile (virtual rig in-process on the virtual bus, sensor noise,
quantization and delays, first-order actuator) on a long synthetic record, samples the
process's resident memory every 10 s from a background thread, and reports: the outcome
(the requirement: no trip), the resident-memory growth after a 30 s warm-up (the
requirement: under 5 MB), loop timing, missed periods and frames lost.

Usage: python benchmarks/soak.py [--minutes 10] [--pga 0.25] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.profile import load_profile  # noqa: E402
from harness.runs.dry_run import DryRunOptions, dry_run  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402

WARM_UP_S = 30.0


def resident_kib() -> int:
    """VmRSS of this process (KiB)."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError("no VmRSS in /proc/self/status")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--pga", type=float, default=0.25, help="record PGA (g)")
    parser.add_argument("--json", default=str(REPO / "benchmarks" / "results" / "soak.json"))
    args = parser.parse_args()
    duration = args.minutes * 60.0
    samples: list[tuple[float, int]] = []
    stop = threading.Event()
    started = time.monotonic()

    def sample() -> None:
        while not stop.wait(10.0):
            samples.append((time.monotonic() - started, resident_kib()))

    sampler = threading.Thread(target=sample, daemon=True)
    sampler.start()
    profile = load_profile(REPO / "profiles" / "nceer_4dof.yaml")
    with tempfile.TemporaryDirectory() as log_dir:
        options = DryRunOptions(study=StudyOptions(duration_s=duration, pga_g=args.pga), log_dir=log_dir,
                                show_console=False, compare=False)  # the loop alone, not the offline twins
        result = dry_run(profile, options)
        stop.set()
    after = [kib for t, kib in samples if t >= WARM_UP_S]
    growth_mib = (max(after) - after[0]) / 1024 if len(after) >= 2 else float("nan")
    timing = result.session.loop.timing
    summary = {
        "minutes": args.minutes,
        "rate_hz": profile.control.rate_hz,
        "outcome": result.session.outcome,
        "trip_reason": result.session.trip_reason,
        "rss_first_after_warm_up_mib": after[0] / 1024 if after else None,
        "rss_max_mib": max(after) / 1024 if after else None,
        "rss_growth_mib": growth_mib,
        "ticks": timing.get("ticks"),
        "missed_periods": timing.get("missed_periods"),
        "lateness_median_us": timing.get("lateness_median_s", float("nan")) * 1e6,
        "lateness_p99_us": timing.get("lateness_p99_s", float("nan")) * 1e6,
        "lateness_max_us": timing.get("lateness_max_s", float("nan")) * 1e6,
        "compute_median_us": timing.get("compute_median_s", float("nan")) * 1e6,
        "frames_received": result.session.bus["frames_received"],
        "frames_lost": result.session.bus["frames_lost"],
        "rss_samples": samples,
    }
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps({k: v for k, v in summary.items() if k != "rss_samples"}, indent=2))
    ok = summary["outcome"] == "completed" and growth_mib < 5.0
    print("soak:", "PASS" if ok else "FAIL", f"(outcome {summary['outcome']}, RSS growth {growth_mib:.2f} MiB)")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
