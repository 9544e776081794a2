"""``harness identify actuator``'s fit: the measured responses in DIR in, ``identified.yaml``,
``identification.json`` and ``actuator_fit.png`` out.

Reads what the measurement wrote (``frf_blocked.csv``, ``frf.csv`` with ``frf_velocity.csv``,
``excitation.json``), fits the SPEC 7a model (:mod:`.actuator_fit`) and writes the files every
identification writes (:mod:`.outputs`). The overlay sets the profile's own ``rig.actuator``
keys, because the identified rig becomes the model of ``simulate --rig-effects`` and of the
actuator-aware designs:

- ``rig.actuator.hydraulics.force_loop_bandwidth_hz``: ``w_f``;
- ``rig.actuator.hydraulics.cylinder.valve_bandwidth_hz``: ``w_v / 2 pi``;
- ``rig.actuator.hydraulics.cylinder.bulk_modulus_Pa``: ``k_h V_t / (4 A^2)`` (free condition);
- ``rig.actuator.delay_s``: ``tau`` less the loop's own share (when the band determines it).

Which values the band determines: the delay only when the band reaches half the valve's
frequency (below, the valve's phase and a delay trade one for the other, and the delay is held
at the loop's value ``rig.actuator.delay_s`` + half a loop period, + half a status period in
real time); ``zeta_v`` and the leakage never (:data:`.actuator_fit.HELD`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import numpy as np

from harness.identification.actuator_fit import (
    FITTED,
    HELD,
    VELOCITY_FILE,
    ActuatorFit,
    ActuatorParameters,
    CommandPath,
    Measured,
    blocked_response,
    bulk_modulus_Pa,
    complex_response,
    fit_actuator,
    free_response,
)
from harness.identification.frf import FrequencyResponse, read_frf_csv
from harness.identification.outputs import OverlayValue, write_overlay, write_record
from harness.identification.run_signals import IdentificationError, run_used
from harness.profile import Profile
from harness.recording import load_run
from harness.report.figure import figure, style

FIT_PLOT_FILE = "actuator_fit.png"
#: The delay is fitted when the band's top reaches this share of the valve's natural frequency.
DELAY_BAND_SHARE = 0.5
#: Files of the measurement, per condition (as harness/runs/identify.py writes them).
BLOCKED_FILE, FREE_FILE = "frf_blocked.csv", "frf.csv"


@dataclass(frozen=True)
class ActuatorIdentification:
    """The fit and the files written."""

    fit: ActuatorFit
    overlay_path: Path
    record_path: Path
    plot_path: Path
    held: dict[str, str]


def loop_delay_s(profile: Profile, lockstep: bool) -> float:
    """The delay the loop itself puts between a command and the recorded load cell (s), less the actuator's transport.

    Half a loop period (the command is held over a tick), and in real time half a status period
    (the load cell's frame is on average that old when the loop reads it).
    """
    delay = 0.5 / profile.control.rate_hz
    if not lockstep:
        delay += 0.5 / profile.can.status_rate_hz
    return delay


def command_path(excitation: dict, rate_hz: float, profile: Profile) -> CommandPath:
    """The loop's hold, and a chirp's amplitude with the servo controller's rate limit (:class:`.actuator_fit.CommandPath`).

    Only a chirp is, at each moment, the sinusoid the orifice's describing function and the rate
    limit's lag are taken for: another signal's amplitude is given as 0.
    """
    amplitude_N = float(excitation["amplitude_N"]) if excitation.get("signal") == "chirp" else 0.0
    return CommandPath(amplitude_N, 1.0 / rate_hz, profile.rig.physics_substep_s, profile.rig.actuator.force_rate_limit_N_per_s)


def read_measured(out_dir: Path, segments: float, command: CommandPath | None = None) -> Measured:
    """The responses in ``out_dir``; ``command`` a chirp's (:attr:`.Measured.command`).

    Raises
    ------
    IdentificationError
        When neither condition's response is there, or the free one lacks its sliding-velocity response.
    """
    blocked = read_frf_csv(out_dir / BLOCKED_FILE) if (out_dir / BLOCKED_FILE).is_file() else None
    free = velocity = None
    if (out_dir / FREE_FILE).is_file():
        if not (out_dir / VELOCITY_FILE).is_file():
            raise IdentificationError(f"{out_dir}: found {FREE_FILE} without {VELOCITY_FILE}; expected both (measure the free "
                             "condition again with this version)")
        free, velocity = read_frf_csv(out_dir / FREE_FILE), read_frf_csv(out_dir / VELOCITY_FILE)
    if blocked is None and free is None:
        raise IdentificationError(f"{out_dir}: found no {BLOCKED_FILE} or {FREE_FILE}; expected a measured condition to fit")
    return Measured(blocked, free, velocity, segments, command)


def identify_actuator_fit(out_dir: Path, profile: Profile, lockstep: bool) -> ActuatorIdentification:
    """Fit the responses in ``out_dir`` and write ``identified.yaml``, ``identification.json`` and the plot.

    Parameters
    ----------
    out_dir : Path
        DIR of ``harness identify actuator``, with ``excitation.json``.
    profile : Profile
        The profile the excitation ran on: its actuator is the first guess and gives the held values.
    lockstep : bool
        The measurement ran in lockstep (the loop's share of the delay).
    """
    record = json.loads((out_dir / "excitation.json").read_text(encoding="utf-8"))
    excitation = record["excitation"]
    rate_hz = float(record["rate_hz"])
    segment_s = 1.0 / float(excitation["resolution_hz"])
    segments = max(1.0, 2.0 * float(excitation["duration_s"]) / segment_s - 1.0)  # Welch, 50 % overlap
    measured = read_measured(out_dir, segments, command_path(excitation, rate_hz, profile))
    hydraulics = profile.rig.actuator.hydraulics
    loop_s = loop_delay_s(profile, lockstep)
    start = ActuatorParameters.from_config(
        hydraulics, profile.rig.actuator.delay_s + loop_s, profile.rig.sensors.velocity.delay_s,
        profile.rig.physics_substep_s,
    )
    high_hz = float(excitation["band_hz"][1])
    held = dict(HELD)
    hold: tuple[str, ...] = ()
    if high_hz < DELAY_BAND_SHARE * hydraulics.cylinder.valve_bandwidth_hz:
        hold = ("delay_s",)
        held["delay_s"] = (
            f"the band stops at {high_hz:g} Hz, below half the valve's {hydraulics.cylinder.valve_bandwidth_hz:g} Hz: "
            f"the valve's phase and a delay trade one for the other; held at rig.actuator.delay_s + the loop's "
            f"{loop_s * 1e3:.2g} ms (widen the band, e.g. --band-hz 1,80 --amplitude-N 700, to fit it)"
        )
    fit = fit_actuator(measured, start, hold)
    sections = _overlay_sections(fit, hydraulics, loop_s)
    header = [
        "The control actuator identified by `harness identify actuator` (SPEC 7a model fitted to the measured",
        "frequency responses; identification.json has every value, its standard error and the fit's error).",
        f"Merge it over the profile with --overlay {out_dir / 'identified.yaml'}.",
    ]
    overlay = write_overlay(out_dir, header, sections)
    plot = fit_plot(measured, fit, out_dir / FIT_PLOT_FILE, f"{profile.name}: actuator, measured and fitted (SPEC 7a)")
    content = {
        "kind": "actuator", "profile": profile.name, "lockstep": lockstep, "rate_hz": rate_hz, "excitation": excitation,
        "model": "SPEC 7a: F = [exp(-s tau) R N w_f G_v u_c - k_h (1 - alpha N G_v H) xdot_b] / (s + c + N w_f G_v)",
        "large_signal": _large_signal_json(measured.command, fit.parameters),
        "parameters": {name: {"value": getattr(fit.parameters, name), "standard_error": fit.standard_errors.get(name),
                              "fitted": name in fit.fitted, "determined": fit.determined(name)} for name in FITTED},
        "held": {name: {"value": getattr(fit.parameters, name, None), "why": why} for name, why in held.items()},
        "valve_zeta_correlation": fit.valve_correlation,
        "bulk_modulus_Pa": bulk_modulus_Pa(fit.parameters.hydraulic_stiffness_N_per_m, hydraulics)
        if "hydraulic_stiffness_N_per_m" in fit.fitted else None,
        "velocity_feedback_Ns_per_m": _velocity_feedback_json(fit, profile),
        "fit_error": [error.as_dict() for error in fit.errors],
        "files": {"overlay": overlay.name, "plot": plot.name},
    }
    runs = [run_used(load_run(out_dir / entry["run_folder"])) for entry in record.get("conditions", {}).values()
            if entry.get("frf_file") and (out_dir / entry["run_folder"]).is_dir()]
    record_path = write_record(out_dir, "identify actuator", runs, content)
    return ActuatorIdentification(fit, overlay, record_path, plot, held)


def _large_signal_json(command: CommandPath | None, p: ActuatorParameters) -> dict[str, object]:
    """What the model's ``N`` (the orifice's describing function) and ``R`` (the hold and rate limit) were taken from."""
    if command is None:
        return {"orifice": "none (small signal)", "command": "continuous"}
    chirp = command.amplitude_N > 0.0
    return {
        "orifice": f"describing function at the chirp's {command.amplitude_N:g} N over A p_s = {p.force_capacity_N:.5g} N"
                   if chirp else "none (small signal: the excitation is no sinusoid)",
        "command": f"held over the loop's {command.tick_s * 1e3:g} ms"
                   + (f", rate limited at {command.rate_limit_N_per_s:g} N/s per {command.sample_s * 1e3:g} ms sample"
                      if chirp and math.isfinite(command.rate_limit_N_per_s) else ""),
    }


def _quality(fit: ActuatorFit, name: str, unit_scale: float = 1.0) -> str:
    error = fit.standard_errors[name] * unit_scale
    verdict = "determined" if fit.determined(name) else "NOT determined by the data"
    return f"+/- {error:.2g} (1 SE), {verdict}; fit error " + "; ".join(
        f"{e.condition} {e.magnitude_rms_pct:.1f} % / {e.phase_rms_deg:.1f} deg rms" for e in fit.errors
    )


def _overlay_sections(fit: ActuatorFit, hydraulics, loop_s: float) -> dict[str, list[OverlayValue]]:
    """The overlay's keys: only the values the fit determined."""
    p = fit.parameters
    actuator: list[OverlayValue] = []
    loop: list[OverlayValue] = []
    cylinder: list[OverlayValue] = []
    if fit.determined("delay_s"):
        note = f"tau {p.delay_s * 1e3:.3g} ms less the loop's {loop_s * 1e3:.2g} ms; {_quality(fit, 'delay_s')}"
        actuator.append(OverlayValue("delay_s", max(p.delay_s - loop_s, 0.0), note))
    if fit.determined("force_loop_bandwidth_hz"):
        loop.append(OverlayValue("force_loop_bandwidth_hz", p.force_loop_bandwidth_hz, _quality(fit, "force_loop_bandwidth_hz")))
    if fit.determined("valve_bandwidth_hz"):
        cylinder.append(OverlayValue("valve_bandwidth_hz", p.valve_bandwidth_hz, _quality(fit, "valve_bandwidth_hz")))
    if fit.determined("hydraulic_stiffness_N_per_m"):
        beta = bulk_modulus_Pa(p.hydraulic_stiffness_N_per_m, hydraulics)
        ratio = beta / p.hydraulic_stiffness_N_per_m
        cylinder.append(OverlayValue(
            "bulk_modulus_Pa", beta,
            f"k_h {p.hydraulic_stiffness_N_per_m:.4g} N/m with the profile's A and V_t; "
            + _quality(fit, "hydraulic_stiffness_N_per_m", ratio),
        ))
    return {"rig.actuator": actuator, "rig.actuator.hydraulics": loop, "rig.actuator.hydraulics.cylinder": cylinder}


def fitted_responses(measured: Measured, fit: ActuatorFit) -> dict[str, tuple[FrequencyResponse, np.ndarray]]:
    """Per condition: the measured response and the fitted model on its bins (complex)."""
    out: dict[str, tuple[FrequencyResponse, np.ndarray]] = {}
    if measured.blocked is not None:
        out["blocked"] = (measured.blocked, blocked_response(fit.parameters, measured.blocked.freq_hz, measured.command))
    if measured.free is not None and measured.velocity is not None:
        model = free_response(fit.parameters, measured.free.freq_hz, complex_response(measured.velocity), measured.command)
        out["free"] = (measured.free, model)
    return out


def fit_plot(measured: Measured, fit: ActuatorFit, path: Path, title: str) -> Path:
    """Magnitude (dB) and phase (deg) of each condition, measured (solid) against fitted (dashed)."""
    colours = {"blocked": "#d62728", "free": "#1f77b4"}
    with matplotlib.rc_context(style()):
        fig = figure(700)
        magnitude, phase = fig.subplots(2, 1, sharex=True)
        for condition, (response, model) in fitted_responses(measured, fit).items():
            colour = colours[condition]
            magnitude.semilogx(response.freq_hz, response.magnitude_db, color=colour, label=f"{condition}, measured")
            magnitude.semilogx(response.freq_hz, 20 * np.log10(np.abs(model)), color=colour, linestyle="--",
                               label=f"{condition}, fitted")
            model_phase = response.phase_deg + np.degrees(np.angle(model * np.exp(-1j * np.radians(response.phase_deg))))
            phase.semilogx(response.freq_hz, response.phase_deg, color=colour)
            phase.semilogx(response.freq_hz, model_phase, color=colour, linestyle="--")
        magnitude.set_ylabel("magnitude (dB, N/N)")
        phase.set_ylabel("phase (deg)")
        phase.set_xlabel("frequency (Hz)")
        for ax in (magnitude, phase):
            ax.grid(True, which="both", alpha=0.3)
        magnitude.legend(loc="lower left")
        magnitude.set_title(title)
        fig.savefig(path, format="png")
    return path


def _velocity_feedback_json(fit: ActuatorFit, profile: Profile) -> dict[str, float] | None:
    """``c_eff`` with its standard error, and the controller's ``m_b p1`` it is judged against (README, commissioning)."""
    found = fit.velocity_feedback()
    if found is None:
        return None
    return {"value": found[0], "standard_error": found[1], "controller_damping_Ns_per_m": controller_damping_Ns_per_m(profile)}


def controller_damping_Ns_per_m(profile: Profile) -> float:
    """``m_b p1`` (N s/m) of the profile's phi design: the damping the controller itself puts on the base mat."""
    design = profile.control.designs.get("phi")
    p1 = getattr(design, "p1_per_s", math.nan) if design is not None else math.nan
    return profile.structure.base_mass_kg * p1


def summary_lines(result: ActuatorIdentification) -> list[str]:
    """What the command prints: each fitted value with its error, the fit's error, what was held."""
    fit = result.fit
    p = fit.parameters
    lines = []
    for name in fit.fitted:
        value, standard_error = getattr(p, name), fit.standard_errors[name]
        state = "" if fit.determined(name) else "  (not determined: left out of the overlay)"
        lines.append(f"{name} = {value:.5g} +/- {standard_error:.2g}{state}")
    for error in fit.errors:
        lines.append(f"fit error {error.condition}: magnitude {error.magnitude_rms_pct:.2f} % rms "
                     f"({error.magnitude_max_pct:.2f} % max), phase {error.phase_rms_deg:.2f} deg rms "
                     f"({error.phase_max_deg:.2f} deg max)")
    found = fit.velocity_feedback()
    if found is not None:
        lines.append(f"effective velocity feedback c_eff = (1 - alpha) k_h / w_f = {found[0]:.4g} +/- {found[1]:.2g} N s/m "
                     f"(1 SE; the servo controller's feed-forward alpha = {p.feedforward_gain:.3g})")
    lines.append("held: " + ", ".join(result.held))
    if not math.isnan(fit.valve_correlation):
        lines.append(f"correlation of valve frequency and damping if both were freed: {fit.valve_correlation:.3f}")
    return lines
