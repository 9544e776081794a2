"""Race against OpenSees: the passive 8-story building on friction bearings, two independent models (issue 12, item 5).

The same case is run by our simulator and by OpenSees (openseespy), from the same
profile values and the same processed table acceleration, and the two are compared
on peaks and on speed.

The case: ``profiles/eight_story.yaml`` (SPEC 6a), PASSIVE (bearings only, no actuator
force), El Centro 1940 NS processed by ``harness.runs.options.prepare_motion`` exactly as
``harness simulate --record el_centro --pga 0.3 --time-scale 1 --duration 30`` does
(cut, scaled to 0.3 g, baseline-corrected; 0.01 s samples, linear between them).

Ours: ``harness.simulation.case.run_case`` with no controller (the compiled Dormand-Prince
kernel, rtol from the profile), sampled at the profile's rate (250 Hz).

OpenSees: a 2D model (ndm 2, ndf 3), one node per level, all at the origin:

- ground node, fixed; base-mat node, free horizontally and vertically; floor nodes,
  free horizontally only; lumped horizontal masses ``m_b``, ``m_1..m_n``;
- story j: a ``zeroLength`` element with an ``Elastic`` material ``E = k_j``,
  ``eta = c_j``: spring and dashpot in parallel on the story drift, as in our model
  (discrete story dashpots, SPEC 1; no Rayleigh damping anywhere, in neither model);
- bearings: one ``flatSliderBearing`` between ground and base mat with
  ``frictionModel VelDependent muSlow muFast transRate``: ``muFast = mu_max``,
  ``muSlow = mu_max - mu_delta``, ``transRate = a_mu`` (s/m), which is Eq. 4 exactly;
  its normal force is the whole weight ``mbar g`` (base mat plus floors), applied
  as a vertical load on the base-mat node in a static step before the earthquake;
  its elastic branch ``kInit = mu W / D_y`` replaces the Bouc-Wen rise of Eq. 5
  (``--kinit-mu`` picks mu at rest or mu_max);
- restraining springs ``k_b`` (base mat to table) as a ``zeroLength`` spring when the
  profile has any (``eight_story.yaml`` has none);
- ``UniformExcitation`` with a ``Path`` time series of the table acceleration; Newmark
  average acceleration, Newton iterations to ``NormDispIncr`` ``--tol``, fixed step ``--dt``.
  Absolute floor accelerations are OpenSees's relative ones plus the table's.

Peaks (SPEC 5: story drifts, absolute floor and base-mat accelerations, sliding
displacement) are taken on both sides at the same instants, the controller sample
times k / rate, by the same function (``harness.signals.peaks.peak_responses``).

Speed: the analysis time of each side (median of --repeat runs after one warm-up,
imports, profile and record loading excluded: our plant plus ``run_case``;
OpenSees's model build, gravity step, transient analysis and output), and the whole
process of each side (a fresh ``python benchmarks/bench_opensees.py --side ours|opensees``
that imports, loads and runs end to end; median of --repeat).

Targets: our analysis at least 3x faster than OpenSees's; every peak within 3 %.

Setup: ``.venv/bin/pip install -e '.[bench]'`` (or ``.venv/bin/pip install openseespy``).
openseespy 3.8 needs Python >= 3.12; on 3.11 pip takes 3.7.1.2, whose bundled
LAPACK cannot find its bundled BLAS (no RUNPATH): :func:`import_opensees` preloads it.

Usage::

    python benchmarks/bench_opensees.py                      # the race, 3 repeats
    python benchmarks/bench_opensees.py --repeat 5 --dt 0.0005
    python benchmarks/bench_opensees.py --yield-displacement-m 1.2e-5   # diagnose the bearing branch
    python benchmarks/bench_opensees.py --side opensees      # one side once, peaks as JSON

Prints the peaks side by side with the % difference and the timing table, and writes
the raw figures to ``benchmarks/results/opensees.json``.
"""

from __future__ import annotations

import argparse
import ctypes
import dataclasses
import importlib.util
import json
import platform
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.model.bearing import BearingConfig
from harness.model.building import GRAVITY_M_S2, BuildingConfig, fixed_base_modes
from harness.model.plant import Plant, TableMotion
from harness.motions import GroundMotion
from harness.profile import Profile, load_profile
from harness.runs.options import StudyOptions, prepare_motion
from harness.signals.peaks import peak_responses
from harness.simulation.case import SamplingSettings, run_case

PROFILE = REPO / "profiles" / "eight_story.yaml"
RECORDS_DIR = REPO.parent / "shared" / "data" / "ground_motions"
RESULTS = REPO / "benchmarks" / "results" / "opensees.json"
RECORD, PGA_G, TIME_SCALE, DURATION_S = "el_centro", 0.3, 1.0, 30.0
PEAK_TARGET_PCT = 3.0
SPEED_TARGET = 3.0

# OpenSees tags.
GROUND, BASE = 1, 2  # nodes; floor j is node BASE + j
AXIAL_MAT, ROTATION_MAT, RESTORING_MAT, STORY_MAT0 = 1, 2, 3, 10
BEARING_ELE, RESTORING_ELE, STORY_ELE0 = 1, 2, 10
FRICTION_TAG = 1
#: Vertical shortening of the bearing under the weight (m): a stiff axial spring.
AXIAL_SHORTENING_M = 1e-6


@dataclass(frozen=True)
class SideResult:
    """One side's run of the case.

    Attributes
    ----------
    peaks : dict
        Flat peaks (``harness.signals.peaks.Peaks.flatten``), SI: m and m/s^2.
    analysis_s : float
        Wall time of the analysis (s), imports and loading excluded.
    details : dict
        Side-specific facts (steps, transient time, fallbacks, ...).
    """

    peaks: dict[str, float]
    analysis_s: float
    details: dict


# ----------------------------------------------------------------------------- inputs


def load_case(profile_path: Path, records_dir: Path,
              yield_displacement_m: float | None) -> tuple[Profile, GroundMotion]:
    """The profile and the processed table motion of the case.

    Parameters
    ----------
    profile_path : Path
        Profile YAML (default ``profiles/eight_story.yaml``).
    records_dir : Path
        Directory of the ground-motion files.
    yield_displacement_m : float or None
        Override of the bearing's Bouc-Wen ``D_y`` (m) for both models (a diagnostic);
        None keeps the profile's.

    Returns
    -------
    profile : Profile
    motion : GroundMotion
        Processed exactly as ``harness simulate`` processes it (``prepare_motion``).
    """
    profile = load_profile(profile_path)
    if yield_displacement_m is not None:
        bearing = dataclasses.replace(profile.bearing, yield_displacement_m=yield_displacement_m)
        profile = dataclasses.replace(profile, bearing=bearing)
    options = StudyOptions(record=RECORD, records_dir=str(records_dir), pga_g=PGA_G, time_scale=TIME_SCALE,
                           duration_s=DURATION_S, controller="none")
    return profile, prepare_motion(profile, options)


# ----------------------------------------------------------------------------- our side


def run_ours(profile: Profile, motion: GroundMotion, rate_hz: float) -> SideResult:
    """Run the passive case with our simulator.

    Parameters
    ----------
    profile : Profile
    motion : GroundMotion
    rate_hz : float
        Sample rate of the outputs (Hz); peaks are taken at these instants.

    Returns
    -------
    SideResult
        Analysis time = plant construction plus ``run_case`` (integration, responses, peaks).
    """
    started = time.perf_counter()
    plant = Plant(profile.structure, profile.bearing, TableMotion.from_motion(motion), rtol=profile.simulation.rtol)
    result = run_case("passive", plant, motion.duration_s, SamplingSettings(rate_hz))
    elapsed = time.perf_counter() - started
    peaks = result.peaks.flatten()
    peaks.pop("peak_force_pct_weight", None)
    return SideResult(peaks, elapsed, {"integrator_steps": result.integrator_steps, "rtol": profile.simulation.rtol})


# ----------------------------------------------------------------------------- OpenSees side


def import_opensees() -> ModuleType:
    """Import ``openseespy.opensees``, working around a packaging fault of openseespylinux 3.7.

    openseespylinux 3.7.1.2 ships ``lib/liblapack.so.3`` and ``lib/libblas.so.3`` beside
    ``opensees.so``; ``opensees.so`` finds its LAPACK through its RUNPATH, but LAPACK has
    no RUNPATH of its own and cannot find the BLAS beside it unless the system has one
    (Debian's libblas3). Loading the bundled BLAS first, with global symbols, satisfies it.

    Raises
    ------
    SystemExit
        openseespy is not installed (with the command that installs it).
    """
    spec = importlib.util.find_spec("openseespylinux")
    if spec is None or spec.origin is None:
        if importlib.util.find_spec("openseespy") is None:
            raise SystemExit("openseespy is not installed: .venv/bin/pip install -e '.[bench]'")
    else:
        bundled_blas = Path(spec.origin).parent / "lib" / "libblas.so.3"
        if bundled_blas.exists():
            ctypes.CDLL(str(bundled_blas), mode=ctypes.RTLD_GLOBAL)
    import openseespy.opensees as ops

    return ops


def bearing_initial_stiffness(bearing: BearingConfig, weight_N: float, kinit_mu: str) -> float:
    """``kInit`` of the flat slider: the Bouc-Wen tangent of Eq. 3-5 at ``nu = 0``.

    Parameters
    ----------
    bearing : BearingConfig
    weight_N : float
        Weight carried by the bearings ``mbar g`` (N).
    kinit_mu : {"rest", "max"}
        Which friction coefficient: at rest ``mu_max - mu_delta`` (the tangent while
        the bearing sticks) or ``mu_max`` (fast sliding).

    Returns
    -------
    float
        ``mu W alpha / D_y`` (N/m).
    """
    mu = bearing.mu_max - bearing.mu_delta if kinit_mu == "rest" else bearing.mu_max
    return mu * weight_N * bearing.alpha / bearing.yield_displacement_m


def build_nodes(ops: ModuleType, building: BuildingConfig) -> None:
    """Ground, base-mat and floor nodes with their fixities and horizontal masses (kg)."""
    ops.node(GROUND, 0.0, 0.0)
    ops.fix(GROUND, 1, 1, 1)
    ops.node(BASE, 0.0, 0.0, "-mass", building.base_mass_kg, 0.0, 0.0)
    ops.fix(BASE, 0, 0, 1)  # vertical free: the bearing carries the weight
    for j, mass in enumerate(building.floor_masses_kg, start=1):
        ops.node(BASE + j, 0.0, 0.0, "-mass", mass, 0.0, 0.0)
        ops.fix(BASE + j, 0, 1, 1)


def build_stories(ops: ModuleType, building: BuildingConfig) -> None:
    """One zeroLength spring-dashpot per story: ``Elastic E = k_j`` (N/m), ``eta = c_j`` (N s/m)."""
    damping = building.story_damping()
    for j, (stiffness, c) in enumerate(zip(building.story_stiffness_N_per_m, damping, strict=True)):
        ops.uniaxialMaterial("Elastic", STORY_MAT0 + j, float(stiffness), float(c))
        ops.element("zeroLength", STORY_ELE0 + j, BASE + j, BASE + j + 1, "-mat", STORY_MAT0 + j, "-dir", 1)


def build_bearing(ops: ModuleType, building: BuildingConfig, bearing: BearingConfig, kinit_N_per_m: float) -> None:
    """The flat slider with Eq. 4's velocity-dependent friction, plus restraining springs if any.

    Local x of the bearing is vertical (axial, the normal force), local y horizontal (shear).
    """
    weight = building.total_weight_N
    ops.uniaxialMaterial("Elastic", AXIAL_MAT, weight / AXIAL_SHORTENING_M)
    ops.uniaxialMaterial("Elastic", ROTATION_MAT, 1.0e10)  # both rotations are fixed; any value
    ops.frictionModel("VelDependent", FRICTION_TAG, bearing.mu_max - bearing.mu_delta, bearing.mu_max,
                      bearing.a_mu_s_per_m)
    ops.element("flatSliderBearing", BEARING_ELE, GROUND, BASE, FRICTION_TAG, kinit_N_per_m,
                "-P", AXIAL_MAT, "-Mz", ROTATION_MAT, "-orient", 0, 1, 0, -1, 0, 0)
    if building.restoring_stiffness_N_per_m > 0.0:
        ops.uniaxialMaterial("Elastic", RESTORING_MAT, building.restoring_stiffness_N_per_m)
        ops.element("zeroLength", RESTORING_ELE, GROUND, BASE, "-mat", RESTORING_MAT, "-dir", 1)


def apply_gravity(ops: ModuleType, weight_N: float) -> None:
    """Put the whole weight ``mbar g`` (N) on the bearing in one static step, then hold it."""
    ops.timeSeries("Constant", 1)
    ops.pattern("Plain", 1, 1)
    ops.load(BASE, 0.0, -weight_N, 0.0)
    ops.system("BandGeneral")
    ops.numberer("Plain")
    ops.constraints("Plain")
    ops.test("NormDispIncr", 1e-12, 20)
    ops.algorithm("Newton")
    ops.integrator("LoadControl", 1.0)
    ops.analysis("Static")
    if ops.analyze(1) != 0:
        raise RuntimeError("OpenSees: the gravity step did not converge")
    ops.loadConst("-time", 0.0)
    ops.wipeAnalysis()


def set_up_transient(ops: ModuleType, motion: GroundMotion, tol_m: float) -> None:
    """Table acceleration (m/s^2) as a Path series, uniform excitation, Newmark average acceleration."""
    ops.timeSeries("Path", 2, "-dt", float(motion.dt_s), "-values", *np.asarray(motion.accel_m_s2).tolist())
    ops.pattern("UniformExcitation", 2, 1, "-accel", 2)
    ops.system("BandGeneral")
    ops.numberer("Plain")
    ops.constraints("Plain")
    ops.test("NormDispIncr", tol_m, 50)
    ops.algorithm("Newton")
    ops.integrator("Newmark", 0.5, 0.25)
    ops.analysis("Transient")


def advance_to(ops: ModuleType, n_steps: int, dt_s: float, target_s: float) -> int:
    """Advance ``n_steps`` of ``dt_s``; if a step fails, finish to ``target_s`` in tenths with line search.

    Returns
    -------
    int
        1 if the fallback was needed, else 0.

    Raises
    ------
    RuntimeError
        The fallback failed too.
    """
    if ops.analyze(n_steps, dt_s) == 0:
        return 0
    ops.algorithm("NewtonLineSearch")
    small = dt_s / 10.0
    while ops.getTime() < target_s - 0.5 * small:
        if ops.analyze(1, small) != 0:
            raise RuntimeError(f"OpenSees did not converge at t = {ops.getTime():.4f} s")
    ops.algorithm("Newton")
    return 1


def opensees_columns(times: np.ndarray, relative_disp: np.ndarray, relative_acc: np.ndarray,
                     table_acc: np.ndarray) -> dict[str, np.ndarray]:
    """Canonical run columns from OpenSees's nodal histories (node order: base mat, floors 1..n).

    Parameters
    ----------
    times : ndarray (K,)
        Sample times (s).
    relative_disp, relative_acc : ndarray (K, n + 1)
        Displacement (m) and acceleration (m/s^2) relative to the table.
    table_acc : ndarray (K,)
        Table acceleration (m/s^2) at ``times``.
    """
    absolute = relative_acc + table_acc[:, None]
    drifts = np.diff(relative_disp, axis=1)
    columns = {
        "t_s": times,
        "sliding_displacement_m": relative_disp[:, 0],
        "base_acceleration_m_s2": absolute[:, 0],
    }
    for j in range(drifts.shape[1]):
        columns[f"drift_{j + 1}_m"] = drifts[:, j]
    for j in range(drifts.shape[1]):
        columns[f"floor_acceleration_{j + 1}_m_s2"] = absolute[:, j + 1]
    return columns


def build_model(ops: ModuleType, building: BuildingConfig, bearing: BearingConfig, kinit_N_per_m: float) -> None:
    """A fresh OpenSees model of the building on its bearing, with the weight applied."""
    ops.wipe()
    ops.model("basic", "-ndm", 2, "-ndf", 3)
    build_nodes(ops, building)
    build_stories(ops, building)
    build_bearing(ops, building, bearing, kinit_N_per_m)
    apply_gravity(ops, building.total_weight_N)


def first_mode_rad_s(ops: ModuleType, profile: Profile, kinit_mu: str) -> float:
    """OpenSees's first circular frequency (rad/s) with the bearing on its elastic branch (stuck).

    A check of the model's masses and stiffnesses against our fixed-base first mode (SPEC 6a:
    5.24 rad/s); the bearing's kInit is some 40 times the first story's stiffness.
    """
    building, bearing = profile.structure, profile.bearing
    build_model(ops, building, bearing, bearing_initial_stiffness(bearing, building.total_weight_N, kinit_mu))
    omega = float(np.sqrt(ops.eigen(1)[0]))
    ops.wipe()
    return omega


def run_opensees(ops: ModuleType, profile: Profile, motion: GroundMotion, rate_hz: float, dt_s: float,
                 tol_m: float, kinit_mu: str) -> SideResult:
    """Build and run the OpenSees model of the passive case.

    Parameters
    ----------
    ops : module
        ``openseespy.opensees``.
    profile : Profile
    motion : GroundMotion
    rate_hz : float
        Output sample rate (Hz); ``1 / (rate_hz dt_s)`` must be a whole number.
    dt_s : float
        OpenSees's fixed time step (s).
    tol_m : float
        ``NormDispIncr`` tolerance of the Newton iterations (m).
    kinit_mu : {"rest", "max"}
        See :func:`bearing_initial_stiffness`.

    Returns
    -------
    SideResult
        Analysis time = model build, gravity, transient analysis and output.
    """
    steps_per_sample = round(1.0 / (rate_hz * dt_s))
    if abs(steps_per_sample * dt_s * rate_hz - 1.0) > 1e-9:
        raise ValueError(f"--dt {dt_s:g} s does not divide the sample period 1/{rate_hz:g} s")
    building, bearing = profile.structure, profile.bearing
    kinit = bearing_initial_stiffness(bearing, building.total_weight_N, kinit_mu)
    n_samples = round(motion.duration_s * rate_hz)
    nodes = [BASE + j for j in range(building.n_stories + 1)]
    started = time.perf_counter()
    build_model(ops, building, bearing, kinit)
    set_up_transient(ops, motion, tol_m)
    transient_started = time.perf_counter()
    disp = np.zeros((n_samples + 1, len(nodes)))
    acc = np.zeros_like(disp)
    fallbacks = 0
    for k in range(1, n_samples + 1):
        fallbacks += advance_to(ops, steps_per_sample, dt_s, k / rate_hz)
        disp[k] = [ops.nodeDisp(node, 1) for node in nodes]
        acc[k] = [ops.nodeAccel(node, 1) for node in nodes]
    transient_s = time.perf_counter() - transient_started
    times = np.arange(n_samples + 1) / rate_hz
    table = TableMotion.from_motion(motion).acceleration(times)
    peaks = peak_responses(opensees_columns(times, disp, acc, table), building.total_weight_N).flatten()
    elapsed = time.perf_counter() - started
    peaks.pop("peak_force_pct_weight", None)
    axial = float(-ops.eleResponse(BEARING_ELE, "basicForce")[0])
    details = {"dt_s": dt_s, "steps": n_samples * steps_per_sample, "tol_m": tol_m, "kinit_N_per_m": kinit,
               "kinit_mu": kinit_mu, "transient_s": transient_s, "fallback_samples": fallbacks,
               "bearing_normal_force_N": axial}
    ops.wipe()
    return SideResult(peaks, elapsed, details)


# ----------------------------------------------------------------------------- comparison and timing


def compare(ours: dict[str, float], theirs: dict[str, float]) -> list[dict]:
    """Rows ``{quantity, ours, opensees, diff_pct}``, diff = (ours - OpenSees) / OpenSees in %."""
    return [{"quantity": key, "ours": ours[key], "opensees": theirs[key],
             "diff_pct": 100.0 * (ours[key] - theirs[key]) / theirs[key]} for key in theirs]


def timed_runs(run: Callable[[], SideResult], repeat: int) -> tuple[SideResult, list[float]]:
    """One warm-up run, then ``repeat`` timed runs; returns the last result and the analysis times (s)."""
    run()
    results = [run() for _ in range(repeat)]
    return results[-1], [r.analysis_s for r in results]


def side_command(side: str, args: argparse.Namespace) -> list[str]:
    """The command line that runs one side once in a fresh interpreter."""
    command = [sys.executable, str(Path(__file__).resolve()), "--side", side, "--profile", str(args.profile),
               "--records-dir", str(args.records_dir), "--dt", repr(args.dt), "--tol", repr(args.tol),
               "--kinit-mu", args.kinit_mu]
    if args.rate is not None:
        command += ["--rate", repr(args.rate)]
    if args.yield_displacement_m is not None:
        command += ["--yield-displacement-m", repr(args.yield_displacement_m)]
    return command


def process_times(side: str, args: argparse.Namespace) -> list[float]:
    """Wall times (s) of ``args.repeat`` fresh processes that import, load and run one side end to end."""
    walls = []
    for _ in range(args.repeat):
        started = time.perf_counter()
        subprocess.run(side_command(side, args), check=True, capture_output=True, text=True)
        walls.append(time.perf_counter() - started)
    return walls


def run_side(side: str, profile: Profile, motion: GroundMotion, args: argparse.Namespace,
             rate_hz: float) -> SideResult:
    """Run one side once (``--side`` mode)."""
    if side == "ours":
        return run_ours(profile, motion, rate_hz)
    return run_opensees(import_opensees(), profile, motion, rate_hz, args.dt, args.tol, args.kinit_mu)


# ----------------------------------------------------------------------------- report


def print_peaks(rows: list[dict]) -> None:
    """Markdown table of the peaks side by side (m, m/s^2) with the % difference."""
    print("| peak | ours | OpenSees | difference |")
    print("|---|---|---|---|")
    for row in rows:
        unit = "m" if row["quantity"].endswith("_m") else "m/s^2"
        scale, shown = (100.0, "cm") if unit == "m" else (1.0, unit)
        name = row["quantity"].removesuffix("_m_s2").removesuffix("_m")
        print(f"| {name} ({shown}) | {row['ours'] * scale:.4f} | {row['opensees'] * scale:.4f} | "
              f"{row['diff_pct']:+.2f} % |")


def print_timing(timing: dict) -> None:
    """Markdown table of the analysis and whole-process times (s) and the ratios."""
    ours, theirs = timing["ours"], timing["opensees"]
    print("| side | analysis median (s) | analysis runs (s) | whole process median (s) | process runs (s) |")
    print("|---|---|---|---|---|")
    for label, side in (("ours", ours), ("OpenSees", theirs)):
        runs = ", ".join(f"{t:.3f}" for t in side["analysis_s"])
        procs = ", ".join(f"{t:.2f}" for t in side["process_s"])
        print(f"| {label} | {side['analysis_median_s']:.3f} | {runs} | {side['process_median_s']:.2f} | {procs} |")
    print(f"\nanalysis: ours / OpenSees = {timing['analysis_ratio']:.4f} "
          f"(ours {1.0 / timing['analysis_ratio']:.1f}x faster; target {SPEED_TARGET:g}x)")
    print(f"whole process: ours / OpenSees = {timing['process_ratio']:.3f} "
          f"(ours {1.0 / timing['process_ratio']:.2f}x faster)")


def timing_summary(ours_runs: list[float], theirs_runs: list[float], ours_procs: list[float],
                   theirs_procs: list[float]) -> dict:
    """Medians and ratios (ours / OpenSees) of the analysis and process times (s)."""
    def side(runs: list[float], procs: list[float]) -> dict:
        return {"analysis_s": runs, "analysis_median_s": statistics.median(runs),
                "process_s": procs, "process_median_s": statistics.median(procs)}

    ours, theirs = side(ours_runs, ours_procs), side(theirs_runs, theirs_procs)
    return {"ours": ours, "opensees": theirs,
            "analysis_ratio": ours["analysis_median_s"] / theirs["analysis_median_s"],
            "process_ratio": ours["process_median_s"] / theirs["process_median_s"]}


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """Command-line options (see the module docstring)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--profile", type=Path, default=PROFILE, help="profile YAML (default: %(default)s)")
    parser.add_argument("--records-dir", type=Path, default=RECORDS_DIR,
                        help="ground-motion files; El Centro is taken from here (default: %(default)s)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="timed runs per side, after one warm-up, and fresh processes per side (default: 3)")
    parser.add_argument("--rate", type=float, default=None,
                        help="output sample rate in Hz; peaks of both sides at these instants (default: the profile's)")
    parser.add_argument("--dt", type=float, default=0.001,
                        help="OpenSees fixed step in s; must divide 1/rate (default: %(default)s)")
    parser.add_argument("--tol", type=float, default=1e-10,
                        help="OpenSees Newton tolerance, NormDispIncr in m (default: %(default)s)")
    parser.add_argument("--kinit-mu", choices=("rest", "max"), default="rest",
                        help="flat slider kInit = mu W / D_y with mu at rest (mu_max - mu_delta: the Bouc-Wen "
                             "tangent while stuck) or mu_max (default: %(default)s)")
    parser.add_argument("--yield-displacement-m", type=float, default=None,
                        help="diagnostic: override D_y (m) in BOTH models; a smaller D_y shrinks the one "
                             "modelling difference, Bouc-Wen rise vs elastic-plastic branch")
    parser.add_argument("--side", choices=("ours", "opensees"), default=None,
                        help="run one side once and print its peaks and analysis time as JSON (what the "
                             "whole-process timing runs)")
    parser.add_argument("--json", type=Path, default=RESULTS, help="raw results (default: %(default)s)")
    return parser.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    """Run the race (or one side with ``--side``); print tables; write JSON."""
    args = parse_args(argv)
    profile, motion = load_case(args.profile, args.records_dir, args.yield_displacement_m)
    rate_hz = args.rate or profile.control.rate_hz
    if args.side is not None:
        result = run_side(args.side, profile, motion, args, rate_hz)
        print(json.dumps({"side": args.side, "analysis_s": result.analysis_s, "peaks": result.peaks}))
        return 0
    ops = import_opensees()
    ours, ours_runs = timed_runs(lambda: run_ours(profile, motion, rate_hz), args.repeat)
    theirs, theirs_runs = timed_runs(
        lambda: run_opensees(ops, profile, motion, rate_hz, args.dt, args.tol, args.kinit_mu), args.repeat)
    timing = timing_summary(ours_runs, theirs_runs, process_times("ours", args), process_times("opensees", args))
    theirs.details["first_mode_stuck_rad_s"] = first_mode_rad_s(ops, profile, args.kinit_mu)
    rows = compare(ours.peaks, theirs.peaks)
    worst = max(rows, key=lambda r: abs(r["diff_pct"]))
    omega = fixed_base_modes(profile.structure)
    print(f"case: {profile.name} passive, {motion.name} {motion.pga_g:.2f} g x{TIME_SCALE:g}, "
          f"{motion.duration_s:g} s; peaks at {rate_hz:g} Hz; OpenSees dt {args.dt:g} s, "
          f"kInit {theirs.details['kinit_N_per_m']:.4g} N/m ({args.kinit_mu})")
    print(f"bearing normal force {theirs.details['bearing_normal_force_N']:.6g} N "
          f"(mbar g {profile.structure.total_weight_N:.6g} N); first mode: ours fixed base "
          f"{omega[0][0]:.3f} rad/s ({100 * omega[1][0]:.2f} %), OpenSees with the bearing stuck "
          f"{theirs.details['first_mode_stuck_rad_s']:.3f} rad/s; OpenSees fallbacks "
          f"{theirs.details['fallback_samples']}\n")
    print_peaks(rows)
    print(f"\nworst peak difference {worst['diff_pct']:+.2f} % ({worst['quantity']}); target {PEAK_TARGET_PCT:g} %\n")
    print_timing(timing)
    document = {
        "machine": platform.platform(), "python": sys.version.split()[0], "opensees_version": ops.version(),
        "date": time.strftime("%Y-%m-%d"), "command": " ".join(["python", "benchmarks/bench_opensees.py",
                                                                *(argv if argv is not None else sys.argv[1:])]),
        "case": {"profile": profile.name, "record": motion.name, "pga_g": motion.pga_g, "time_scale": TIME_SCALE,
                 "duration_s": motion.duration_s, "rate_hz": rate_hz,
                 "yield_displacement_m": profile.bearing.yield_displacement_m,
                 "gravity_m_s2": GRAVITY_M_S2},
        "ours": ours.details, "opensees": theirs.details, "peaks": rows,
        "worst_peak": {"quantity": worst["quantity"], "diff_pct": worst["diff_pct"]}, "timing": timing,
        "targets": {"peaks_within_pct": PEAK_TARGET_PCT, "analysis_speedup": SPEED_TARGET,
                    "peaks_met": abs(worst["diff_pct"]) <= PEAK_TARGET_PCT,
                    "speed_met": 1.0 / timing["analysis_ratio"] >= SPEED_TARGET},
    }
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(document, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
