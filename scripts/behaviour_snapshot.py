#!/usr/bin/env python3
"""Save what the commands compute, to check that a restructuring changed no behaviour.

Runs, through the command line only (so it works across any change of the package's
insides): ``harness simulate --json`` on both shipped profiles (every controller of the
eight-story study, the rig's phi controller ideal and with ``--rig-effects``), and a
lockstep ``harness dry-run`` (deterministic: the rig waits for each command). From the
dry run's ``signals.csv`` it keeps, per column, the peak |value|, leaving out the columns
that measure host timing. Writes one JSON document.

Simulate results must be identical (to 1e-12). The dry run's peaks are compared to 1 %:
in lockstep the table still starts on the first tick after a wall-clock settle time, so
one run in a few starts one tick earlier or later (seen: 4903 against 4904 rows, table
displacement peak 67.910 against 67.915 mm).

Usage: .venv/bin/python scripts/behaviour_snapshot.py OUT.json [--compare OLD.json]
With --compare it exits 1 and names every value that differs.
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
HARNESS = str(Path(sys.executable).parent / "harness")
RECORDS = REPO.parent / "shared" / "data" / "ground_motions"
#: Columns that measure the host, not the physics or the control.
TIMING_COLUMNS = {"lateness_s", "compute_s", "overrun"}
SIMULATE_CASES = {
    "eight_story_FSF-I": ["profiles/eight_story.yaml", "--controller", "FSF-I"],
    "eight_story_FSF-II": ["profiles/eight_story.yaml", "--controller", "FSF-II"],
    "eight_story_OF-I": ["profiles/eight_story.yaml", "--controller", "OF-I"],
    "eight_story_OF-II_a_mu": ["profiles/eight_story.yaml", "--controller", "OF-II", "--variant", "a_mu_0.5"],
    "eight_story_FSF-I_scale_0.7": ["profiles/eight_story.yaml", "--controller", "FSF-I", "--design-stiffness-scale", "0.7"],
    "rig_phi": ["profiles/nceer_4dof.yaml"],
    "rig_phi_rig_effects": ["profiles/nceer_4dof.yaml", "--rig-effects", "--delay", "0.002"],
}


def simulate(args: list[str], folder: Path) -> dict:
    """The JSON document of one ``harness simulate`` run."""
    out = folder / "simulate.json"
    subprocess.run([HARNESS, "simulate", *args, "--duration", "10", "--json", str(out), "--quiet"],
                   check=True, cwd=REPO, stdout=subprocess.DEVNULL)
    return json.loads(out.read_text())


def dry_run_signals(folder: Path) -> dict:
    """Per-column peak |value| of a lockstep dry run's signals.csv."""
    subprocess.run([HARNESS, "dry-run", "--lockstep", "--duration", "8", "--quiet", "--log-dir", str(folder)],
                   check=True, cwd=REPO, stdout=subprocess.DEVNULL)
    (run,) = [p for p in folder.iterdir() if p.is_dir()]
    with open(run / "signals.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    summary = {}
    for name in rows[0]:
        if name in TIMING_COLUMNS:
            continue
        values = [abs(float(row[name])) for row in rows if row[name] not in ("", "nan")]
        summary[name] = max(values, default=0.0)
    return summary


def differences(old, new, path: str = "", rel_tol: float = 1e-12) -> list[str]:
    """Paths of every value that differs between two JSON documents (floats to ``rel_tol``)."""
    if isinstance(old, dict) and isinstance(new, dict):
        found = [f"{path}/{k}: only in one" for k in set(old) ^ set(new)]
        for key in sorted(set(old) & set(new)):
            found += differences(old[key], new[key], f"{path}/{key}", 1e-2 if key == "dry_run" else rel_tol)
        return found
    if isinstance(old, list) and isinstance(new, list) and len(old) == len(new):
        return [d for i, (a, b) in enumerate(zip(old, new, strict=True)) for d in differences(a, b, f"{path}[{i}]", rel_tol)]
    if isinstance(old, float) and isinstance(new, float):
        return [] if math.isclose(old, new, rel_tol=rel_tol, abs_tol=1e-15) else [f"{path}: {old!r} -> {new!r}"]
    return [] if old == new else [f"{path}: {old!r} -> {new!r}"]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("out", type=Path, help="where to write the snapshot")
    parser.add_argument("--compare", type=Path, help="an earlier snapshot to compare with")
    args = parser.parse_args()
    snapshot = {"simulate": {}, "dry_run": None}
    with tempfile.TemporaryDirectory() as tmp:
        for name, case in SIMULATE_CASES.items():
            folder = Path(tmp) / name
            folder.mkdir()
            snapshot["simulate"][name] = simulate(case, folder)
            print(f"simulate {name}: done", file=sys.stderr)
        folder = Path(tmp) / "dry_run"
        folder.mkdir()
        snapshot["dry_run"] = dry_run_signals(folder)
        print("lockstep dry run: done", file=sys.stderr)
    args.out.write_text(json.dumps(snapshot, indent=1, sort_keys=True) + "\n")
    if args.compare:
        found = differences(json.loads(args.compare.read_text()), snapshot)
        for line in found:
            print(line)
        print(f"{len(found)} values differ from {args.compare}")
        return 1 if found else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
