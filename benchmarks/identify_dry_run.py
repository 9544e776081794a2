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

It prints, per value, the truth, the profile's value, the identified one and its error, against
the issue's targets (modal frequencies within 2 %, damping within 30 %, story stiffness within
10 %, friction within 10 %).

Usage: python benchmarks/identify_dry_run.py [--duration-noise S] [--duration-quake S] [--seed N] [--out DIR]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

from harness.cli import main  # noqa: E402
from harness.identification.bearing import identify_bearing  # noqa: E402
from harness.identification.structure import identify_structure  # noqa: E402
from harness.model.building import fixed_base_modes  # noqa: E402
from harness.profile import load_profile  # noqa: E402

TRUE_STIFFNESS = (0.8395e6, 1.848e6, 1.7464e6)
TRUE_DAMPING = 0.015
TRUE_BEARING = {"mu_max": 0.075, "mu_delta": 0.024, "a_mu_s_per_m": 70.0}
TARGETS = {"frequency": 0.02, "damping": 0.3, "stiffness": 0.1, "friction": 0.1}


def truth_settings() -> list[str]:
    """The ``--set`` options that give the virtual rig its own truth."""
    stiffness = ",".join(f"{k:g}" for k in TRUE_STIFFNESS)
    settings = [f"rig.truth.structure.story_stiffness_N_per_m=[{stiffness}]",
                f"rig.truth.structure.first_mode_damping_ratio={TRUE_DAMPING:g}"]
    settings += [f"rig.truth.bearing.{key}={value:g}" for key, value in TRUE_BEARING.items()]
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
    import dataclasses

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
    return table


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
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="identify-dry-run-"))
    print(markdown(rows(out, args.duration_noise, args.duration_quake, args.seed)))
    print(f"\nrun folders and identifications in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(run())
