"""``harness identify bearing``: the friction law of Eq. 3-5 from run folders.

For each run: the friction force from the base mat's force balance
(:mod:`harness.identification.force_balance`: load cell, base-mat and floor accelerations,
restraining springs, the profile's masses), the sliding motion (displacement fused with
velocity), then one fit over all runs together (:mod:`harness.identification.friction_fit`).
Written to DIR: ``identified.yaml`` (the determined ``bearing.*`` values), ``identification.json``
and ``friction.png`` (:mod:`harness.identification.bearing_plot`).

The actuator's force is the load cell's (``force_measured_N``); an offline simulation's case,
which has no load cell, gives the force it applied (``force_command_N``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.identification import friction_fit as ff
from harness.identification.bearing_plot import friction_plot
from harness.identification.force_balance import friction_from_balance
from harness.identification.outputs import (
    OVERLAY_FILE,
    RECORD_FILE,
    OverlayValue,
    claim_result_folder,
    write_overlay,
    write_record,
)
from harness.identification.run_signals import (
    RunUsed,
    design_bearing,
    distinct_runs_used,
    floor_columns,
    load_runs_checked,
    require_columns,
    same_building,
    uniform_signals,
)
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.recording import RunData
from harness.signals import columns as layout

PLOT_FILE = "friction.png"
#: The files DIR gets (:func:`~harness.identification.outputs.claim_result_folder`).
RESULT_FILES = (OVERLAY_FILE, RECORD_FILE, PLOT_FILE)
PURPOSE = "the bearing's identification (the base mat's force balance, Eq. 1-2)"


@dataclass(frozen=True)
class BearingIdentification:
    """What ``harness identify bearing`` found and wrote.

    Attributes
    ----------
    fit : FrictionFit
    design : BearingConfig
        The profile's bearing (of the first run).
    building : BuildingConfig
        The masses and springs the force balance used.
    runs : tuple of RunUsed
    overlay_path, record_path, plot_path : Path
    """

    fit: ff.FrictionFit
    design: BearingConfig
    building: BuildingConfig
    runs: tuple[RunUsed, ...]
    overlay_path: Path
    record_path: Path
    plot_path: Path


def actuator_force_column(run: RunData) -> str:
    """The column holding the actuator's force: the load cell's, or an offline simulation's applied force."""
    if not run.has(layout.FORCE_MEASURED) and run.kind == "simulation" and run.has(layout.FORCE_COMMAND):
        return layout.FORCE_COMMAND
    return layout.FORCE_MEASURED


def needed_columns(run: RunData, n_stories: int) -> dict[str, str]:
    """Column -> what it holds, for every column the bearing's identification reads from ``run``."""
    return {
        actuator_force_column(run): "the actuator's force on the base mat, the load cell (N)",
        layout.SLIDING_DISPLACEMENT: "sliding displacement x_b (m)",
        layout.SLIDING_VELOCITY: "sliding velocity xdot_b (m/s)",
        layout.BASE_ACCELERATION: "absolute acceleration of the base mat (m/s^2)",
        **floor_columns(n_stories),
    }


def sliding_record(run: RunData, building: BuildingConfig) -> ff.SlidingRecord:
    """The run's sliding motion and its friction force from the force balance, on a uniform grid.

    Raises
    ------
    IdentificationError
        If the run lacks a column (:func:`needed_columns`).
    """
    needed = needed_columns(run, building.n_stories)
    require_columns(run, needed, PURPOSE)
    rate_hz, signals = uniform_signals(run, needed)
    floors = [signals[layout.floor_acceleration(j)] for j in range(1, building.n_stories + 1)]
    actuator = signals[actuator_force_column(run)]
    others = friction_from_balance(building, np.zeros_like(actuator), signals[layout.SLIDING_DISPLACEMENT],
                                   signals[layout.BASE_ACCELERATION], floors)
    measured = signals[layout.SLIDING_DISPLACEMENT]
    displacement = ff.fused_displacement(measured, signals[layout.SLIDING_VELOCITY], rate_hz)
    return ff.SlidingRecord(run.path.name, rate_hz, displacement, signals[layout.SLIDING_VELOCITY], actuator, others,
                            measured)


def overlay_values(fit: ff.FrictionFit) -> list[OverlayValue]:
    """The determined values, each with its standard error and the fit's error as the comment."""
    quality = f"fit rms {fit.rms_error_N:.3g} N ({100 * fit.relative_rms_error:.2g} % of the peak friction)"
    values = []
    for name in fit.determined:
        estimate = fit.estimates[name]
        values.append(OverlayValue(name, estimate.value, f"+/- {estimate.standard_error:.2g} (1 SE, "
                                   f"{100 * estimate.relative_error:.2g} %); {quality}; profile had {estimate.design:.6g}"))
    return values


def identify_bearing(paths: Sequence[Path | str], out_dir: Path, lowpass_hz: float = ff.LOWPASS_HZ,
                     force: bool = False) -> BearingIdentification:
    """Identify the friction law from the run folders ``paths``; write DIR's files.

    ``force`` replaces the results of an earlier identification in ``out_dir`` (else refused).

    Raises
    ------
    RunFolderError
        For a path that is not a run folder, or an ``out_dir`` holding earlier results without ``force``.
    IdentificationError
        For a run without the columns needed, an incomplete run, the same run twice, or runs of
        buildings with different masses.
    """
    runs = load_runs_checked(paths)
    building = same_building(runs)
    used = distinct_runs_used(runs)
    claim_result_folder(out_dir, RESULT_FILES, force)
    records = [sliding_record(run, building) for run in runs]
    design = design_bearing(runs[0])
    fit = ff.fit_friction(records, design, building.total_weight_N, lowpass_hz)
    out_dir.mkdir(parents=True, exist_ok=True)
    header = [
        f"harness identify bearing: the friction law (Eq. 3-5) from {len(runs)} run(s); identification.json has the details.",
        "A profile overlay: merged over a profile, these values replace its own (the identified rig is the design model).",
        f"Determined: {', '.join(fit.determined) or 'none'}." + (f" {fit.note}" if fit.note else ""),
    ]
    overlay_path = write_overlay(out_dir, header, {"bearing": overlay_values(fit)})
    plot_path = friction_plot(records, fit, building.total_weight_N, out_dir / PLOT_FILE,
                              f"bearing friction from {len(runs)} run(s): measured (force balance) and fitted")
    record_path = write_record(out_dir, "identify bearing", used, {
        "kind": "bearing",
        "model": "f = mu mbar g nu, mu = mu_max - mu_delta exp(-a_mu |xdot_b|) (Eq. 3-4), nu of Eq. 5 along x_b",
        "parameters": {name: estimate.as_dict() for name, estimate in fit.estimates.items()},
        "determined": list(fit.determined),
        "held_at_profile": {"alpha": design.alpha, "beta": design.beta, "gamma": design.gamma, "eta": design.eta},
        "note": fit.note or None,
        "simex": fit.simex.as_dict() if fit.simex else None,
        "fit": {
            "rms_error_N": fit.rms_error_N, "peak_friction_N": fit.peak_friction_N,
            "relative_rms_error": fit.relative_rms_error, "correlation_samples": fit.correlation_samples,
            "load_cell_delay_s": fit.delay_s, "load_cell_delay_se_s": fit.delay_se_s,
            "evaluations": fit.evaluations, "lowpass_hz": lowpass_hz, "crossover_hz": ff.CROSSOVER_HZ,
            "method": "scipy.optimize.least_squares (trf), standard errors the larger of the Jacobian's (inflated by "
                      "the residuals' correlation time) and a block sandwich's"
                      + ("; the values SIMEX-corrected for the displacement and velocity sensors' noise (quadratic "
                         "extrapolant, standard error the plain fit's and the extrapolation's combined)" if fit.simex else ""),
        },
        "force_balance": {
            "total_weight_N": building.total_weight_N, "base_mass_kg": building.base_mass_kg,
            "floor_masses_kg": list(building.floor_masses_kg),
            "restoring_stiffness_N_per_m": building.restoring_stiffness_N_per_m,
        },
        "per_run": [{"run": record.label, "actuator_force": actuator_force_column(run), "slid": slid,
                     "peak_sliding_speed_m_s": float(np.abs(record.velocity_m_s).max()),
                     "sliding_range_m": float(np.ptp(record.displacement_m)), "duration_s": record.duration_s}
                    for run, record, slid in zip(runs, records, fit.slid, strict=True)],
        "files": {"overlay": overlay_path.name, "plot": plot_path.name},
    })
    return BearingIdentification(fit, design, building, used, overlay_path, record_path, plot_path)
