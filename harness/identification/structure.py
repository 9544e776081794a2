"""``harness identify structure``: fixed-base modes, then story stiffness and damping, from run folders.

1. Each run's base-mat and floor accelerations, band-passed alike and decimated
   (:mod:`harness.identification.structure_records`; the base mat's acceleration blended
   with its differentiated velocity where that is quieter, so the input's noise does not bias
   the damping); the measured response ``a_j / a_b`` (H1) gives the starting frequencies and the plot.
2. The modes: frequencies, damping ratios and participations, fitted in the time domain
   without the masses (:mod:`harness.identification.modal_fit`).
3. The stories: stiffness and damping of the shear building with the profile's masses that
   reproduce the floors' accelerations (:mod:`harness.identification.story_fit`), started where
   its frequencies are the identified ones; its own modes are compared with step 2's.

Written to DIR: ``identified.yaml`` (the determined ``structure.*`` values), ``identification.json``
and ``frf.png`` (:mod:`harness.identification.structure_plot`). A value is determined when its
relative standard error is below the accuracy :data:`DETERMINED_RELATIVE_ERROR` names and, for
a mode, it lies within the band.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.identification.choices import MIN_BAND_BINS
from harness.identification.fit_statistics import BLOCKS, relative_error, t_factor_95
from harness.identification.modal_fit import ModalFit, fit_modes, modal_response
from harness.identification.outputs import (
    OVERLAY_FILE,
    RECORD_FILE,
    OverlayValue,
    claim_result_folder,
    write_overlay,
    write_record,
)
from harness.identification.run_signals import (
    IdentificationError,
    RunUsed,
    distinct_runs_used,
    floor_columns,
    load_runs_checked,
    require_columns,
    same_building,
    uniform_signals,
)
from harness.identification.story_fit import (
    DampingModel,
    StoryFit,
    fit_frequency_response,
    fit_stories,
    floor_frequency_response,
    undamped_frequencies_hz,
    with_model_error,
)
from harness.identification.structure_plot import response_plot
from harness.identification.structure_records import (
    MeasuredResponse,
    StructureRecord,
    band_passed,
    base_acceleration_estimate,
    crossover_hz,
    frf_estimate,
)
from harness.model.building import BuildingConfig, fixed_base_modes
from harness.recording import RunData
from harness.signals import columns as layout

PLOT_FILE = "frf.png"
#: The files DIR gets (:func:`~harness.identification.outputs.claim_result_folder`).
RESULT_FILES = (OVERLAY_FILE, RECORD_FILE, PLOT_FILE)
PURPOSE = "the structure's identification (base mat in, floors out)"
#: Resolution of the measured response (Hz): the plot's, and the starting fit's.
RESOLUTION_HZ = 0.1
#: Largest relative standard error of a determined value, by kind (the accuracy each is wanted to).
DETERMINED_RELATIVE_ERROR = {"frequency": 0.02, "damping": 0.3, "stiffness": 0.1, "story_damping": 0.3}
#: Largest RMS error of the modal fit relative to the floors' band-passed RMS for anything to be determined:
#: above it the floors' motion is mostly what the base mat did not cause (sensor noise, a table at rest).
MAX_UNEXPLAINED = 0.5


@dataclass(frozen=True)
class Determination:
    """Whether one identified value is determined, and why."""

    determined: bool
    reason: str


@dataclass(frozen=True)
class StructureIdentification:
    """What ``harness identify structure`` found and wrote."""

    modal: ModalFit
    stories: StoryFit
    design: BuildingConfig
    band_hz: tuple[float, float]
    modes: tuple[Determination, ...]  # per mode: frequency and damping together
    stiffness: Determination
    damping: Determination
    runs: tuple[RunUsed, ...]
    overlay_path: Path
    record_path: Path
    plot_path: Path


def default_band(design: BuildingConfig, rate_hz: float) -> tuple[float, float]:
    """Half the design's first fixed-base frequency to 1.5 times its last (at most 0.4 of the rate)."""
    omega, _ = fixed_base_modes(design)
    return 0.5 * float(omega[0]) / (2.0 * np.pi), min(1.5 * float(omega[-1]) / (2.0 * np.pi), 0.4 * rate_hz)


def structure_record(run: RunData, n_stories: int, band_hz: tuple[float, float] | None, design: BuildingConfig
                     ) -> tuple[StructureRecord, tuple[float, float]]:
    """The run's band-passed input and outputs, and the band used.

    Raises
    ------
    IdentificationError
        If the run lacks a column, or the band does not fit its sample rate.
    """
    needed = {layout.BASE_ACCELERATION: "absolute acceleration of the base mat (m/s^2), the input", **floor_columns(n_stories)}
    require_columns(run, needed, PURPOSE)
    with_velocity = run.has(layout.BASE_VELOCITY)
    rate_hz, signals = uniform_signals(run, [*needed, *((layout.BASE_VELOCITY,) if with_velocity else ())])
    band = band_hz if band_hz is not None else default_band(design, rate_hz)
    if band[1] >= 0.45 * rate_hz:
        raise IdentificationError(f"run {run.path}: the band's upper frequency {band[1]:g} Hz is too close to the Nyquist "
                                  f"frequency of its {rate_hz:g} Hz rows; expected at most {0.4 * rate_hz:g} Hz (--band-hz)")
    floors = [signals[layout.floor_acceleration(j)] for j in range(1, n_stories + 1)]
    base = signals[layout.BASE_ACCELERATION]
    if with_velocity:
        base = base_acceleration_estimate(rate_hz, base, signals[layout.BASE_VELOCITY], input_crossover_hz(run, rate_hz))
    return band_passed(run.path.name, rate_hz, base, floors, band), band


def input_crossover_hz(run: RunData, rate_hz: float) -> float:
    """The crossover of the base mat's acceleration estimate (Hz) from the run's profile's sensor noise (``rig.sensors``).

    See :mod:`harness.identification.structure_records`; a profile without the sensors' noise
    gives the accelerometer alone.
    """
    sensors = (run.profile.get("rig") or {}).get("sensors") or {}
    acceleration = float((sensors.get("acceleration") or {}).get("noise_std_m_s2", 0.0) or 0.0)
    velocity = float((sensors.get("velocity") or {}).get("noise_std_m_s", 0.0) or 0.0)
    return crossover_hz(acceleration, velocity, rate_hz)


def check_band_bins(measured: MeasuredResponse, band_hz: tuple[float, float], given: bool) -> None:
    """Refuse a band holding fewer than :data:`~harness.identification.choices.MIN_BAND_BINS` frequencies of the response.

    The response has a frequency every ``1 / segment`` Hz, and a segment is at most a quarter
    of the shortest run (:func:`~harness.identification.structure_records.frf_estimate`).

    Parameters
    ----------
    measured : MeasuredResponse
    band_hz : tuple of float
    given : bool
        True if ``--band-hz`` set the band (else it is :func:`default_band`).

    Raises
    ------
    IdentificationError
        Naming the band, the frequencies it holds at the response's resolution and what would hold enough.
    """
    inside = int(np.count_nonzero((measured.freq_hz >= band_hz[0]) & (measured.freq_hz <= band_hz[1])))
    if inside < MIN_BAND_BINS:
        step_hz = float(measured.freq_hz[1] - measured.freq_hz[0])
        band = f"--band-hz {band_hz[0]:g},{band_hz[1]:g}" if given else \
            f"the default band {band_hz[0]:.3g}-{band_hz[1]:.3g} Hz (the design's modes)"
        raise IdentificationError(
            f"{band} holds {inside} frequencies of the measured response (one every {step_hz:.3g} Hz); expected at least "
            f"{MIN_BAND_BINS}, a response to fit and not a point: a band at least {MIN_BAND_BINS * step_hz:.3g} Hz wide, "
            "or longer runs (a segment is at most a quarter of the shortest run, so a longer run resolves finer)"
        )


def start_frequencies(measured: MeasuredResponse, design: BuildingConfig, band_hz: tuple[float, float]) -> np.ndarray:
    """One starting frequency per story (Hz): the modes of the building fitted to the measured response in the band.

    The frequency-domain fit (:func:`~harness.identification.story_fit.fit_frequency_response`)
    starts from the design and finds the modes from well off it; picking peaks of the measured
    response would take noise for modes where the coherence is low.
    """
    inside = (measured.freq_hz >= band_hz[0]) & (measured.freq_hz <= band_hz[1])
    masses = np.asarray(design.floor_masses_kg, dtype=float)
    stiffness, _ = fit_frequency_response(measured.freq_hz[inside], measured.response[:, inside],
                                          measured.coherence[:, inside], masses,
                                          np.asarray(design.story_stiffness_N_per_m, dtype=float), design.story_damping())
    return undamped_frequencies_hz(masses, stiffness)


def _determinations(modal: ModalFit, stories: StoryFit, band_hz: tuple[float, float]) -> tuple[tuple[Determination, ...],
                                                                                                  Determination, Determination]:
    """Per mode, for the stiffness and for the damping: determined or not, and why.

    Nothing is determined when the modes leave more than :data:`MAX_UNEXPLAINED` of the floors'
    motion unexplained; the damping only with the stiffness it is proportional to or shapes.
    """
    unexplained = modal.relative_rms_error
    explained = unexplained < MAX_UNEXPLAINED
    why_not = "" if explained else (
        f"; the modes leave {100 * unexplained:.0f} % of the floors' rms unexplained (at most {100 * MAX_UNEXPLAINED:g} %): "
        "the base mat barely moved, or the floors' sensors hold mostly noise")
    modes = []
    for r, (f, f_se, z, z_se) in enumerate(zip(modal.frequency_hz, modal.frequency_se_hz, modal.damping_ratio,
                                               modal.damping_se, strict=True), start=1):
        inside = bool(band_hz[0] <= f <= band_hz[1])
        f_rel, z_rel = relative_error(float(f), float(f_se)), relative_error(float(z), float(z_se))
        precise = f_rel < DETERMINED_RELATIVE_ERROR["frequency"] and z_rel < DETERMINED_RELATIVE_ERROR["damping"]
        ok = explained and inside and precise
        where = "within" if inside else "outside"
        modes.append(Determination(ok, f"mode {r}: {f:.4g} Hz {where} the band {band_hz[0]:g}-{band_hz[1]:g} Hz; standard "
                                       f"errors {100 * f_rel:.2g} % (frequency), {100 * z_rel:.2g} % (damping){why_not}"))
    k_rel = [relative_error(float(k), float(se)) for k, se in zip(stories.stiffness_N_per_m, stories.stiffness_se, strict=True)]
    c_rel = [relative_error(float(c), float(se)) for c, se in zip(stories.damping_Ns_per_m, stories.damping_se, strict=True)]
    listed = ", ".join(f"{100 * e:.2g} %" for e in k_rel)
    limit = 100 * DETERMINED_RELATIVE_ERROR["stiffness"]
    stiffness = Determination(explained and max(k_rel) < DETERMINED_RELATIVE_ERROR["stiffness"],
                              f"story stiffness standard errors {listed} (at most {limit:g} %){why_not}")
    if stories.first_mode_damping_ratio is not None:
        rel = relative_error(stories.first_mode_damping_ratio, stories.first_mode_damping_se or 0.0)
        precise = rel < DETERMINED_RELATIVE_ERROR["damping"]
        text = (f"first-mode damping ratio standard error {100 * rel:.2g} % (at most "
                f"{100 * DETERMINED_RELATIVE_ERROR['damping']:g} %)")
    else:
        precise = max(c_rel) < DETERMINED_RELATIVE_ERROR["story_damping"]
        text = (f"story damping standard errors {', '.join(f'{100 * e:.2g} %' for e in c_rel)} (at most "
                f"{100 * DETERMINED_RELATIVE_ERROR['story_damping']:g} %)")
    if not stiffness.determined:
        text += "; and the stiffness it goes with is not determined"
    damping = Determination(stiffness.determined and precise, text + why_not)
    return tuple(modes), stiffness, damping


def overlay_values(stories: StoryFit, modal: ModalFit, design: BuildingConfig, stiffness: Determination,
                   damping: Determination) -> list[OverlayValue]:
    """The determined ``structure.*`` values with their quality; a damping key of the other form is cleared (null)."""
    frequency_hz, ratio = stories.modes()
    gap = np.max(np.abs(frequency_hz - modal.frequency_hz) / modal.frequency_hz)
    quality = (f"floors' rms error {100 * stories.rms_error_m_s2 / modal.rms_signal_m_s2:.2g} % of their rms; modes "
               f"reproduced within {100 * gap:.2g} % in frequency")
    values = []
    if stiffness.determined:
        errors = ", ".join(f"{100 * se / k:.2g}" for k, se in zip(stories.stiffness_N_per_m, stories.stiffness_se, strict=True))
        values.append(OverlayValue("story_stiffness_N_per_m", tuple(float(k) for k in stories.stiffness_N_per_m),
                                   f"1 SE {errors} % (95 %: {t_factor_95():.3g} SE); {quality}; profile had "
                                   f"{', '.join(f'{k:.4g}' for k in design.story_stiffness_N_per_m)}"))
    if damping.determined:
        zetas = ", ".join(f"{z:.3g}" for z in ratio)
        if stories.first_mode_damping_ratio is not None:
            values.append(OverlayValue("first_mode_damping_ratio", stories.first_mode_damping_ratio,
                                       f"+/- {stories.first_mode_damping_se:.2g} (1 SE; 95 % +/- "
                                       f"{t_factor_95() * (stories.first_mode_damping_se or 0):.2g}); "
                                       f"stiffness-proportional: mode damping {zetas}; modal fit "
                                       f"{', '.join(f'{z:.3g}' for z in modal.damping_ratio)}"))
            if design.story_damping_Ns_per_m is not None:
                values.append(OverlayValue("story_damping_Ns_per_m", None, "cleared: the damping is given as a ratio"))
        else:
            errors = ", ".join(f"{100 * se / c:.2g}" for c, se in zip(stories.damping_Ns_per_m, stories.damping_se, strict=True))
            values.append(OverlayValue("story_damping_Ns_per_m", tuple(float(c) for c in stories.damping_Ns_per_m),
                                       f"1 SE {errors} %; mode damping {zetas}; modal fit "
                                       f"{', '.join(f'{z:.3g}' for z in modal.damping_ratio)}"))
            if design.first_mode_damping_ratio is not None:
                values.append(OverlayValue("first_mode_damping_ratio", None, "cleared: the damping is given per story"))
    return values


def identify_structure(paths: Sequence[Path | str], out_dir: Path, band_hz: tuple[float, float] | None = None,
                       damping_model: DampingModel | None = None, force: bool = False) -> StructureIdentification:
    """Identify the structure from the run folders ``paths``; write DIR's files.

    Parameters
    ----------
    paths : sequence of path
    out_dir : Path
    band_hz : tuple of float, optional
        The band (Hz); default :func:`default_band` of the first run.
    damping_model : {"per_story", "proportional"}, optional
        Default: the form the run's profile gives its damping in.
    force : bool
        Replace the results of an earlier identification in ``out_dir`` (else refused).

    Raises
    ------
    RunFolderError, IdentificationError
    """
    runs = load_runs_checked(paths)
    design = same_building(runs)
    used = distinct_runs_used(runs)
    claim_result_folder(out_dir, RESULT_FILES, force)
    records, bands = zip(*(structure_record(run, design.n_stories, band_hz, design) for run in runs), strict=True)
    band = bands[0]
    if len({round(r.rate_hz, 6) for r in records}) > 1:
        raise IdentificationError(f"runs {', '.join(str(r.path) for r in runs)}: their rows come at different rates; "
                                  "expected runs of one loop rate (identify each rate on its own)")
    model: DampingModel = damping_model or ("proportional" if design.first_mode_damping_ratio is not None else "per_story")
    measured = frf_estimate(records, RESOLUTION_HZ)
    check_band_bins(measured, band, band_hz is not None)
    modal = fit_modes(records, [float(f) for f in start_frequencies(measured, design, band)])
    stories = with_model_error(fit_stories(records, design, modal.frequency_hz, float(modal.damping_ratio[0]), model),
                               modal.frequency_hz, float(modal.damping_ratio[0]))
    modes, stiffness, damping = _determinations(modal, stories, band)
    out_dir.mkdir(parents=True, exist_ok=True)
    values = overlay_values(stories, modal, design, stiffness, damping)
    header = [
        f"harness identify structure: story stiffness and damping from {len(runs)} run(s) with the profile's masses; "
        "identification.json has the details.",
        "A profile overlay: merged over a profile, these values replace its own (the identified rig is the design model).",
        f"Stiffness {'determined' if stiffness.determined else 'NOT determined'}: {stiffness.reason}.",
        f"Damping {'determined' if damping.determined else 'NOT determined'}: {damping.reason}.",
    ]
    overlay_path = write_overlay(out_dir, header, {"structure": values})
    masses = np.asarray(design.floor_masses_kg, dtype=float)
    story_model = floor_frequency_response(masses, stories.stiffness_N_per_m, stories.damping_Ns_per_m, measured.freq_hz,
                                           stories.delay_s)
    plot_path = response_plot(measured, story_model, modal_response(modal, measured.freq_hz), band, out_dir / PLOT_FILE,
                              f"floor / base-mat acceleration from {len(runs)} run(s): measured, story model, modal fit")
    story_hz, story_zeta = stories.modes()
    record_path = write_record(out_dir, "identify structure", used, {
        "kind": "structure",
        "band_hz": list(band),
        "modes": [{
            "frequency_hz": float(modal.frequency_hz[r]), "frequency_se_hz": float(modal.frequency_se_hz[r]),
            "damping_ratio": float(modal.damping_ratio[r]), "damping_se": float(modal.damping_se[r]),
            "participation": [float(v) for v in modal.participation[r]],
            "story_model_frequency_hz": float(story_hz[r]), "story_model_damping_ratio": float(story_zeta[r]),
            "determined": modes[r].determined, "reason": modes[r].reason,
        } for r in range(len(modal.frequency_hz))],
        "modal_fit": {"delay_s": modal.delay_s, "rms_error_m_s2": modal.rms_error_m_s2,
                      "rms_signal_m_s2": modal.rms_signal_m_s2, "evaluations": modal.evaluations},
        "stories": {
            "damping_model": stories.damping_model,
            "floor_masses_kg": list(design.floor_masses_kg),
            "story_stiffness_N_per_m": [float(v) for v in stories.stiffness_N_per_m],
            "story_stiffness_se": [float(v) for v in stories.stiffness_se],
            "story_damping_Ns_per_m": [float(v) for v in stories.damping_Ns_per_m],
            "story_damping_se": [float(v) for v in stories.damping_se],
            "first_mode_damping_ratio": stories.first_mode_damping_ratio,
            "first_mode_damping_se": stories.first_mode_damping_se,
            "stiffness": {"determined": stiffness.determined, "reason": stiffness.reason},
            "damping": {"determined": damping.determined, "reason": damping.reason},
            "profile_story_stiffness_N_per_m": list(design.story_stiffness_N_per_m),
            "delay_s": stories.delay_s, "rms_error_m_s2": stories.rms_error_m_s2, "evaluations": stories.evaluations,
        },
        "method": "time-domain output error: models driven by the base mat's acceleration (the accelerometer above, the "
                  "velocity sensor's derivative below the crossover where their noise is equal; exact first-order-hold "
                  "discretisation), scipy.optimize.least_squares; modes by variable projection; standard errors the larger "
                  f"of the Jacobian's (inflated by the residuals' correlation time) and the spread of {BLOCKS} blocks of time "
                  "(block sandwich); the story stiffnesses' widened by twice the story model's largest relative miss of the "
                  "modal fit's frequencies, the first-mode damping ratio's by its difference from the modal fit's",
        "interval_95": f"value -/+ {t_factor_95():.4g} standard errors (Student's t, {BLOCKS - 1} degrees of freedom)",
        "files": {"overlay": overlay_path.name, "plot": plot_path.name},
    })
    return StructureIdentification(modal, stories, design, band, modes, stiffness, damping, used, overlay_path, record_path,
                                   plot_path)
