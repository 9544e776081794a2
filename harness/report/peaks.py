"""Peak responses of one run: the numbers SPEC section 5 says people compare.

Peak |drift| of each story, peak |absolute acceleration| of each floor and of the
base mat, peak |sliding displacement| ``x_b``, and peak |u| as a percentage of the
total weight ``mbar*g`` (``metadata["total_weight_N"]``). Also the table motion
actually reproduced (PGA, PGV, PGD), so two runs of "the same record" can be seen
to be fed the same input. Values are held in SI; each :class:`Quantity` says how to
show it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.peaks import peak_abs, reduction_pct

from harness.record.columns import drift, floor_acceleration
from harness.record.reader import RunData

#: The control force u of SPEC section 5, best source first: the supervised command
#: sent to the actuator, else the controller's raw output. The force the actuator
#: measured is reported in a row of its own. A column of NaN means "not recorded".
FORCE_COLUMNS: tuple[str, ...] = ("force_command_N", "force_raw_N")
MEASURED_FORCE = "force_measured_N"


@dataclass(frozen=True)
class Quantity:
    """One compared quantity.

    Attributes
    ----------
    key : str
        Stable identifier, e.g. ``"drift_2"``, ``"force_percent_weight"``.
    label : str
        Human label, e.g. ``"Story 2 drift"``.
    unit : str
        Display unit, e.g. ``"mm"``.
    scale : float
        Multiply the SI value by this to get the display unit.
    digits : int
        Decimals to show.
    """

    key: str
    label: str
    unit: str
    scale: float
    digits: int

    def show(self, value_si: float | None) -> str:
        """The value in the display unit, formatted; ``"-"`` when absent."""
        if value_si is None or not np.isfinite(value_si):
            return "-"
        return f"{value_si * self.scale:.{self.digits}f}"


def quantities(n_stories: int) -> list[Quantity]:
    """The compared quantities for an ``n_stories`` building, in table order."""
    rows = [
        Quantity("table_pga", "Table peak acceleration", "m/s^2", 1.0, 3),
        Quantity("table_pgv", "Table peak velocity", "mm/s", 1e3, 1),
        Quantity("table_pgd", "Table peak displacement", "mm", 1e3, 2),
    ]
    for j in range(n_stories, 0, -1):
        rows.append(Quantity(f"drift_{j}", f"Story {j} drift", "mm", 1e3, 3))
    for j in range(n_stories, 0, -1):
        rows.append(Quantity(f"floor_acceleration_{j}", f"Floor {j} abs. acceleration", "m/s^2", 1.0, 3))
    rows += [
        Quantity("base_acceleration", "Base mat abs. acceleration", "m/s^2", 1.0, 3),
        Quantity("sliding_displacement", "Base mat sliding displacement", "mm", 1e3, 2),
        Quantity("force_percent_weight", "Peak control force / weight", "%", 1.0, 2),
        Quantity("measured_force_percent_weight", "Peak measured actuator force / weight", "%", 1.0, 2),
    ]
    return rows


def force_column(run: RunData) -> str | None:
    """The column holding the control force u in ``run`` (:data:`FORCE_COLUMNS`, all-NaN ones skipped), or None."""
    for name in FORCE_COLUMNS:
        if name in run.signals and np.isfinite(run.signals[name]).any():
            return name
    return None


def run_peaks(run: RunData, n_stories: int | None = None) -> dict[str, float | None]:
    """Peak of every quantity of :func:`quantities` for ``run`` (SI; None when the column is absent).

    Parameters
    ----------
    run : RunData
    n_stories : int, optional
        Stories to report (default: the run's own).
    """
    stories = run.n_stories if n_stories is None else n_stories
    sources = {
        "table_pga": "table_acceleration_m_s2",
        "table_pgv": "table_velocity_m_s",
        "table_pgd": "table_displacement_m",
        "base_acceleration": "base_acceleration_m_s2",
        "sliding_displacement": "sliding_displacement_m",
    }
    for j in range(1, stories + 1):
        sources[f"drift_{j}"] = drift(j)
        sources[f"floor_acceleration_{j}"] = floor_acceleration(j)
    peaks: dict[str, float | None] = {}
    for key, column in sources.items():
        peaks[key] = peak_abs(run.signals[column]) if column in run.signals else None
    column = force_column(run)
    peaks["force_percent_weight"] = 0.0 if run.is_passive and column is None else _percent_of_weight(run, column)
    measured = MEASURED_FORCE if MEASURED_FORCE in run.signals else None
    peaks["measured_force_percent_weight"] = _percent_of_weight(run, measured)
    return peaks


def _percent_of_weight(run: RunData, column: str | None) -> float | None:
    weight = run.metadata.get("total_weight_N")
    if column is None or not isinstance(weight, (int, float)) or weight <= 0:
        return None
    peak = peak_abs(run.signals[column])
    return None if peak is None else 100.0 * peak / float(weight)

#: The report's name for :func:`harness.peaks.reduction_pct`: one SPEC 5 formula for reports and consoles.
reduction_percent = reduction_pct
