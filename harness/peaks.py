"""Peak responses people compare (SPEC 5), from run-folder columns.

The same function serves ``harness simulate``, dry runs and reports, so every table
of peaks in the project is computed one way.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np


def story_count(columns: Mapping[str, np.ndarray]) -> int:
    """Number of stories with a ``drift_j_m`` column."""
    n = 0
    while f"drift_{n + 1}_m" in columns:
        n += 1
    return n


def peak_abs(values: np.ndarray) -> float | None:
    """Largest finite |value|, or None if there is none."""
    values = np.asarray(values, dtype=float)
    finite = np.abs(values[np.isfinite(values)])
    return float(finite.max()) if finite.size else None


def _peak(values: np.ndarray) -> float:
    peak = peak_abs(values)
    return float("nan") if peak is None else peak


def peak_responses(columns: Mapping[str, np.ndarray], total_weight_N: float, force_column: str = "force_command_N") -> dict:
    """Peaks of one case.

    Parameters
    ----------
    columns : mapping
        Canonical columns (``drift_j_m``, ``floor_acceleration_j_m_s2``,
        ``sliding_displacement_m``, ``base_acceleration_m_s2``, a force column).
    total_weight_N : float
        ``mbar g`` (N), for the force as % of weight.
    force_column : str
        Column of the force applied to the base mat; absent means a passive case (0 %).

    Returns
    -------
    dict
        ``{"sliding_displacement_m", "base_acceleration_m_s2", "drift_m": [1..n],
        "floor_acceleration_m_s2": [1..n], "peak_force_pct_weight"}`` (SI).
    """
    n = story_count(columns)
    force = columns.get(force_column)
    return {
        "sliding_displacement_m": _peak(columns["sliding_displacement_m"]),
        "base_acceleration_m_s2": _peak(columns["base_acceleration_m_s2"]),
        "drift_m": [_peak(columns[f"drift_{j}_m"]) for j in range(1, n + 1)],
        "floor_acceleration_m_s2": [_peak(columns[f"floor_acceleration_{j}_m_s2"]) for j in range(1, n + 1)],
        "peak_force_pct_weight": 0.0 if force is None else 100.0 * _peak(force) / total_weight_N,
    }


def reduction_pct(passive: float | None, hybrid: float | None) -> float | None:
    """Percent reduction ``100 (passive - hybrid) / passive`` (SPEC 5); None if either is absent or passive is 0."""
    if passive is None or hybrid is None or passive == 0.0:
        return None
    return 100.0 * (passive - hybrid) / passive


def flatten(peaks: Mapping) -> dict[str, float]:
    """One scalar per entry, with story lists expanded (``drift_m[3]`` -> ``drift_3_m``)."""
    flat: dict[str, float] = {}
    for key, value in peaks.items():
        if isinstance(value, (list, tuple)):
            for j, item in enumerate(value, start=1):
                name = f"drift_{j}_m" if key == "drift_m" else f"floor_acceleration_{j}_m_s2"
                flat[name] = float(item)
        else:
            flat[key] = float(value)
    return flat
