"""Checks every loaded record passes: enough samples, a uniform positive step, sane values."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.config.input_limits import MIN_RUN_SAMPLES
from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2, accel_factor

#: Fewest samples a record may have, and a run of it cover (harness/config/input_limits.py says why).
MIN_SAMPLES = MIN_RUN_SAMPLES
#: Largest |acceleration| a record may contain (g); larger values mean a unit mistake.
MAX_ABS_ACCEL_G = 10.0
#: Allowed deviation of a time stamp from the uniform grid, as a fraction of the step.
TIME_TOLERANCE = 0.01


def check_count(count: int, file: str | Path) -> None:
    """Refuse fewer than :data:`MIN_SAMPLES` samples."""
    if count < MIN_SAMPLES:
        raise RecordError(f"{file}: found {count} samples, expected at least {MIN_SAMPLES}")


def uniform_step(times_s: np.ndarray, linenos: np.ndarray, file: str | Path) -> float:
    """Check that time stamps advance by one fixed step and return it (s).

    Every step must be positive and within :data:`TIME_TOLERANCE` of the median
    step, and every stamp within that tolerance of the uniform grid from the
    first to the last stamp (which also catches a slow drift of the clock).

    Raises
    ------
    RecordError
        Naming the first line that breaks the rule.
    """
    steps = np.diff(times_s)
    nonpositive = np.flatnonzero(steps <= 0)
    if nonpositive.size:
        i = int(nonpositive[0])
        raise RecordError(
            f"{file}:{linenos[i + 1]}: time {times_s[i + 1]:g} s does not advance from {times_s[i]:g} s "
            f"(line {linenos[i]}); expected increasing times with a uniform step"
        )
    typical = float(np.median(steps))
    _refuse_step(np.flatnonzero(np.abs(steps - typical) > TIME_TOLERANCE * typical), times_s, linenos, typical, file)
    dt = float(times_s[-1] - times_s[0]) / (times_s.size - 1)
    off_grid = np.abs(times_s - (times_s[0] + dt * np.arange(times_s.size))) > TIME_TOLERANCE * dt
    _refuse_step(np.flatnonzero(off_grid[1:]), times_s, linenos, dt, file)
    return dt


def _refuse_step(bad: np.ndarray, times_s: np.ndarray, linenos: np.ndarray, dt: float, file: str | Path) -> None:
    if bad.size:
        i = int(bad[0])
        raise RecordError(
            f"{file}:{linenos[i + 1]}: non-uniform time step: {times_s[i]:g} s -> {times_s[i + 1]:g} s "
            f"is a step of {times_s[i + 1] - times_s[i]:g} s, expected the uniform step {dt:g} s; "
            "resample the record to a fixed step"
        )


def check_samples(values: np.ndarray, linenos: np.ndarray, file: str | Path, unit: str = "m/s^2") -> None:
    """Refuse too few samples and any |acceleration| beyond :data:`MAX_ABS_ACCEL_G`, naming the line.

    Parameters
    ----------
    values : ndarray
        Accelerations in ``unit``, as read from the file (checked before any conversion, so
        a value near the float limit such as 1e308 cannot overflow to infinity).
    linenos : ndarray
        File line of each value.
    file : str or Path
        For messages.
    unit : str
        Unit of ``values``: ``"g"``, ``"m/s^2"``, ``"cm/s^2"`` (or an alias).
    """
    check_count(values.size, file)
    to_g = accel_factor(unit) / G_M_S2  # at most 1, so the product below cannot overflow
    peak_g = np.abs(values) * to_g
    worst = int(np.argmax(peak_g))
    if peak_g[worst] > MAX_ABS_ACCEL_G:
        in_g = "" if unit == "g" else f" ({values[worst] * to_g:.4g} g)"
        raise RecordError(
            f"{file}:{linenos[worst]}: acceleration {values[worst]:.4g} {unit}{in_g} exceeds "
            f"{MAX_ABS_ACCEL_G:g} g, which no record reaches; check the unit (header or record.accel_unit)"
        )
