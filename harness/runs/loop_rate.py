"""The loop-rate checks every run's loop passes, whatever calls it: the command line, a benchmark, a test.

:func:`check_loop_rate` refuses a loop rate at which a run could not arm or hold its loop, and
for a virtual rig a rate it cannot step. The commands call it first, naming
``--rate`` where it set the rate; :func:`harness.runs.session.run_session` (every loop: dry run,
run, identification) and :func:`harness.runs.dry_run.serving_virtual_rig` (every virtual rig) call
it again before anything starts, so a path that skips the command line cannot skip them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from harness.config import input_limits as limits
from harness.errors import ProfileError

if TYPE_CHECKING:
    from harness.profile import Profile


def given_as(option: str, given: bool, profile: Profile, key: str) -> tuple[str, str | None]:
    """(source, key path) of a :class:`ProfileError` about a value: the option if it was given, else the profile's key.

    Parameters
    ----------
    option : str
        The command-line option, e.g. ``--rate``.
    given : bool
        True if the option set the value.
    profile : Profile
        The profile whose file and key are named otherwise.
    key : str
        The profile's key path, e.g. ``control.rate_hz``.
    """
    return (option, None) if given else (profile.source_path, key)


def check_loop_rate(profile: Profile, rate_given: bool, *, virtual_rig: bool) -> None:
    """Refuse a loop rate at which a run or a dry run could not arm, or not hold the loop, before anything starts.

    The range of ``--rate`` says what the parser accepts; a loop also needs its period short
    enough for what the profile's safety settings expect of it (harness/config/input_limits.py
    derives each):

    - :data:`~harness.config.input_limits.STALL_BUDGET_PERIODS` periods within ``safety.run.max_stall_s``;
    - :data:`~harness.config.input_limits.WATCHDOG_PERIODS` periods within ``rig.drive.watchdog_timeout_s``;
    - the sensor frames' period (once per tick, or ``can.sensor_rate_hz`` where the profile sets one) within
      ``safety.sensors.max_sensor_age_s``: a sample is up to a period old when a tick reads it;
    - for the virtual rig of a dry run, a whole number of ``rig.physics_substep_s`` per period.

    A lockstep dry run is held to the same bounds: it rehearses the real-time loop at the
    same rate, so a rate that loop cannot hold would rehearse nothing (and far below them the
    rig's step of period / ``physics_substep_s`` sub-steps outgrows ``loop.lockstep_timeout_s``:
    ``--rate 0.001`` asked for two million a step, and the dry run could not arm).

    Parameters
    ----------
    profile : Profile
        Resolved: ``--rate`` already folded in (``resolve_profile``).
    rate_given : bool
        True if ``--rate`` set the rate (the message then names it; else ``control.rate_hz``).
    virtual_rig : bool
        True for a dry run.

    Raises
    ------
    ProfileError
        Naming ``--rate`` (or ``control.rate_hz``, or ``can.sensor_rate_hz``), the rate found, the least rate accepted and why.
    """
    rate_hz = profile.control.rate_hz
    period_s = 1.0 / rate_hz
    source, key = given_as("--rate", rate_given, profile, "control.rate_hz")
    bounds = (
        ("safety.run.max_stall_s", profile.safety.run.max_stall_s, limits.STALL_BUDGET_PERIODS,
         "the shortest stall, one missed deadline, is two periods between ticks"),
        ("rig.drive.watchdog_timeout_s", profile.rig.drive.watchdog_timeout_s, limits.WATCHDOG_PERIODS,
         "the drive disables itself when no command reaches it for that long"),
    )
    too_slow = [(name, value, periods, why) for name, value, periods, why in bounds if period_s * periods > value * (1 + 1e-9)]
    if too_slow:
        least_hz = max(periods / value for _, value, periods, _ in bounds)
        reasons = "; ".join(f"{periods:g} periods must fit in {name} ({value * 1e3:g} ms: {why})"
                            for name, value, periods, why in too_slow)
        raise ProfileError(
            f"found {rate_hz:g} Hz (a period of {period_s * 1e3:g} ms), expected at least {least_hz:g} Hz: {reasons} "
            "(docs/SAFETY.md, Stall budget; lockstep too is held to this, as it rehearses the real-time loop)", source, key,
        )
    sensor_rate_hz = profile.can.sensor_frame_rate_hz
    sensor_period_s = 1.0 / sensor_rate_hz
    age_s = profile.safety.sensors.max_sensor_age_s
    if sensor_period_s > age_s * (1 + 1e-9):
        sensor_source, sensor_key = (source, key) if profile.can.sensor_rate_hz is None else (
            profile.source_path, "can.sensor_rate_hz")
        raise ProfileError(
            f"found sensor frames every {sensor_period_s * 1e3:g} ms ({sensor_rate_hz:g} Hz), expected at "
            f"least {1.0 / age_s:g} Hz: a sample is up to a period old when a tick reads it, and "
            f"safety.sensors.max_sensor_age_s is {age_s * 1e3:g} ms", sensor_source, sensor_key,
        )
    if virtual_rig:
        _check_rig_substeps(profile, period_s, source, key)


def _check_rig_substeps(profile: Profile, period_s: float, source: str, key: str | None) -> None:
    """The virtual rig steps whole physics sub-steps per loop period (else its process exits once the run began)."""
    substep_s = profile.rig.physics_substep_s
    steps = round(period_s / substep_s)
    if steps >= 1 and abs(steps * substep_s - period_s) <= 1e-9 * period_s:
        return
    fewer = max(1, math.floor(period_s / substep_s))
    nearby = sorted({1.0 / (n * substep_s) for n in (fewer, fewer + 1)}, reverse=True)
    raise ProfileError(
        f"found {profile.control.rate_hz:g} Hz: its period of {period_s * 1e3:g} ms is not a whole number of the virtual "
        f"rig's physics sub-steps (rig.physics_substep_s = {substep_s * 1e3:g} ms); expected a rate such as "
        + " or ".join(f"{rate:g} Hz" for rate in nearby), source, key,
    )
