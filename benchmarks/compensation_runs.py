"""Force-tracking compensation measured in dry runs on the servo-hydraulic rig, lockstep and real time (issue 24, item 3).

For El Centro (0.34 g), Hachinohe (0.23 g) and Pacoima (0.40 g), time scale 2, 30 s, on the
shipped servo-hydraulic rig (``profiles/nceer_4dof.yaml``), one dry run per method and path:

- methods: the phi controller with ``control.compensation`` none, model and adaptive, and the
  actuator-aware output design phi-A (which carries its own flow term: compensation none);
- paths: ``lockstep`` (the rig advances one step per command: deterministic) and ``real time``
  (``harness dry-run`` as a user runs it: 500 Hz, the rig in its own process on the private bus).

Per run, from its run folder: the force tracking (as ``harness report`` computes it,
:mod:`harness.report.force_tracking_table`: the load cell against the controller's force over
the record: delay, RMS and peak error in % of the force asked), the drift reduction per story
and the floor-acceleration reduction against the ideal passive simulation (as ``rig_table.py
--dry-runs`` and ``actuator_design.py``), the sliding displacement, the peak force (load cell)
and the peak command in % of the weight, and the outcome. The ideal controlled simulation
(``harness simulate``, phi) gives the drift reductions the target is judged against.

Results go to a JSON file as each run ends (``--out``), so an interrupted series keeps what it
measured; ``--table FILE`` prints the Markdown table of such a file without running anything
(``--reread``: after reading every run back from its run folder).

Usage: python benchmarks/compensation_runs.py [--paths lockstep,realtime] [--records el_centro,...]
                                              [--methods none,model,adaptive,phi-A] [--out FILE]
       python benchmarks/compensation_runs.py --table FILE [--reread]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.profile import load_profile  # noqa: E402
from harness.recording.peaks import run_peaks  # noqa: E402
from harness.recording.reader import load_run  # noqa: E402
from harness.report.force_tracking_table import record_span, run_tracking  # noqa: E402
from harness.runs.dry_run import DryRunOptions, dry_run  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study  # noqa: E402
from harness.signals.columns import FORCE_RAW  # noqa: E402
from harness.signals.peaks import reduction_pct  # noqa: E402

sys.path.insert(0, str(REPO / "benchmarks"))
from rig_table import RIG_RECORDS  # noqa: E402

PROFILE = REPO / "profiles" / "nceer_4dof.yaml"

#: Methods: label -> (controller, control.compensation).
METHODS = {"none": ("phi", "none"), "model": ("phi", "model"), "adaptive": ("phi", "adaptive"),
           "phi-A": ("phi-A", "none")}
PATHS = {"lockstep": True, "realtime": False}
DRIFTS = ("drift_1_m", "drift_2_m", "drift_3_m")
FLOORS = ("floor_acceleration_1_m_s2", "floor_acceleration_2_m_s2", "floor_acceleration_3_m_s2")


def study_options(record: str, pga_g: float, records_dir: str, duration_s: float) -> StudyOptions:
    """The record at its level, time scale 2, ``duration_s`` long."""
    return StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0, duration_s=duration_s)


def ideal(record: str, pga_g: float, records_dir: str, duration_s: float) -> dict[str, Any]:
    """The ideal simulation's passive and phi peaks (flattened), the reference of every reduction."""
    study = run_study(load_profile(PROFILE), replace(study_options(record, pga_g, records_dir, duration_s),
                                                     controller="phi"))
    return {case: result.peaks.flatten() for case, result in study.cases.items()}


def one_run(record: str, pga_g: float, method: str, lockstep: bool, records_dir: str, duration_s: float,
            log_dir: str) -> dict[str, Any]:
    """One dry run of ``method``: its peaks, force tracking and outcome, read back from its run folder."""
    controller, compensation = METHODS[method]
    profile = load_profile(PROFILE, overrides=[f"control.compensation={compensation}"])
    study = replace(study_options(record, pga_g, records_dir, duration_s), controller=controller)
    result = dry_run(profile, DryRunOptions(study=study, lockstep=lockstep, show_console=False, compare=False,
                                            log_dir=log_dir))
    return read_back(result.session.run_path)


def read_back(run_folder: str | Path) -> dict[str, Any]:
    """A run folder's peaks, force tracking over the record (the report's), outcome and trip reason."""
    run = load_run(run_folder)
    peaks = run_peaks(run)
    tracked = run_tracking(run).get(FORCE_RAW)
    start, end = record_span(run)
    trip = next((event for event in run.events if event.get("kind") == "fault"), None)
    return {"peaks": peaks.flatten(), "measured_force_pct_weight": peaks.measured_force_pct_weight,
            "tracking": None if tracked is None else tracked.as_json(),
            "outcome": run.outcome, "trip_reason": run.metadata.get("trip_reason"),
            "trip_record_s": None if trip is None else float(trip["t_s"]) - start,
            "record_s": end - start, "run_folder": str(run.path)}


def reread(results: dict[str, Any]) -> dict[str, Any]:
    """Every run of a results file read back again from its run folder (after a change to what is measured)."""
    for entry in results.values():
        for path in PATHS:
            for method, run in entry.get(path, {}).items():
                entry[path][method] = read_back(run["run_folder"])
    return results


def measure(args: argparse.Namespace, log_dir: str) -> dict[str, Any]:
    """Every record, path and method asked for; written to ``args.out`` after each run."""
    results: dict[str, Any] = json.loads(Path(args.out).read_text()) if args.resume and Path(args.out).is_file() else {}
    for path in args.paths:  # every lockstep run first: the real-time runs, one at a time, after them
        for record, pga_g in RIG_RECORDS:
            if record not in args.records:
                continue
            entry = results.setdefault(record, {"pga_g": pga_g})
            if "ideal" not in entry:
                entry["ideal"] = ideal(record, pga_g, args.records_dir, args.duration)
            for method in args.methods:
                if method in entry.get(path, {}):
                    continue
                run = one_run(record, pga_g, method, PATHS[path], args.records_dir, args.duration, log_dir)
                entry.setdefault(path, {})[method] = run
                Path(args.out).write_text(json.dumps(results, indent=1) + "\n")
                print(f"{record} {path} {method}: {run['outcome']}", file=sys.stderr)
    return results


def _reductions(passive: dict[str, float], peaks: dict[str, float], keys: tuple[str, ...]) -> str:
    values = [reduction_pct(passive[key], peaks[key]) for key in keys]
    return "/".join("-" if value is None else f"{value:.0f}" for value in values)


def _tracking_cells(tracking: dict[str, Any] | None) -> list[str]:
    if tracking is None:
        return ["-", "-", "-", "-"]
    return [f"{tracking['delay_s'] * 1e3:.1f}", f"{tracking['correlation']:.2f}", f"{tracking['rms_error_percent']:.0f}",
            f"{tracking['peak_error_percent']:.0f}"]


def _force_cells(run: dict[str, Any]) -> list[str]:
    return [f"{run['measured_force_pct_weight']:.1f}", f"{run['peaks']['peak_force_pct_weight']:.1f}"]


HEADINGS = ("record", "path", "method", "tracking delay (ms)", "correlation at the delay", "RMS error % of force asked",
            "peak error % of force asked", "drift reduction % (stories 1/2/3)",
            "floor acc. reduction % (floors 1/2/3)", "sliding disp. mm", "peak force % W (load cell)",
            "peak command % W", "outcome")


def table_rows(results: dict[str, Any]) -> list[list[str]]:
    """A row per record, path and method; the ideal simulation's row first for each record."""
    rows = []
    for record, pga_g in RIG_RECORDS:
        entry = results.get(record)
        if entry is None:
            continue
        passive, controlled = entry["ideal"]["passive"], entry["ideal"]["controlled"]
        name = f"{record} {pga_g:.2f} g"
        rows.append([name, "ideal simulation", "phi", "-", "-", "-", "-", _reductions(passive, controlled, DRIFTS),
                     _reductions(passive, controlled, FLOORS), f"{controlled['sliding_displacement_m'] * 1e3:.1f}",
                     "-", f"{controlled['peak_force_pct_weight']:.1f}", "-"])
        for path in PATHS:
            for method, run in entry.get(path, {}).items():
                peaks = run["peaks"]
                outcome = run["outcome"]
                if run.get("trip_reason"):
                    at = run.get("trip_record_s")
                    outcome += f" ({run['trip_reason']}" + (f" at {at:.1f} s of record)" if at is not None else ")")
                if run.get("first_attempt"):  # a run repeated after the host tripped it (see the README)
                    outcome += f", 2nd attempt; 1st: {run['first_attempt']}"
                rows.append([name, path, method, *_tracking_cells(run["tracking"]),
                             _reductions(passive, peaks, DRIFTS), _reductions(passive, peaks, FLOORS),
                             f"{peaks['sliding_displacement_m'] * 1e3:.1f}", *_force_cells(run), outcome])
    return rows


def tracking_ratios(results: dict[str, Any]) -> list[str]:
    """Per record and path: each method's RMS tracking error as a fraction of none's (target: at most 1/3)."""
    lines = []
    for record, _ in RIG_RECORDS:
        for path in PATHS:
            runs = results.get(record, {}).get(path, {})
            base = (runs.get("none") or {}).get("tracking")
            if not base:
                continue
            parts = []
            for method, run in runs.items():
                if method != "none" and run.get("tracking"):
                    ratio = run["tracking"]["rms_error_N"] / base["rms_error_N"]
                    parts.append(f"{method} {ratio:.2f}" if math.isfinite(ratio) else f"{method} -")
            lines.append(f"{record} {path}: RMS error / none's: " + ", ".join(parts))
    return lines


def print_table(results: dict[str, Any]) -> None:
    """The Markdown table and the tracking ratios."""
    print("| " + " | ".join(HEADINGS) + " |")
    print("|" + "---|" * len(HEADINGS))
    for row in table_rows(results):
        print("| " + " | ".join(row) + " |")
    print()
    for line in tracking_ratios(results):
        print(f"- {line}")


def _names(text: str, allowed: Any) -> list[str]:
    names = [name for name in text.split(",") if name]
    unknown = [name for name in names if name not in allowed]
    if unknown:
        raise SystemExit(f"unknown {unknown}; expected some of {sorted(allowed)}")
    return names


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"),
                        help="folder with el_centro, hachinohe and pacoima (default ../shared/data/ground_motions)")
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of each record (default 30)")
    parser.add_argument("--paths", default="lockstep,realtime", help="lockstep, realtime or both (default both)")
    parser.add_argument("--records", default=",".join(record for record, _ in RIG_RECORDS))
    parser.add_argument("--methods", default=",".join(METHODS), help=f"some of {', '.join(METHODS)} (default all)")
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "compensation_runs.json"),
                        help="results file, written after each run")
    parser.add_argument("--resume", action="store_true", help="keep the runs already in --out and run the rest")
    parser.add_argument("--log-dir", default=None, help="where the run folders go (default: a temporary folder)")
    parser.add_argument("--table", default=None, metavar="FILE", help="print the table of a results file and stop")
    parser.add_argument("--reread", action="store_true",
                        help="with --table: read every run back from its run folder first, and rewrite the file")
    args = parser.parse_args()
    if args.table and args.reread:
        results = reread(json.loads(Path(args.table).read_text()))
        Path(args.table).write_text(json.dumps(results, indent=1) + "\n")
        print_table(results)
        return 0
    if args.table:
        print_table(json.loads(Path(args.table).read_text()))
        return 0
    args.paths = _names(args.paths, PATHS)
    args.records = _names(args.records, dict(RIG_RECORDS))
    args.methods = _names(args.methods, METHODS)
    with tempfile.TemporaryDirectory() as scratch:
        results = measure(args, args.log_dir or scratch)
    print_table(results)
    return 0


if __name__ == "__main__":
    sys.exit(main())
