"""Simulator speed and accuracy against the tight-tolerance solve_ivp reference (issue 2, item 7).

For each case it runs, side by side in one process: the compiled kernel (median of
--repeat runs) and the solve_ivp reference (LSODA, rtol 1e-9, once), both from rest
with the same controller, sampling and friction estimate, and reports wall times,
the real-time factor (simulated seconds per wall second), the speed ratio, and the
largest relative difference of any peak.

With --startup it times whole commands as a user types them instead (issue 12, item 4):
the warm `harness simulate` of the eight-story building (El Centro 0.3 g, 30 s, OF-I,
2 x 30 s simulated), `harness --help`, and the floors under them (a bare interpreter,
``import numpy``, ``import numba``, importing the profile loader), each the median of
--repeat fresh processes. Targets: the simulate command 1.0 s or less, --help 0.3 s or less.

Usage: python benchmarks/bench_simulate.py [--records-dir DIR] [--repeat N] [--json PATH] [--startup]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.control.factory import make_controller, make_friction_estimator  # noqa: E402
from harness.model.plant import Plant, TableMotion  # noqa: E402
from harness.model.reference import ReferencePlant  # noqa: E402
from harness.motions import load_motion  # noqa: E402
from harness.profile import load_profile  # noqa: E402
from harness.simulation.case import SamplingSettings, run_case  # noqa: E402

CASES = [
    # (label, profile, record, pga, time scale, controller, rate Hz, target real-time factor)
    ("8-story, FSF-I, 250 Hz", "eight_story.yaml", "el_centro", 0.30, 1.0, "FSF-I", 250.0, 100.0),
    ("8-story, OF-I, 250 Hz", "eight_story.yaml", "el_centro", 0.30, 1.0, "OF-I", 250.0, 100.0),
    ("4-DOF rig, phi, 1 kHz", "nceer_4dof.yaml", "el_centro", 0.34, 2.0, "phi", 1000.0, 50.0),
]
DURATION_S = 30.0


def run(plant_class, profile, table, controller_name, rate_hz):
    plant = plant_class(profile.structure, profile.bearing, table, rtol=profile.simulation.rtol)
    controller = make_controller(profile, controller_name)
    estimator = make_friction_estimator(profile)
    settings = SamplingSettings(rate_hz, 0.0, "estimator")
    started = time.perf_counter()
    result = run_case("controlled", plant, DURATION_S, settings, controller, estimator)
    return time.perf_counter() - started, result


def wall_time_s(argv: list[str]) -> float:
    """Wall time (s) of one fresh process running ``argv`` to completion; raises if it fails."""
    started = time.perf_counter()
    subprocess.run(argv, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=REPO)
    return time.perf_counter() - started


def startup(records_dir: str, repeat: int, json_path: str) -> int:
    """Median wall times (s) of whole commands and of the imports under them, in one run."""
    python, harness = sys.executable, str(Path(sys.executable).parent / "harness")
    simulate = [harness, "simulate", "profiles/eight_story.yaml", "--records-dir", records_dir, "--record", "el_centro",
                "--pga", "0.3", "--duration", "30", "--controller", "OF-I", "--quiet"]
    commands = [
        ("python -c pass", [python, "-c", "pass"], None),
        ("import numpy", [python, "-c", "import numpy"], None),
        ("import numba", [python, "-c", "import numba"], None),
        ("import harness.profile", [python, "-c", "import harness.profile"], None),
        ("harness --help", [harness, "--help"], 0.3),
        ("harness simulate eight_story OF-I (2 x 30 s)", simulate, 1.0),
    ]
    wall_time_s(simulate)  # warm the kernel cache and the page cache
    rows = []
    for label, argv, target in commands:
        times = [wall_time_s(argv) for _ in range(repeat)]
        rows.append({"command": label, "wall_s_median": statistics.median(times), "wall_s_min": min(times),
                     "target_s": target})
    Path(json_path).parent.mkdir(parents=True, exist_ok=True)
    Path(json_path).write_text(json.dumps({"machine": platform.platform(), "python": sys.version.split()[0],
                                           "repeat": repeat, "rows": rows}, indent=2) + "\n")
    print("| command | median wall (s) | min (s) | target (s) |")
    print("|---|---|---|---|")
    for r in rows:
        target = "" if r["target_s"] is None else f"{r['target_s']:.1f}"
        print(f"| {r['command']} | {r['wall_s_median']:.2f} | {r['wall_s_min']:.2f} | {target} |")
    return 0


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"))
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--json", default=None, help="raw results (default benchmarks/results/simulate.json, "
                        "or startup.json with --startup)")
    parser.add_argument("--startup", action="store_true", help="time whole commands and imports instead")
    args = parser.parse_args()
    results = REPO / "benchmarks" / "results"
    if args.startup:
        return startup(args.records_dir, args.repeat, args.json or str(results / "startup.json"))
    args.json = args.json or str(results / "simulate.json")
    rows = []
    for label, profile_file, record, pga, time_scale, controller, rate, target in CASES:
        profile = load_profile(REPO / "profiles" / profile_file)
        try:
            motion = load_motion(profile.record, base_dir=profile.base_dir, records_dir_flag=args.records_dir,
                                 name=record, pga_g=pga, time_scale=time_scale, duration_s=DURATION_S)
        except Exception as err:  # noqa: BLE001 - a benchmark falls back to the synthetic record
            print(f"{record} unavailable ({err}); using the synthetic record", file=sys.stderr)
            motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", pga_g=pga,
                                 time_scale=time_scale, duration_s=DURATION_S)
        table = TableMotion.from_motion(motion)
        run(Plant, profile, table, controller, rate)  # warm-up: load the compiled kernel
        ours = [run(Plant, profile, table, controller, rate) for _ in range(args.repeat)]
        ours_wall = statistics.median(w for w, _ in ours)
        ref_wall, reference = run(ReferencePlant, profile, table, controller, rate)
        mine, theirs = ours[0][1].peaks.flatten(), reference.peaks.flatten()
        worst_key = max(theirs, key=lambda k: abs(mine[k] - theirs[k]) / abs(theirs[k]) if theirs[k] else 0.0)
        worst = abs(mine[worst_key] - theirs[worst_key]) / abs(theirs[worst_key]) * 100
        row = {
            "case": label, "record": f"{motion.name} {motion.pga_g:.2f} g x{time_scale:g}", "duration_s": DURATION_S,
            "ours_wall_s_median": ours_wall, "ours_realtime_factor": DURATION_S / ours_wall,
            "target_realtime_factor": target, "reference_wall_s": ref_wall,
            "speedup_vs_reference": ref_wall / ours_wall, "worst_peak_error_pct": worst, "worst_peak": worst_key,
        }
        rows.append(row)
        print(f"{label:26s} ours {ours_wall:6.3f} s ({row['ours_realtime_factor']:6.0f}x real time, target {target:g}x) | "
              f"reference {ref_wall:6.2f} s | ratio {row['speedup_vs_reference']:5.1f} | worst peak {worst:.4f} % ({worst_key})")
    Path(args.json).parent.mkdir(parents=True, exist_ok=True)
    Path(args.json).write_text(json.dumps({"machine": platform.platform(), "python": sys.version.split()[0],
                                           "repeat": args.repeat, "rows": rows}, indent=2) + "\n")
    print("\n| case | record | ours (median) | real-time factor (target) | solve_ivp rtol 1e-9 | ratio | worst peak error |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['case']} | {r['record']} | {r['ours_wall_s_median']:.3f} s | {r['ours_realtime_factor']:.0f}x "
              f"({r['target_realtime_factor']:.0f}x) | {r['reference_wall_s']:.2f} s | {r['speedup_vs_reference']:.0f}x | "
              f"{r['worst_peak_error_pct']:.4f} % ({r['worst_peak']}) |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
