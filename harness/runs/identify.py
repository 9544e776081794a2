"""``harness identify actuator``: the actuator's command-to-force frequency response, measured on a rig.

Each condition is one control session, the same as a dry run's or a run's: the same loop,
the same supervisor with every interlock and limit active, a run folder with the whole
record. Only the controller differs: :class:`~harness.identification.excitation.ExcitationController`
plays the excitation from the start of RUNNING, and the supervisor shapes it as it shapes a
controller's force. The table is not started: it holds still (the virtual table at its
held position; a real table under its own controller, which the harness does not start).

- The virtual rig (default) runs in its own process on a private bus, as ``harness dry-run``
  starts it, in lockstep unless real time is asked for. The ``blocked`` condition sets the
  profile's ``rig.base_pinned``: the rig holds the base mat to the table.
- A rig already serving ``--interface``/``--channel`` (a real one) is run in real time; the
  lab clamps the base mat for the blocked condition, and the run only records it.

The input of the estimate is the supervised force command (``force_command_N``), the output
the load cell's force from ACTUATOR_STATUS (``force_measured_N``), both as the run folder
recorded them at the loop's ticks, so the response includes what the harness sees of the
loop's own delay (a loop period between a command and the status frame that shows it).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from harness import exit_codes
from harness.identification.actuator import FIT_PLOT_FILE, ActuatorIdentification, identify_actuator_fit
from harness.identification.actuator_fit import VELOCITY_FILE
from harness.identification.excitation import (
    ExcitationController,
    check_within_limits,
    excitation_signal,
)
from harness.identification.excitation_settings import Excitation
from harness.identification.frf import FrequencyResponse, h1_estimate, read_frf_csv, write_frf_csv
from harness.identification.outputs import OVERLAY_FILE, RECORD_FILE, claim_result_folder
from harness.identification.plot import bode_plot
from harness.loop.table_link import CanTableLink
from harness.model.warmup import warm_up
from harness.profile import Profile
from harness.recording import load_run
from harness.recording.metadata import environment, write_json_atomic
from harness.runs.dry_run import private_bus, serving_virtual_rig
from harness.runs.options import prepare_motion
from harness.runs.session import SessionResult, SessionSettings, run_session
from harness.signals.columns import FORCE_COMMAND, FORCE_MEASURED, SLIDING_VELOCITY, TIME

Condition = Literal["free", "blocked"]
CONDITIONS: tuple[Condition, ...] = ("free", "blocked")
#: The estimate's file per condition, in DIR.
FRF_FILES: dict[Condition, str] = {"free": "frf.csv", "blocked": "frf_blocked.csv"}
#: What the Bode plot's legend calls each condition.
CONDITION_LABELS: dict[Condition, str] = {
    "free": "free (structure on its bearings)", "blocked": "blocked (base mat held to the table)",
}
PLOT_FILE = "frf.png"
EXCITATION_FILE = "excitation.json"
#: Every result file DIR gets (:func:`~harness.identification.outputs.claim_result_folder`); the run folders
#: are new folders each time.
RESULT_FILES = (*FRF_FILES.values(), VELOCITY_FILE, PLOT_FILE, EXCITATION_FILE, OVERLAY_FILE, RECORD_FILE, FIT_PLOT_FILE)


@dataclass(frozen=True)
class IdentifyOptions:
    """The command line's choices for ``harness identify actuator``.

    Attributes
    ----------
    excitation : Excitation
    out_dir : Path
        DIR: the estimates, the plot, ``excitation.json`` and the run folders.
    conditions : tuple of {"free", "blocked"}
        Run one after the other, in this order.
    interface, channel : str, optional
        The bus (default: the profile's ``can`` section).
    external_rig : bool
        A rig (a real one, or a ``harness rig``) already serves the bus: start no virtual rig,
        run in real time.
    lockstep : bool
        The virtual rig advances one step per command (ignored with ``external_rig``).
    show_console : bool
    force : bool
        Replace the results of an earlier identification in DIR (else refused before anything moves).
    """

    excitation: Excitation
    out_dir: Path
    conditions: tuple[Condition, ...] = ("free",)
    interface: str | None = None
    channel: str | None = None
    external_rig: bool = False
    lockstep: bool = True
    show_console: bool = True
    force: bool = False

    @property
    def in_lockstep(self) -> bool:
        """True when the run is in lockstep: a virtual rig this command starts, asked to."""
        return self.lockstep and not self.external_rig


@dataclass
class ConditionResult:
    """One condition's session and, if the excitation ran to its end, its estimate."""

    condition: Condition
    session: SessionResult
    response: FrequencyResponse | None = None
    frf_path: Path | None = None


@dataclass
class IdentifyResult:
    """Every condition run, the plot and the excitation's record."""

    profile: Profile
    conditions: list[ConditionResult]
    excitation_path: Path
    plot_path: Path | None = None
    declined: Condition | None = None  # the condition the operator did not arm for (a real rig)
    fit: ActuatorIdentification | None = None  # the SPEC 7a model fitted to every response in DIR

    @property
    def exit_code(self) -> int:
        """The first condition's status that is not OK; ``INPUT_ERROR`` if the operator declined to arm."""
        for result in self.conditions:
            if result.session.exit_code != exit_codes.OK:
                return result.session.exit_code
        return exit_codes.INPUT_ERROR if self.declined else exit_codes.OK


def condition_profile(profile: Profile, condition: Condition, virtual_rig: bool) -> Profile:
    """The profile a condition runs on: on the virtual rig, ``rig.base_pinned`` is True exactly for ``blocked``.

    On a real rig the profile is unchanged: the lab clamps the base mat, the run records the condition.
    """
    if not virtual_rig:
        return profile
    return dataclasses.replace(profile, rig=dataclasses.replace(profile.rig, base_pinned=condition == "blocked"))


def excitation_span(t_s: np.ndarray, start_t_s: float, duration_s: float, rate_hz: float) -> np.ndarray:
    """Mask of the rows from the excitation's first sample to its last (loop times ``start .. start + duration``)."""
    half_period = 0.5 / rate_hz
    return (t_s >= start_t_s - half_period) & (t_s <= start_t_s + duration_s + half_period)


def on_tick_grid(t_s: np.ndarray, values: np.ndarray, rate_hz: float) -> np.ndarray:
    """``values`` at every tick from ``t_s[0]`` to ``t_s[-1]`` (linear between rows).

    A real-time loop that skipped a deadline has no row for it; lockstep has every one
    (the values then come back unchanged).
    """
    grid = t_s[0] + np.arange(int(round((t_s[-1] - t_s[0]) * rate_hz)) + 1) / rate_hz
    return np.interp(grid, t_s, values)


def estimate_from_run(
    run_path: Path, start_t_s: float, excitation: Excitation, rate_hz: float, output: str = FORCE_MEASURED,
) -> FrequencyResponse:
    """The H1 estimate from a finished run folder, force command to ``output``, within the excitation's band.

    Parameters
    ----------
    run_path : Path
    start_t_s : float
        Loop time the excitation started at (s): the session's ``record_start_t_s``.
    excitation : Excitation
    rate_hz : float
        The loop's rate (Hz).
    output : str
        The output's column: the load cell's force (default) or the sliding velocity (the free
        condition's ``T``, :data:`~harness.identification.actuator_fit.VELOCITY_FILE`).
    """
    run = load_run(run_path)
    t = run[TIME]
    span = excitation_span(t, start_t_s, excitation.duration_s, rate_hz)
    command = on_tick_grid(t[span], run[FORCE_COMMAND][span], rate_hz)
    measured = on_tick_grid(t[span], run[output][span], rate_hz)
    response = h1_estimate(command, measured, rate_hz, excitation.segment_samples(rate_hz))
    return response.within(excitation.low_hz, excitation.high_hz)


def _metadata(excitation: Excitation, condition: Condition, external_rig: bool) -> dict:
    """What a condition's ``metadata.json`` says of the identification (and the controller's name)."""
    held = "the lab's clamp (recorded, not set)" if external_rig else "rig.base_pinned"
    return {
        "controller": f"excitation ({excitation.signal})",
        "identification": {
            "kind": "actuator", "condition": condition, "excitation": excitation.as_dict(),
            "base_mat_held_by": held if condition == "blocked" else None, "table": "not started (held still)",
        },
    }


def _write_excitation_record(out_dir: Path, profile: Profile, options: IdentifyOptions, runs: dict) -> Path:
    """``excitation.json``: the options, the profile, the software, and per condition of this run its run folder and outcome."""
    path = out_dir / EXCITATION_FILE
    env = environment()
    write_json_atomic(path, {
        "command": "identify actuator",
        "profile": profile.name, "profile_file": profile.source_path, "variant": profile.variant or None,
        "overlay": profile.overlay_record(),
        "excitation": options.excitation.as_dict(),
        "rate_hz": profile.control.rate_hz,
        "rig": "external (--interface/--channel)" if options.external_rig else "virtual",
        "lockstep": options.in_lockstep,
        "input": FORCE_COMMAND, "output": FORCE_MEASURED, "estimator": "H1 = Pxy / Pxx, Welch, Hann, 50 % overlap",
        "harness_version": env["packages"].get("shaketable-harness"), "git_commit": env["git_commit"],
        "conditions": dict(runs),
    })
    return path


def plot_conditions(out_dir: Path, title: str) -> Path | None:
    """Draw every condition whose estimate is in ``out_dir`` on one Bode plot (``frf.png``); None if there is none."""
    present = [condition for condition in CONDITIONS if (out_dir / FRF_FILES[condition]).is_file()]
    responses = {CONDITION_LABELS[condition]: read_frf_csv(out_dir / FRF_FILES[condition]) for condition in present}
    if not responses:
        return None
    return bode_plot(responses, out_dir / PLOT_FILE, title)


def run_condition(
    profile: Profile, condition: Condition, options: IdentifyOptions, samples: np.ndarray, console, on_host_timing,
) -> SessionResult:
    """One condition's session on the virtual rig or the external one."""
    rate_hz = profile.control.rate_hz
    controller = ExcitationController(samples, rate_hz)
    virtual = not options.external_rig
    profile = condition_profile(profile, condition, virtual)
    can = private_bus(profile.can_settings(options.interface, options.channel), options.external_rig, f"-{condition}")
    settings = SessionSettings(
        kind="dry-run" if virtual else "run", can=can, duration_s=options.excitation.duration_s, log_dir=options.out_dir,
        lockstep=options.in_lockstep, show_console=options.show_console,
        metadata=_metadata(options.excitation, condition, options.external_rig),
    )
    if virtual:
        with serving_virtual_rig(profile, can, options.in_lockstep, prepare_motion(profile)) as coordinator:
            settings.peer_pids = coordinator.peer_pids  # the private channel admits only the rig process
            return run_session(
                profile, settings, controller=controller, on_start=controller.start, on_link=coordinator.on_link,
                make_lockstep=coordinator.lockstep_wait if options.in_lockstep else None,
                stop_table=coordinator.table.stop, on_host_timing=on_host_timing, console=console,
            )
    # A real table is not started; a trip still sends its stop (``stop_table``) where the table is on the bus.
    table = CanTableLink(lockstep=False) if profile.table is None or profile.table.link == "can" else None
    return run_session(
        profile, settings, controller=controller, on_start=controller.start,
        on_link=table.attach if table is not None else None, stop_table=table.stop if table is not None else None,
        on_host_timing=on_host_timing, console=console,
    )


def excitation_safety(profile: Profile) -> Profile:
    """``profile`` for a run whose command is an identification excitation: ``force_oscillation`` indicates.

    The excitation commands force up to the top of its band (30 Hz by default, 2 kN) on purpose: it
    is the run's controller, so the check of force above the controller's band has no band to stand
    on, and would stop the sweep as it nears its top (docs/SAFETY.md, "Sustained oscillation"). Its
    amplitude and rate are bounded before anything moves (``check_within_limits``), and every other
    check stays as the profile says. The check still records what it sees (``indicate``).
    """
    force = dataclasses.replace(profile.safety.force, oscillation_action="indicate")
    return dataclasses.replace(profile, safety=dataclasses.replace(profile.safety, force=force))


def identify_actuator(
    profile: Profile,
    options: IdentifyOptions,
    console=None,
    on_host_timing=None,
    confirm: Callable[[Condition], bool] | None = None,
) -> IdentifyResult:
    """Measure the actuator's frequency response in each condition; see the module docstring.

    Parameters
    ----------
    profile : Profile
        Loaded, with ``--set`` and ``--variant`` folded in.
    options : IdentifyOptions
    console : rich Console, optional
    on_host_timing : callable, optional
        The pre-flight timing check's report (real time only).
    confirm : callable, optional
        ``confirm(condition) -> bool``, asked before each condition on an external rig (the
        operator clamps or frees the base mat first); False stops before arming.

    Raises
    ------
    ExcitationError
        An excitation beyond ``safety.force``, too short for its resolution or with too few of its
        frequencies in the band, before anything moves.
    RunFolderError
        A DIR holding an earlier identification's results without ``options.force``, before anything moves.
    """
    warm_up()  # compile the kernels now, never inside the loop or the rig
    excitation = options.excitation
    rate_hz = profile.control.rate_hz
    samples = excitation_signal(excitation, rate_hz)
    measured_rate_hz = None if options.in_lockstep else profile.can.status_rate_hz
    check_within_limits(excitation, samples, rate_hz, profile.safety.force, measured_rate_hz)
    profile = excitation_safety(profile)
    out_dir = Path(options.out_dir)
    claim_result_folder(out_dir, RESULT_FILES, options.force)  # the fit then reads this run's responses only
    out_dir.mkdir(parents=True, exist_ok=True)
    runs: dict = {}
    excitation_path = _write_excitation_record(out_dir, profile, options, runs)
    result = IdentifyResult(profile, [], excitation_path)
    for condition in options.conditions:
        if options.external_rig and confirm is not None and not confirm(condition):
            result.declined = condition
            break
        session = run_condition(profile, condition, options, samples, console, on_host_timing)
        done = ConditionResult(condition, session)
        result.conditions.append(done)
        start = session.loop.record_start_t_s
        entry = {"run_folder": session.run_path.name, "outcome": session.outcome, "trip_reason": session.trip_reason or None,
                 "excitation": excitation.as_dict(), "frf_file": None}
        if session.outcome == "completed" and session.record_complete and start is not None:
            done.response = estimate_from_run(session.run_path, start, excitation, rate_hz)
            done.frf_path = write_frf_csv(out_dir / FRF_FILES[condition], done.response)
            entry["frf_file"] = done.frf_path.name
            if condition == "free":  # what moved the piston: the fit's T (harness/identification/actuator_fit.py)
                velocity = estimate_from_run(session.run_path, start, excitation, rate_hz, SLIDING_VELOCITY)
                entry["velocity_file"] = write_frf_csv(out_dir / VELOCITY_FILE, velocity).name
        runs[condition] = entry
        _write_excitation_record(out_dir, profile, options, runs)
        if done.response is None:
            break  # a trip or a stop: the next condition does not run
    if any(done.response is not None for done in result.conditions):
        result.fit = identify_actuator_fit(out_dir, profile, options.in_lockstep)
    result.plot_path = plot_conditions(out_dir, f"{profile.name}: actuator force command to load cell, H1 ({excitation.signal}, "
                                                f"{excitation.amplitude_N:g} N, {excitation.low_hz:g}-{excitation.high_hz:g} Hz)")
    return result


def frequency_where(response: FrequencyResponse, values: np.ndarray, level: float) -> float:
    """The first frequency (Hz) at which ``values`` falls to ``level`` or below (linear between bins); NaN if never."""
    below = np.nonzero(values <= level)[0]
    if len(below) == 0:
        return math.nan
    k = int(below[0])
    if k == 0:
        return float(response.freq_hz[0])
    f0, f1, v0, v1 = response.freq_hz[k - 1], response.freq_hz[k], values[k - 1], values[k]
    return float(f0 + (level - v0) * (f1 - f0) / (v1 - v0)) if v1 != v0 else float(f1)


def summary(response: FrequencyResponse) -> str:
    """One line: the gain at the lowest frequency, the -3 dB and -90 deg frequencies, the coherence."""

    def at(frequency_hz: float) -> str:
        return f"{frequency_hz:.3g} Hz" if math.isfinite(frequency_hz) else "not within the band"

    gain = float(response.magnitude[0])
    return (
        f"|H| {gain:.3f} N/N at {response.freq_hz[0]:.3g} Hz; -3 dB at "
        f"{at(frequency_where(response, response.magnitude, gain / math.sqrt(2.0)))}; phase -90 deg at "
        f"{at(frequency_where(response, response.phase_deg, -90.0))}; coherence median "
        f"{float(np.median(response.coherence)):.3f}, lowest {float(response.coherence.min()):.3f}"
    )
