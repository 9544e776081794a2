"""Identification through the harness, end to end: dry runs on a virtual rig whose truth is not the profile's.

The virtual rig is given its own structure and bearing (``rig.truth``): story stiffness +15 %,
-12 % and +18 %, first-mode damping 1.5 % (the profile: 1 %), and a bearing with mu_max +25 %,
mu_delta -20 %, a_mu -22 %. The harness does not know them: each run folder's profile holds the
design. Then, as a lab would, on the shipped rig (servo-hydraulic actuator and table, the
sensors' noise and quantization on, lockstep):

1. ``harness dry-run --lockstep --record white_noise:0.5-20`` (0.1 g) and
   ``harness identify structure`` on its run folder;
2. ``harness dry-run --lockstep`` (the profile's synthetic record at 0.34 g) and
   ``harness identify bearing`` on its run folder.

3. ``harness identify actuator --both --band-hz 1,80 --amplitude-N 700`` on an actuator whose
   bulk modulus is 30 % above and valve 30 % slower than the profile believes
   (``rig.truth.actuator``).

It prints, per value, the truth, the profile's value, the identified one and its error, against
the issue's targets (modal frequencies within 2 %, damping within 30 %, story stiffness within
10 %, friction within 10 %, the actuator's two responses within 5 % and 5 deg over the band).

Then the prediction (``--predict``): the three overlays merged into one, and for El Centro
(0.34 g, time scale 2, 30 s) a lockstep dry run of the hidden rig against ``harness simulate
--rig-effects``, once on the original profile and once on the identified one (the dry run and
the simulation each with the same profile, so the same controller design): the largest
difference of their peaks (drifts, floor and base-mat accelerations, sliding displacement,
peak force), target 5 % with the identified profile.

Usage: python benchmarks/identify_dry_run.py [--duration-noise S] [--duration-quake S] [--seed N] [--out DIR]
       [--predict] [--records-dir DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import dataclasses  # noqa: E402
import json  # noqa: E402

import numpy as np  # noqa: E402
import yaml  # noqa: E402

from harness.cli import main  # noqa: E402
from harness.identification.actuator_fit import (  # noqa: E402
    ActuatorParameters,
    blocked_response,
    velocity_feedback_response,
)
from harness.identification.bearing import identify_bearing  # noqa: E402
from harness.identification.structure import identify_structure  # noqa: E402
from harness.model.building import fixed_base_modes  # noqa: E402
from harness.profile import (
    load_profile,  # noqa: E402
    merge,  # noqa: E402
)
from harness.rig.truth import true_hydraulics  # noqa: E402
from harness.runs.dry_run import DryRunOptions  # noqa: E402
from harness.runs.dry_run import dry_run as dry_run_study  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study  # noqa: E402

TRUE_STIFFNESS = (0.8395e6, 1.848e6, 1.7464e6)
TRUE_DAMPING = 0.015
TRUE_BEARING = {"mu_max": 0.075, "mu_delta": 0.024, "a_mu_s_per_m": 70.0}
TRUE_ACTUATOR = {"bulk_modulus_Pa": 1.3e9, "valve_bandwidth_hz": 52.5}  # the profile: 1.0e9, 75
TARGETS = {"frequency": 0.02, "damping": 0.3, "stiffness": 0.1, "friction": 0.1, "actuator": 0.05, "prediction": 0.05}


def truth_settings() -> list[str]:
    """The ``--set`` options that give the virtual rig its own truth."""
    stiffness = ",".join(f"{k:g}" for k in TRUE_STIFFNESS)
    settings = [f"rig.truth.structure.story_stiffness_N_per_m=[{stiffness}]",
                f"rig.truth.structure.first_mode_damping_ratio={TRUE_DAMPING:g}"]
    settings += [f"rig.truth.bearing.{key}={value:g}" for key, value in TRUE_BEARING.items()]
    settings += [f"rig.truth.actuator.{key}={value:g}" for key, value in TRUE_ACTUATOR.items()]
    return [word for setting in settings for word in ("--set", setting)]


def dry_run(log_dir: Path, *options: str) -> Path:
    """One lockstep dry run on the rig with its own truth; its run folder."""
    log_dir.mkdir(parents=True, exist_ok=True)
    status = main(["dry-run", "--lockstep", "--quiet", "--log-dir", str(log_dir), *truth_settings(), *options])
    if status != 0:
        raise SystemExit(f"dry run {' '.join(options)} ended with exit status {status}")
    (folder,) = [p for p in log_dir.iterdir() if (p / "metadata.json").is_file()]
    return folder


def rows(out: Path, noise_s: float, quake_s: float, seed: int) -> list[tuple[str, float, float, float, float]]:
    """(value, truth, profile, identified, target) for every identified value."""
    profile = load_profile()
    noise_run = dry_run(out / "noise", "--record", "white_noise:0.5-20", "--duration", f"{noise_s:g}", "--set",
                        f"record.seed={seed}")
    quake_run = dry_run(out / "quake", "--duration", f"{quake_s:g}", "--set", f"record.seed={seed}")
    structure = identify_structure([noise_run], out / "structure")
    bearing = identify_bearing([quake_run], out / "bearing")

    truth = dataclasses.replace(profile.structure, story_stiffness_N_per_m=TRUE_STIFFNESS, first_mode_damping_ratio=TRUE_DAMPING)
    true_omega, true_zeta = fixed_base_modes(truth)
    design_omega, design_zeta = fixed_base_modes(profile.structure)
    table = []
    for r in range(3):
        table.append((f"mode {r + 1} frequency (Hz)", true_omega[r] / (2 * np.pi), design_omega[r] / (2 * np.pi),
                      float(structure.modal.frequency_hz[r]), TARGETS["frequency"]))
    for r in range(3):
        table.append((f"mode {r + 1} damping ratio", true_zeta[r], design_zeta[r], float(structure.modal.damping_ratio[r]),
                      TARGETS["damping"]))
    for j in range(3):
        table.append((f"story {j + 1} stiffness (N/m)", TRUE_STIFFNESS[j], profile.structure.story_stiffness_N_per_m[j],
                      float(structure.stories.stiffness_N_per_m[j]), TARGETS["stiffness"]))
    table.append(("first-mode damping ratio (story model)", TRUE_DAMPING, float(profile.structure.first_mode_damping_ratio or 0),
                  float(structure.stories.first_mode_damping_ratio or np.nan), TARGETS["damping"]))
    for key, value in TRUE_BEARING.items():
        table.append((f"bearing {key}", value, getattr(profile.bearing, key), bearing.fit.estimates[key].value,
                      TARGETS["friction"]))
    table.append(("bearing yield_displacement_m", profile.bearing.yield_displacement_m, profile.bearing.yield_displacement_m,
                  bearing.fit.estimates["yield_displacement_m"].value, TARGETS["friction"]))
    return table + actuator_rows(out, profile)


def identify_actuator_on_the_hidden_rig(out: Path) -> dict:
    """``harness identify actuator --both`` past the force loop, on the CAN path; the fitted values (identification.json)."""
    status = main(["identify", "actuator", "--out", str(out / "actuator"), "--both", "--band-hz", "1,80",
                   "--amplitude-N", "700", "--duration", "40", "--quiet", *truth_settings()])
    if status != 0:
        raise SystemExit(f"identify actuator ended with exit status {status}")
    return json.loads((out / "actuator" / "identification.json").read_text())


def actuator_rows(out: Path, profile) -> list[tuple[str, float, float, float, float]]:
    """The actuator's identified values, and its two responses against the true ones (worst bin over the band)."""
    record = identify_actuator_on_the_hidden_rig(out)
    believed = profile.rig.actuator.hydraulics
    truth = true_hydraulics(believed, load_profile(overrides=truth_settings()[1::2]).rig.truth.actuator)
    loop_s = 0.5 / profile.control.rate_hz
    true_p = ActuatorParameters.from_config(truth, profile.rig.actuator.delay_s + loop_s)
    fitted = {k: v["value"] for k, v in record["parameters"].items()}
    found = ActuatorParameters(**{**true_p.__dict__, **fitted})
    rows = [
        ("actuator bulk modulus (Pa)", truth.cylinder.bulk_modulus_Pa, believed.cylinder.bulk_modulus_Pa,
         record["bulk_modulus_Pa"], TARGETS["actuator"]),
        ("actuator valve bandwidth (Hz)", truth.cylinder.valve_bandwidth_hz, believed.cylinder.valve_bandwidth_hz,
         found.valve_bandwidth_hz, TARGETS["actuator"]),
        ("actuator force loop bandwidth (Hz)", truth.force_loop_bandwidth_hz, believed.force_loop_bandwidth_hz,
         found.force_loop_bandwidth_hz, TARGETS["actuator"]),
    ]
    band = np.arange(1.0, 80.0, 0.25)
    believed_p = ActuatorParameters.from_config(believed, profile.rig.actuator.delay_s + loop_s)
    for name, response in (("blocked response", blocked_response), ("velocity feedback response", velocity_feedback_response)):
        truth_h, found_h, believed_h = (response(p, band) for p in (true_p, found, believed_p))
        worst = float(np.max(np.abs(np.abs(found_h / truth_h) - 1)))
        rows.append((f"actuator {name}, worst magnitude over 1-80 Hz (ratio to truth)", 1.0,
                     1.0 + float(np.max(np.abs(np.abs(believed_h / truth_h) - 1))), 1.0 + worst, TARGETS["actuator"]))
        phase = float(np.max(np.abs(np.degrees(np.angle(found_h / truth_h)))))
        print(f"{name}: worst phase error {phase:.2f} deg (profile: "
              f"{float(np.max(np.abs(np.degrees(np.angle(believed_h / truth_h))))):.1f} deg)", file=sys.stderr)
    return rows


def merged_overlay(out: Path) -> Path:
    """The three identifications' overlays merged into one file (mappings merge, values replace)."""
    merged: dict = {}
    for kind in ("structure", "bearing", "actuator"):
        merged = merge(merged, yaml.safe_load((out / kind / "identified.yaml").read_text()) or {})
    path = out / "identified_all.yaml"
    path.write_text(yaml.safe_dump(merged, sort_keys=False))
    return path


def largest_peak_difference(overlay: Path | None, records_dir: str, log_dir: Path) -> tuple[float, str]:
    """Dry run of the hidden rig against ``simulate --rig-effects``, both on the same profile: largest peak difference."""
    options = StudyOptions(record="el_centro", records_dir=records_dir, pga_g=0.34, time_scale=2.0, duration_s=30.0)
    believed = load_profile(overlay=overlay)
    predicted = run_study(believed, dataclasses.replace(options, rig_effects=True)).cases["controlled"].peaks.flatten()
    hidden = load_profile(overlay=overlay, overrides=truth_settings()[1::2])
    log_dir.mkdir(parents=True, exist_ok=True)
    run = dry_run_study(hidden, DryRunOptions(study=options, lockstep=True, show_console=False, compare=False,
                                              log_dir=str(log_dir)))
    measured = run.peaks.flatten()
    worst, where = 0.0, ""
    for key, value in measured.items():
        if not isinstance(value, float) or key not in predicted or not value:
            continue
        difference = abs(predicted[key] / value - 1.0)
        if difference > worst:
            worst, where = difference, key
    return worst, where


def markdown(table: list[tuple[str, float, float, float, float]]) -> str:
    lines = ["| value | truth | profile | identified | error | target |", "|---|---:|---:|---:|---:|---:|"]
    for name, truth, design, found, target in table:
        error = found / truth - 1.0
        mark = "" if abs(error) <= target else " (missed)"
        lines.append(f"| {name} | {truth:.4g} | {design:.4g} | {found:.4g} | {100 * error:+.1f} %{mark} | {100 * target:g} % |")
    return "\n".join(lines)


def run(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration-noise", type=float, default=60.0, help="white-noise dry run length (s)")
    parser.add_argument("--duration-quake", type=float, default=30.0, help="earthquake dry run length (s)")
    parser.add_argument("--seed", type=int, default=0, help="record.seed of both dry runs")
    parser.add_argument("--out", type=Path, default=None, help="where the run folders and identifications go (default: temp)")
    parser.add_argument("--predict", action="store_true", help="then compare dry runs and simulations, original and identified")
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"),
                        help="where the El Centro record is (default: ../shared/data/ground_motions)")
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="identify-dry-run-"))
    print(markdown(rows(out, args.duration_noise, args.duration_quake, args.seed)))
    if args.predict:
        overlay = merged_overlay(out)
        print("\n| profile | largest peak difference, dry run of the hidden rig vs simulate --rig-effects | where | target |")
        print("|---|---:|---|---:|")
        for name, used in (("original", None), ("identified", overlay)):
            worst, where = largest_peak_difference(used, args.records_dir, out / f"predict_{name}")
            print(f"| {name} | {100 * worst:.1f} % | {where} | {100 * TARGETS['prediction']:g} % |")
    print(f"\nrun folders and identifications in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(run())
