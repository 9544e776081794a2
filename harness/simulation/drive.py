"""The table motion a run achieved, as the drive of the rig twin: ``harness simulate --rig-effects --drive-from RUN_DIR``.

A dry run's or run's folder records, tick by tick, the table's measured displacement ``x_0``
and velocity ``xdot_0`` (``signals.csv``). :func:`achieved_motion` turns them into a
:class:`~harness.motions.GroundMotion` on the run's own tick grid: its displacement and velocity
samples are the run's measured ones, as recorded, and its acceleration is the derivative of
that velocity (so the plant's table, which reads the three samples, moves through the run's
measured states at every tick). :func:`driven_profile` makes the twin's table a motion source
(``rig.table.model: motion_source``), so the twin's table follows that motion exactly instead of
answering the payload's reactions: the shaking the rig really produced, under a new controller.

Twin sample ``k`` is the run's tick ``k``: the rates must agree, and the run's first tick is
record time 0.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from harness.errors import HarnessError
from harness.motions import GroundMotion
from harness.profile import Profile
from harness.recording.layout import RunFolderError
from harness.signals.columns import TABLE_DISPLACEMENT, TABLE_VELOCITY, TIME

#: The kinds of run folder whose table motion a rig produced (the loop against a rig, virtual or real).
DRIVING_KINDS = ("dry-run", "run")
#: Least number of ticks a run must hold to drive the twin (two samples make one step).
MIN_TICKS = 2
#: Tolerance on a rate agreement (Hz): the rates are written as decimal numbers.
RATE_TOLERANCE_HZ = 1e-9


class DriveFromError(HarnessError, ValueError):
    """A ``--drive-from`` folder that cannot drive the twin: not a run folder, no table signals, another rate."""


def achieved_motion(
    run_dir: Path | str, rate_hz: float, duration_s: float | None = None, profile_name: str | None = None,
) -> GroundMotion:
    """The table motion the run in ``run_dir`` achieved, on its tick grid, to drive the rig twin.

    Parameters
    ----------
    run_dir : Path or str
        A run folder of ``harness dry-run`` or ``harness run``.
    rate_hz : float
        The twin's controller rate (Hz); the run's loop rate must be the same.
    duration_s : float, optional
        Keep the first ``duration_s`` seconds of the motion (s); None keeps all of it.
    profile_name : str, optional
        The name of the profile the twin runs; a note says so where the run's was another.

    Returns
    -------
    GroundMotion
        ``dt_s`` the run's period (s); ``displacement_m`` and ``velocity_m_s`` the run's measured
        ``table_displacement_m`` and ``table_velocity_m_s`` at its ticks (resampled linearly onto
        the whole-period grid where a real-time run missed periods), ``accel_m_s2`` the derivative of
        that velocity (m/s^2, :func:`numpy.gradient`); time scale 1; its notes say where it came from.

    Raises
    ------
    DriveFromError
        Saying what was found and what was expected: a folder that is not a run folder, a run of
        another kind, a run without the table signals, a run at another rate, too few ticks.
    """
    from harness.recording import load_run

    folder = Path(run_dir)
    try:
        run = load_run(folder)
    except RunFolderError as err:
        raise DriveFromError(f"--drive-from: {err} (the folder a `harness dry-run` or `harness run` outcome line "
                             "names)") from None
    _check_kind(folder, run.kind)
    if not run.has(TIME, TABLE_DISPLACEMENT, TABLE_VELOCITY):
        raise DriveFromError(f"--drive-from {folder}: found no {TABLE_DISPLACEMENT} and {TABLE_VELOCITY} in its "
                             f"signals.csv, expected the table's measured displacement and velocity per tick")
    run_rate_hz = _run_rate_hz(folder, run.metadata, run.profile)
    if abs(run_rate_hz - rate_hz) > RATE_TOLERANCE_HZ:
        raise DriveFromError(f"--drive-from {folder}: found a run at {run_rate_hz:g} Hz, expected the twin's rate "
                             f"{rate_hz:g} Hz (each twin sample takes the table's state at the run's tick of the same "
                             f"number): give --rate {run_rate_hz:g}, or a profile whose control.rate_hz is {run_rate_hz:g}")
    _check_finite(folder, run[TABLE_DISPLACEMENT], run[TABLE_VELOCITY])
    times, displacement, velocity = _on_tick_grid(folder, run[TIME], run[TABLE_DISPLACEMENT], run[TABLE_VELOCITY],
                                                  1.0 / rate_hz, duration_s)
    notes: tuple[str, ...] = (
        f"the table motion run {folder} achieved: its measured {TABLE_DISPLACEMENT} and {TABLE_VELOCITY} at "
        f"{rate_hz:g} Hz, acceleration their velocity's derivative; the twin's table follows it exactly "
        "(rig.table.model motion_source): the run's shaking, not the table's answer to this controller's forces",
    )
    run_profile = run.metadata.get("profile_name")
    if profile_name is not None and run_profile and run_profile != profile_name:
        notes += (f"the run was made with profile {run_profile!r}, this simulation runs {profile_name!r}: the shaking is "
                  "that run's, the structure and rig are this profile's",)
    return GroundMotion(
        name=f"achieved_{folder.name}", dt_s=1.0 / rate_hz, time_scale=1.0, t_s=times,
        accel_m_s2=np.gradient(velocity, 1.0 / rate_hz), velocity_m_s=velocity, displacement_m=displacement,
        notes=notes, source=str(folder),
    )


def driven_profile(profile: Profile) -> Profile:
    """``profile`` with a table that follows its drive exactly (``rig.table.model: motion_source``)."""
    table = dataclasses.replace(profile.rig.table, model="motion_source")
    return dataclasses.replace(profile, rig=dataclasses.replace(profile.rig, table=table))


def _check_kind(folder: Path, kind: str) -> None:
    """Refuse a folder whose table motion no rig produced (a simulation's case)."""
    if kind not in DRIVING_KINDS:
        raise DriveFromError(f"--drive-from {folder}: found a run folder of kind {kind!r}, expected one of "
                             f"{', '.join(DRIVING_KINDS)}: the table motion a rig achieved (a simulation's table is "
                             "its record)")


def _check_finite(folder: Path, displacement_m: np.ndarray, velocity_m_s: np.ndarray) -> None:
    """Refuse a table signal with a gap (a tick whose table reading was not a number)."""
    gaps = np.flatnonzero(~(np.isfinite(displacement_m) & np.isfinite(velocity_m_s)))
    if gaps.size:
        raise DriveFromError(f"--drive-from {folder}: found {gaps.size} ticks whose {TABLE_DISPLACEMENT} or "
                             f"{TABLE_VELOCITY} is not a number (the first: row {gaps[0] + 1}), expected a reading "
                             "at every tick")


def _run_rate_hz(folder: Path, metadata: dict, profile_data: dict) -> float:
    """The run's loop rate (Hz): its metadata's ``rate_hz``, else its profile's ``control.rate_hz``."""
    rate = metadata.get("rate_hz")
    if rate is None:
        rate = (profile_data.get("control") or {}).get("rate_hz")
    if not isinstance(rate, (int, float)) or not rate > 0:
        raise DriveFromError(f"--drive-from {folder}: found loop rate {rate!r} in its metadata.json and profile.yaml, "
                             "expected a positive number of Hz")
    return float(rate)


def _on_tick_grid(
    folder: Path, t_s: np.ndarray, displacement_m: np.ndarray, velocity_m_s: np.ndarray, period_s: float,
    duration_s: float | None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Time (s), displacement (m) and velocity (m/s) on the grid ``k * period_s`` from the run's first tick.

    A lockstep run's ticks are on the grid already (its samples are kept as they are); a real-time
    run's missed periods are filled by linear interpolation between the ticks either side.
    """
    if len(t_s) < MIN_TICKS or not np.all(np.isfinite(t_s)) or np.any(np.diff(t_s) <= 0.0):
        raise DriveFromError(f"--drive-from {folder}: found {len(t_s)} ticks, expected at least {MIN_TICKS} with "
                             "finite, increasing times t_s")
    span_s = float(t_s[-1] - t_s[0]) if duration_s is None else min(float(t_s[-1] - t_s[0]), duration_s)
    count = int(np.floor(span_s / period_s + 1e-9)) + 1
    times = np.arange(count) * period_s
    run_times = t_s - t_s[0]
    if len(run_times) >= count and np.allclose(run_times[:count], times, rtol=0.0, atol=1e-9):
        return times, displacement_m[:count].copy(), velocity_m_s[:count].copy()
    return times, np.interp(times, run_times, displacement_m), np.interp(times, run_times, velocity_m_s)
