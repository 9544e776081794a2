"""The actuator-aware designs against the phi controller on the servo-hydraulic rig (issue 24, item 2).

For El Centro (0.34 g), Hachinohe (0.23 g) and Pacoima (0.40 g), time scale 2, 30 s, on the
shipped servo-hydraulic rig (``profiles/nceer_4dof.yaml``), each column is one controller
through one path:

- ``phi twin``, ``phi dry run``: the phi controller (Eq. 22-23) commanding the cylinder's force
  loop directly (no compensation), on the rig twin (``harness simulate --rig-effects``) and in
  a lockstep dry run;
- ``phi-A twin``, ``phi-A dry run``: the actuator-aware output design (base mat, table and the
  load cell; harness/control/actuator_aware.py, Eq. A9-A13);
- ``FSF-A twin*``: the actuator-aware full-state design (Eq. A2-A8), reading the twin's TRUE
  plant state: an offline design study no rig can run.

Rows: drift reduction per story, floor and base-mat acceleration reduction (against the same
ideal passive simulation, as ``rig_table.py --dry-runs``), the sliding displacement, the peak
force the actuator applied (load cell) and the peak command, in % of the weight, the share of
samples whose raw command exceeded the supervisor's force limit, and the outcome. Peaks are the
measured signals', as a dry run records them.

The dry-run columns need the loop to hand the controller the load cell's force
(``Measurements.actuator_force_N`` filled in the loop's tick); without it they are left out
(``--twin-only`` leaves them out anyway).

With ``--model-error`` it prints instead, for El Centro, the twin with the rig's actuator off
the design's model by 30 % (bulk modulus 0.7 and 1.3 GPa: ``k_h`` and with it ``k_h / w_f`` off
by 30 %, the force loop still tuned to 20 Hz on the rig; servo-valve bandwidth 52.5 and 97.5 Hz):
the controllers are designed on the profile's nominal actuator, the rig runs the perturbed one,
and the supervisor's tracking check expects the rig's own velocity feedback.

Usage: python benchmarks/actuator_design.py [--records-dir DIR] [--duration S] [--twin-only] [--log-dir DIR]
       python benchmarks/actuator_design.py --model-error [--records-dir DIR] [--duration S]
"""

from __future__ import annotations

import argparse
import inspect
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

from harness.profile import Profile, load_profile  # noqa: E402
from harness.runs.dry_run import DryRunOptions, dry_run  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study
from harness.signals.peaks import Peaks, reduction_pct  # noqa: E402

sys.path.insert(0, str(REPO / "benchmarks"))
from rig_table import PREDICTED as REDUCTIONS  # noqa: E402  (the same rows as the source's table)
from rig_table import RIG_RECORDS  # noqa: E402

#: Columns: (label, design, path); path "twin" or "dry run".
COLUMNS = (("phi twin", "phi", "twin"), ("phi dry run", "phi", "dry run"), ("phi-A twin", "phi-A", "twin"),
           ("phi-A dry run", "phi-A", "dry run"), ("FSF-A twin*", "FSF-A", "twin"))


def loop_reads_the_load_cell() -> bool:
    """Whether the loop's tick fills ``Measurements.actuator_force_N`` (the dry-run columns need it)."""
    from harness.loop import tick

    return "actuator_force_N" in inspect.getsource(tick)


def _summary(peaks: Peaks, columns: dict | None, force_limit_N: float, outcome: str) -> dict:
    flat = peaks.flatten()
    clamped = None
    if columns is not None and "force_raw_N" in columns:
        clamped = float(np.mean(np.abs(columns["force_raw_N"]) > force_limit_N))
    return {**flat, "measured_force_pct_weight": peaks.measured_force_pct_weight, "clamped": clamped,
            "outcome": outcome}


def run_column(profile: Profile, design: str, path: str, options: StudyOptions, log_dir: str) -> dict:
    """Peaks (and the command's clamped share) of one design through one path."""
    limit = profile.safety.force.max_force_N
    if path == "twin":
        controlled = run_study(profile, replace(options, controller=design, rig_effects=True))
        case = controlled.cases["controlled"]
        return _summary(case.peaks, case.columns, limit, case.extra["outcome"])
    study = replace(options, controller=design)
    run = dry_run(profile, DryRunOptions(study=study, lockstep=True, show_console=False, compare=False, log_dir=log_dir))
    return _summary(run.peaks, None, limit, str(run.session.outcome).split(".")[-1].lower())


def measure(records_dir: str, duration_s: float, columns: tuple, log_dir: str) -> dict:
    """Per record: the ideal passive peaks and each column's summary."""
    profile = load_profile(REPO / "profiles" / "nceer_4dof.yaml")
    results: dict = {}
    for record, pga_g in RIG_RECORDS:
        options = StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0, duration_s=duration_s)
        passive = run_study(profile, replace(options, controller="none"))
        results[record] = {"passive": passive.cases["passive"].peaks.flatten()}
        for label, design, path in columns:
            results[record][label] = run_column(profile, design, path, options, log_dir)
            print(f"{record} {label}: {results[record][label]['outcome']}", file=sys.stderr)
    return results


#: Actuator model errors of the robustness study: (label, overrides of the rig's actuator).
MODEL_ERRORS = (
    ("nominal", ()),
    ("bulk modulus -30 %", ("rig.actuator.hydraulics.cylinder.bulk_modulus_Pa=0.7e9",)),
    ("bulk modulus +30 %", ("rig.actuator.hydraulics.cylinder.bulk_modulus_Pa=1.3e9",)),
    ("valve bandwidth -30 %", ("rig.actuator.hydraulics.cylinder.valve_bandwidth_hz=52.5",)),
    ("valve bandwidth +30 %", ("rig.actuator.hydraulics.cylinder.valve_bandwidth_hz=97.5",)),
)


def model_error_study(records_dir: str, duration_s: float) -> list[list[str]]:
    """El Centro on the twin with the rig's actuator off the design's model: one row per error."""
    from harness.control.factory import build_controller_for_rig
    from harness.simulation.twin import run_rig_twin

    nominal = load_profile(REPO / "profiles" / "nceer_4dof.yaml")
    options = StudyOptions(record="el_centro", records_dir=records_dir, pga_g=0.34, time_scale=2.0, duration_s=duration_s)
    passive = run_study(nominal, replace(options, controller="none")).cases["passive"].peaks.flatten()
    table = []
    for label, overrides in MODEL_ERRORS:
        rig = load_profile(REPO / "profiles" / "nceer_4dof.yaml", overrides=list(overrides))
        feedback = rig.rig.actuator.hydraulics.loop_damping_Ns_per_m()
        rig = load_profile(REPO / "profiles" / "nceer_4dof.yaml",
                           overrides=[*overrides, f"safety.force.velocity_feedback_Ns_per_m={feedback:.0f}"])
        motion = run_study(rig, replace(options, controller="none")).motion
        row = [label]
        for design in ("phi", "phi-A"):
            case = run_rig_twin(rig, motion, nominal.control.rate_hz, build_controller_for_rig(nominal, design))
            peaks = case.peaks.flatten()
            drifts = "/".join(f"{reduction_pct(passive[f'drift_{j}_m'], peaks[f'drift_{j}_m']):.0f}" for j in (1, 2, 3))
            row += [drifts, f"{case.peaks.measured_force_pct_weight:.1f}", case.extra["outcome"]]
        table.append(row)
        print(f"model error {label}: done", file=sys.stderr)
    return table


def rows(results: dict, columns: tuple) -> list[list[str]]:
    """The table: one row per quantity, per record one cell per column."""
    table = []
    for key, label in REDUCTIONS:
        row = [label]
        for record, _ in RIG_RECORDS:
            passive = results[record]["passive"][key]
            for name, _, _ in columns:
                reduction = reduction_pct(passive, results[record][name][key])
                row.append("-" if reduction is None else f"{reduction:.0f}")
        table.append(row)
    extra = {
        "sliding displacement mm (passive)": lambda r, c: f"{c['sliding_displacement_m'] * 1e3:.1f} "
                                                          f"({r['passive']['sliding_displacement_m'] * 1e3:.1f})",
        "peak actuator force % W (load cell)": lambda r, c: f"{c['measured_force_pct_weight']:.1f}",
        "peak command % W": lambda r, c: f"{c['peak_force_pct_weight']:.1f}",
        "command beyond the force limit, % of samples": lambda r, c: "-" if c["clamped"] is None else f"{100 * c['clamped']:.1f}",
        "outcome": lambda r, c: c["outcome"],
    }
    for label, cell in extra.items():
        row = [label]
        for record, _ in RIG_RECORDS:
            for name, _, _ in columns:
                row.append(cell(results[record], results[record][name]))
        table.append(row)
    return table


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"),
                        help="folder with el_centro, hachinohe and pacoima (default ../shared/data/ground_motions)")
    parser.add_argument("--duration", type=float, default=30.0, help="seconds of each record (default 30)")
    parser.add_argument("--twin-only", action="store_true", help="leave out the lockstep dry runs")
    parser.add_argument("--log-dir", default=None, help="where the dry runs' folders go (default: a temporary folder)")
    parser.add_argument("--model-error", action="store_true",
                        help="El Centro on the twin with the rig's actuator 30 %% off the design's model")
    args = parser.parse_args()
    if args.model_error:
        names = ["rig's actuator", "phi: drift reduction % (stories 1/2/3)", "phi: peak force % W", "phi: outcome",
                 "phi-A: drift reduction % (stories 1/2/3)", "phi-A: peak force % W", "phi-A: outcome"]
        print("| " + " | ".join(names) + " |")
        print("|" + "---|" * len(names))
        for row in model_error_study(args.records_dir, args.duration):
            print("| " + " | ".join(row) + " |")
        return 0
    columns = COLUMNS
    if args.twin_only or not loop_reads_the_load_cell():
        if not args.twin_only:
            print("the loop does not hand the controller the load cell's force: dry-run columns left out", file=sys.stderr)
        columns = tuple(column for column in COLUMNS if column[2] == "twin")
    with tempfile.TemporaryDirectory() as scratch:
        results = measure(args.records_dir, args.duration, columns, args.log_dir or scratch)
    names = ["quantity", *(f"{record} {pga_g:.2f} g: {name}" for record, pga_g in RIG_RECORDS for name, _, _ in columns)]
    print("| " + " | ".join(names) + " |")
    print("|" + "---|" * len(names))
    for row in rows(results, columns):
        print("| " + " | ".join(row) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
