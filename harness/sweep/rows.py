"""The row of one case in the results: its inputs, every peak (flattened), reductions, outcome and times.

Columns, by name:

- inputs: ``case_id`` (the key), ``case_index``, ``record``, ``pga_g``, ``controller``, one
  column per axis (``bearing.mu_max`` holds the SI value, ``scale:KEY`` the factor), ``sample``;
- peaks: ``passive.NAME`` and ``controlled.NAME`` for every name of :meth:`harness.signals.peaks.Peaks.flatten`
  (``sliding_displacement_m``, ``drift_3_m``, ``floor_acceleration_8_m_s2``, ``peak_force_pct_weight``
  ...), plus ``max_drift_m`` and ``max_floor_acceleration_m_s2`` over the stories;
- ``reduction_pct.NAME``: ``100 (passive - controlled) / passive`` (SPEC 5), NaN where undefined;
- ``outcome`` (``ok`` or ``failed``), ``error`` (the exception, empty when ok), ``wall_time_s``
  (the case in its worker, s), ``integration_s`` (of it, the time-stepping of its simulations, s),
  ``worker`` (host:pid).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from harness.signals.peaks import Peaks, reduction_pct

OK, FAILED = "ok", "failed"
OUTCOME, ERROR, WALL_TIME, INTEGRATION, WORKER = "outcome", "error", "wall_time_s", "integration_s", "worker"
PASSIVE, CONTROLLED, REDUCTION = "passive", "controlled", "reduction_pct"
MAX_DRIFT, MAX_FLOOR_ACCELERATION = "max_drift_m", "max_floor_acceleration_m_s2"
SLIDING = "sliding_displacement_m"
NAN = float("nan")


def _largest(values: tuple[float, ...]) -> float:
    finite = [v for v in values if math.isfinite(v)]
    return max(finite) if finite else NAN


def flat_peaks(peaks: Peaks) -> dict[str, float]:
    """:meth:`Peaks.flatten` with the largest drift and floor acceleration over the stories."""
    return {
        **peaks.flatten(),
        MAX_DRIFT: _largest(peaks.drift_m),
        MAX_FLOOR_ACCELERATION: _largest(peaks.floor_acceleration_m_s2),
    }


def peak_columns(peaks: Mapping[str, Peaks]) -> dict[str, float]:
    """Peak and reduction columns of a case's simulations (``passive``, and ``controlled`` if any)."""
    flat = {case: flat_peaks(value) for case, value in peaks.items()}
    columns = {f"{case}.{name}": value for case, values in flat.items() for name, value in values.items()}
    if PASSIVE in flat and CONTROLLED in flat:
        for name, passive in flat[PASSIVE].items():
            reduction = reduction_pct(passive, flat[CONTROLLED].get(name))
            columns[f"{REDUCTION}.{name}"] = NAN if reduction is None else reduction
    return columns


def outcome_columns(error: BaseException | None, wall_time_s: float, integration_s: float, worker: str) -> dict[str, Any]:
    """Outcome, error text and times of a case."""
    return {
        OUTCOME: OK if error is None else FAILED,
        ERROR: "" if error is None else f"{type(error).__name__}: {error}",
        WALL_TIME: wall_time_s,
        INTEGRATION: integration_s,
        WORKER: worker,
    }
