"""The rows of every peak table: which quantities of :class:`~harness.signals.peaks.Peaks`, in what order, how shown.

One catalogue serves the console tables of ``harness simulate`` and ``harness dry-run``
(:func:`response_quantities` in :data:`CONSOLE_WORDING`) and the report's tables
(:func:`report_quantities`: the table motion, the SPEC 5 responses and the measured
force, in :data:`REPORT_WORDING`). Both list stories top down, as the building stands.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from harness.signals.peaks import Peaks, reduction_pct


@dataclass(frozen=True)
class Quantity:
    """One compared quantity: where its peak is in :class:`Peaks` and how to show it.

    Attributes
    ----------
    key : str
        Stable identifier, e.g. ``"drift_2"``, ``"force_percent_weight"`` (the report's CSV ``key``).
    label : str
        Human label, e.g. ``"Story 2 drift"``.
    unit : str
        Display unit, e.g. ``"mm"``.
    scale : float
        Multiply the SI value by this to get the display unit.
    digits : int
        Decimals to show.
    field : str
        The :class:`Peaks` attribute holding the SI value.
    story : int or None
        For per-story attributes (tuples), the story (from 1); None for scalars.
    comparable : bool
        A percent reduction passive -> controlled means something (not for the table
        motion, which is the input, nor for forces, which are 0 when passive).
    """

    key: str
    label: str
    unit: str
    scale: float
    digits: int
    field: str
    story: int | None = None
    comparable: bool = True

    def si_value(self, peaks: Peaks) -> float | None:
        """The SI peak in ``peaks``; None when absent (story beyond the case's, not finite)."""
        value = getattr(peaks, self.field)
        if self.story is not None:
            value = value[self.story - 1] if self.story <= len(value) else None
        return value if value is not None and math.isfinite(value) else None

    def display_value(self, peaks: Peaks) -> float | None:
        """The peak in the display unit (:attr:`scale` times the SI value); None when absent."""
        value = self.si_value(peaks)
        return None if value is None else value * self.scale

    def reduction(self, passive: Peaks, controlled: Peaks) -> float | None:
        """Percent reduction passive -> controlled (:func:`harness.signals.peaks.reduction_pct`); None if not comparable."""
        return reduction_pct(self.si_value(passive), self.si_value(controlled)) if self.comparable else None


@dataclass(frozen=True)
class Wording:
    """How one kind of table names its rows: headings, labels (``{j}``: the story) and units."""

    quantity_heading: str
    unit_heading: str
    drift: str
    floor_acceleration: str
    base_acceleration: str
    sliding_displacement: str
    force: str
    force_unit: str
    acceleration_unit: str


#: The unit of every acceleration in every table, console and files alike.
ACCELERATION_UNIT = "m/s²"

#: The report's tables (text, HTML, CSV).
REPORT_WORDING = Wording(
    "Quantity", "Unit", "Story {j} drift", "Floor {j} abs. acceleration", "Base mat abs. acceleration",
    "Sliding displacement x_b", "Control force / weight", "%", ACCELERATION_UNIT,
)

#: The console tables of ``harness simulate`` (one study or a batch) and ``harness dry-run``.
CONSOLE_WORDING = Wording(
    "response", "unit", "story {j} drift", "floor {j} abs. acceleration", "base mat acceleration",
    "sliding displacement x_b", "peak force", "% weight", ACCELERATION_UNIT,
)


def response_quantities(n_stories: int, wording: Wording = REPORT_WORDING) -> list[Quantity]:
    """The SPEC 5 responses of an ``n_stories`` building, in table order.

    Story drifts (mm) and floor absolute accelerations top down, the base mat's absolute
    acceleration, its sliding displacement (mm) and the peak control force (% of weight).
    """
    stories = range(n_stories, 0, -1)
    acceleration = wording.acceleration_unit
    return [
        *(Quantity(f"drift_{j}", wording.drift.format(j=j), "mm", 1e3, 3, "drift_m", j) for j in stories),
        *(
            Quantity(f"floor_acceleration_{j}", wording.floor_acceleration.format(j=j), acceleration, 1.0, 3,
                     "floor_acceleration_m_s2", j)
            for j in stories
        ),
        Quantity("base_acceleration", wording.base_acceleration, acceleration, 1.0, 3, "base_acceleration_m_s2"),
        Quantity("sliding_displacement", wording.sliding_displacement, "mm", 1e3, 2, "sliding_displacement_m"),
        Quantity("force_percent_weight", wording.force, wording.force_unit, 1.0, 2, "peak_force_pct_weight",
                 comparable=False),
    ]


def report_quantities(n_stories: int) -> list[Quantity]:
    """The report's rows: the table motion, :func:`response_quantities`, then the measured actuator force."""
    acceleration = REPORT_WORDING.acceleration_unit
    return [
        Quantity("table_pga", "Table peak acceleration", acceleration, 1.0, 3, "table_acceleration_m_s2", comparable=False),
        Quantity("table_pgv", "Table peak velocity", "mm/s", 1e3, 1, "table_velocity_m_s", comparable=False),
        Quantity("table_pgd", "Table peak displacement", "mm", 1e3, 2, "table_displacement_m", comparable=False),
        *response_quantities(n_stories, REPORT_WORDING),
        Quantity("measured_force_percent_weight", "Measured force / weight", "%", 1.0, 2,
                 "measured_force_pct_weight", comparable=False),
    ]
