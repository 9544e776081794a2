"""How well the actuator gave the controller's force: the force-tracking error of a case.

The load cell's force at sample ``k + 1`` is the actuator's answer to what the controller
asked for at sample ``k`` (the command is held over the period). The error compared between
compensation methods (``control.compensation``, harness/control/compensation.py) is the load
cell's force against the controller's force ``force_raw_N`` of the sample before; the error
against the command actually sent (``force_command_N``, which holds a compensator's flow term)
is the actuator's own. Both are NaN when a column is absent or holds fewer than two samples.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from harness.signals.columns import FORCE_COMMAND, FORCE_MEASURED, FORCE_RAW


def force_tracking_rms_N(columns: Mapping[str, np.ndarray], asked: str = FORCE_RAW) -> float:
    """RMS (N) of ``force_measured_N[k + 1] - columns[asked][k]`` over the finite samples.

    Parameters
    ----------
    columns : mapping of str to ndarray
        A case's columns (the rig twin's, a run folder's signals).
    asked : str
        ``force_raw_N`` (the controller's force, default) or ``force_command_N`` (the command sent).
    """
    if asked not in (FORCE_RAW, FORCE_COMMAND):
        raise ValueError(f"asked must be {FORCE_RAW!r} or {FORCE_COMMAND!r}, found {asked!r}")
    if FORCE_MEASURED not in columns or asked not in columns:
        return math.nan
    measured, wanted = np.asarray(columns[FORCE_MEASURED], dtype=float), np.asarray(columns[asked], dtype=float)
    error = measured[1:] - wanted[:-1]
    error = error[np.isfinite(error)]
    return float(np.sqrt(np.mean(np.square(error)))) if error.size else math.nan
