"""Does the structure identification's stated 95 % interval cover the truth? Coverage over seeds on the virtual rig.

For each seed, the README's commissioning step 4 on the virtual rig with the shipped profile
(its own values are the truth: no ``rig.truth``): ``harness dry-run --lockstep --record
white_noise:0.5-20 --duration S --set record.seed=SEED``, then ``harness identify structure``
on its run folder (a run stopped early by a check, exit status 4, is identified on the rows it
recorded, as a lab would). For every identified value (three modal frequencies and damping
ratios, three story stiffnesses, the story model's first-mode damping ratio) it counts the
seeds whose stated 95 % interval (:func:`harness.identification.fit_statistics.interval_95`) holds the truth, and
prints a markdown table: covered seeds, the mean error and the mean stated half-width.

With ``--bearing``, the README's bearing step instead: ``harness dry-run --lockstep --duration S
--set record.seed=SEED`` (the default synthetic record, its seed varied: the base mat slides), then
``harness identify bearing`` on its run folder, against the shipped bearing (``mu_max``,
``mu_delta``, ``a_mu``, ``D_y``). Its intervals are value -/+ 1.96 standard errors (the values
SIMEX-corrected for the sensors' noise in the fit's input; their errors the plain fit's, the larger
of the Jacobian's and the blocks' over 8 stretches of the record, combined with the
extrapolation's Monte Carlo error). Run folders already in ``--out`` are identified again
without a new dry run.

With ``--actuator``, the README's actuator step: ``harness identify actuator --both --duration S
--set rig.seed=SEED`` (lockstep, the default chirp over 1-30 Hz, free and blocked; the seed varies
the sensors' noise), against the shipped actuator as its linearised model states it
(:class:`~harness.identification.actuator_fit.ActuatorParameters` from the profile, the delay the
loop's share plus the actuator's): every value the fit frees. Intervals: as the structure's,
value -/+ t (7 degrees of freedom, 2.36) standard errors, as ``identification.json`` states them.
Folders already in ``--out`` are fitted again without new runs.

Usage: python benchmarks/identify_coverage.py [--bearing | --actuator] [--seeds N] [--duration S] [--workers W]
[--out DIR]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

from harness.cli import main  # noqa: E402
from harness.identification.actuator import identify_actuator_fit, loop_delay_s  # noqa: E402
from harness.identification.actuator_fit import FITTED, ActuatorParameters  # noqa: E402
from harness.identification.bearing import identify_bearing  # noqa: E402
from harness.identification.fit_statistics import t_factor_95  # noqa: E402
from harness.identification.friction_fit import PARAMETERS  # noqa: E402
from harness.identification.structure import identify_structure  # noqa: E402
from harness.model.building import fixed_base_modes  # noqa: E402
from harness.profile import load_profile  # noqa: E402
from harness.rig.grid import half_up  # noqa: E402


def truth() -> dict[str, float]:
    """The shipped profile's structure: what the virtual rig runs when no ``rig.truth`` is set."""
    structure = load_profile().structure
    omega, zeta = fixed_base_modes(structure)
    values = {f"mode {r + 1} frequency (Hz)": float(omega[r] / (2 * np.pi)) for r in range(3)}
    values |= {f"mode {r + 1} damping ratio": float(zeta[r]) for r in range(3)}
    values |= {f"story {j + 1} stiffness (N/m)": float(k) for j, k in enumerate(structure.story_stiffness_N_per_m)}
    values["first-mode damping ratio (story model)"] = float(structure.first_mode_damping_ratio or np.nan)
    return values


#: Labels of the bearing's identified values, in the order of the fit's PARAMETERS (the profile's attributes).
BEARING_LABELS = ("mu_max", "mu_delta", "a_mu (s/m)", "D_y (m)")


def bearing_truth() -> dict[str, float]:
    """The shipped profile's bearing: what the virtual rig runs when no ``rig.truth`` is set."""
    bearing = load_profile().bearing
    return {label: float(getattr(bearing, name)) for label, name in zip(BEARING_LABELS, PARAMETERS, strict=True)}


def one_bearing_seed(job: tuple[int, float, Path]) -> dict[str, tuple[float, float]]:
    """(identified, standard error) per bearing value for one seed of the synthetic record."""
    seed, duration_s, out = job
    logs = out / f"bearing{seed}"
    if not logs.is_dir():
        status = main(["dry-run", "--lockstep", "--quiet", "--log-dir", str(logs), "--duration", f"{duration_s:g}",
                       "--set", f"record.seed={seed}"])
        if status not in (0, 4):
            raise SystemExit(f"seed {seed}: dry run ended with exit status {status}")
    (folder,) = [p for p in logs.iterdir() if (p / "metadata.json").is_file()]
    fit = identify_bearing([folder], out / f"identb{seed}", force=True).fit
    return {label: (fit.estimates[name].value, fit.estimates[name].standard_error)
            for label, name in zip(BEARING_LABELS, PARAMETERS, strict=True)}


def actuator_truth() -> dict[str, float]:
    """The shipped actuator as the fit's model states it (no ``rig.truth``): what the fit should find."""
    profile = load_profile()
    step_s = 1.0 / profile.control.rate_hz  # in lockstep the rig delays its sensors by whole steps (harness/rig/sensors.py)
    velocity_lag_s = half_up(profile.rig.sensors.velocity.delay_s / step_s) * step_s
    truth = ActuatorParameters.from_config(
        profile.rig.actuator.hydraulics, profile.rig.actuator.delay_s + loop_delay_s(profile, lockstep=True),
        velocity_lag_s, profile.rig.physics_substep_s,
    )
    return {name: float(getattr(truth, name)) for name in FITTED}


def one_actuator_seed(job: tuple[int, float, Path]) -> dict[str, tuple[float, float]]:
    """(identified, standard error) per value the actuator fit freed, for one seed of the sensors' noise."""
    seed, duration_s, out = job
    folder = out / f"actuator{seed}"
    if not (folder / "excitation.json").is_file():
        status = main(["identify", "actuator", "--both", "--quiet", "--yes", "--out", str(folder), "--force",
                       "--duration", f"{duration_s:g}", "--set", f"rig.seed={seed}"])
        if status != 0:
            raise SystemExit(f"seed {seed}: identify actuator ended with exit status {status}")
    else:  # fitted again on the responses measured before (a changed fit, the same data)
        identify_actuator_fit(folder, load_profile(), lockstep=True)
    parameters = json.loads((folder / "identification.json").read_text(encoding="utf-8"))["parameters"]
    return {name: (float(p["value"]), float(p["standard_error"])) for name, p in parameters.items() if p["fitted"]}


def one_seed(job: tuple[int, float, Path]) -> dict[str, tuple[float, float]]:
    """(identified, standard error) per value for one seed."""
    seed, duration_s, out = job
    logs = out / f"seed{seed}"
    if not logs.is_dir():  # an earlier call's run folder is reused (--out): the runs are the slow part
        status = main(["dry-run", "--lockstep", "--quiet", "--log-dir", str(logs), "--record", "white_noise:0.5-20",
                       "--duration", f"{duration_s:g}", "--set", f"record.seed={seed}"])
        if status not in (0, 4):  # 4: stopped early by a check; its rows up to the stop are still a measurement
            raise SystemExit(f"seed {seed}: dry run ended with exit status {status}")
    (folder,) = [p for p in logs.iterdir() if (p / "metadata.json").is_file()]
    found = identify_structure([folder], out / f"ident{seed}", force=True)
    modal, stories = found.modal, found.stories
    values = {f"mode {r + 1} frequency (Hz)": (modal.frequency_hz[r], modal.frequency_se_hz[r]) for r in range(3)}
    values |= {f"mode {r + 1} damping ratio": (modal.damping_ratio[r], modal.damping_se[r]) for r in range(3)}
    values |= {f"story {j + 1} stiffness (N/m)": (stories.stiffness_N_per_m[j], stories.stiffness_se[j]) for j in range(3)}
    values["first-mode damping ratio (story model)"] = (stories.first_mode_damping_ratio or np.nan,
                                                        stories.first_mode_damping_se or np.nan)
    return {k: (float(v), float(se)) for k, (v, se) in values.items()}


def table(results: list[dict[str, tuple[float, float]]], truths: dict[str, float] | None = None,
          t: float | None = None) -> str:
    truths = truth() if truths is None else truths
    t = t_factor_95() if t is None else t
    lines = [f"| value | truth | covered (of {len(results)}) | mean error | largest error | mean stated 95 % half-width |",
             "|---|---:|---:|---:|---:|---:|"]
    for name, true in truths.items():
        if any(name not in r for r in results):  # held, not fitted
            continue
        found = np.array([r[name][0] for r in results])
        half = t * np.array([r[name][1] for r in results])
        covered = int(np.count_nonzero(np.abs(found - true) <= half))
        error = found / true - 1.0
        lines.append(f"| {name} | {true:.5g} | {covered} | {100 * error.mean():+.2f} % | "
                     f"{100 * error[np.argmax(np.abs(error))]:+.2f} % | {100 * np.mean(half / true):.2f} % |")
    return "\n".join(lines)


def run(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20)
    parser.add_argument("--duration", type=float, default=30.0, help="white-noise dry run length (s)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--out", type=Path, default=None, help="where the run folders go (default: temp)")
    step = parser.add_mutually_exclusive_group()
    step.add_argument("--bearing", action="store_true", help="the bearing step (synthetic record) instead")
    step.add_argument("--actuator", action="store_true",
                      help="the actuator step (identify actuator --both; --duration is the chirp's) instead")
    args = parser.parse_args(argv)
    out = args.out or Path(tempfile.mkdtemp(prefix="identify-coverage-"))
    if args.actuator:
        with ProcessPoolExecutor(args.workers) as pool:
            results = list(pool.map(one_actuator_seed, [(seed, args.duration, out) for seed in range(args.seeds)]))
        print(table(results, actuator_truth()))
        print(f"\n{args.seeds} seeds of the sensors' noise, identify actuator --both with {args.duration:g} s chirps "
              f"(lockstep); folders in {out}")
        return 0
    if args.bearing:
        with ProcessPoolExecutor(args.workers) as pool:
            results = list(pool.map(one_bearing_seed, [(seed, args.duration, out) for seed in range(args.seeds)]))
        print(table(results, bearing_truth(), 1.96))
        print(f"\n{args.seeds} seeds, {args.duration:g} s lockstep dry runs of the synthetic record; run folders in {out}")
        return 0
    with ProcessPoolExecutor(args.workers) as pool:
        results = list(pool.map(one_seed, [(seed, args.duration, out) for seed in range(args.seeds)]))
    print(table(results))
    print(f"\n{args.seeds} seeds, {args.duration:g} s lockstep white-noise dry runs; run folders in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(run())
