"""The shaking table's own limits and the check of a ground motion against them, before a run.

A motion the table cannot follow must be refused before the hydraulics move, not
discovered by a stroke interlock halfway through: :func:`check_table_limits`
compares the processed motion's PGD, PGV and PGA with the table's half-stroke,
velocity and acceleration limits and names every limit that is exceeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from harness.config.schema import quantity
from harness.errors import RecordError
from harness.motions.processing import GroundMotion


@dataclass(frozen=True)
class TableLimits:
    """Performance limits of the shaking table (profile section ``table:`` or similar).

    Parameters
    ----------
    stroke_limit_m : float
        Half-stroke of the table actuator (m): the table moves within ``+/-`` this.
    velocity_limit_m_s : float
        Largest |table velocity| (m/s).
    acceleration_limit_g : float
        Largest |table acceleration| with the specimen on it (g).
    link : {"can", "none"}
        How ``harness run`` reaches the table controller: ``can`` sends RIG_CONTROL start at
        RUNNING and stop at the end and on a trip, and counts record time from the controller's
        RIG_STATUS ``table_running``; ``none`` says the table controller is not on the bus (the
        operator starts and stops it; the consequence is printed before arming).
    """

    stroke_limit_m: float = quantity(unit="m", gt=0, doc="table half-stroke, +/- (m)")
    velocity_limit_m_s: float = quantity(unit="m/s", gt=0, doc="largest |table velocity| (m/s)")
    acceleration_limit_g: float = quantity(unit="g", gt=0, doc="largest |table acceleration| (g)")
    link: Literal["can", "none"] = quantity("can", doc="table controller on the CAN bus (RIG_CONTROL/RIG_STATUS) or not")

    def __post_init__(self) -> None:
        for name in ("stroke_limit_m", "velocity_limit_m_s", "acceleration_limit_g"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise ValueError(f"{name}: expected a finite number > 0, found {value!r}")


@dataclass(frozen=True)
class LimitExcess:
    """One exceeded limit: what, how much the motion needs, how much the table has (SI)."""

    limit: str
    needed: float
    available: float
    unit: str


class TableLimitError(RecordError):
    """A ground motion needs more stroke, velocity or acceleration than the table has.

    Attributes
    ----------
    excesses : tuple of LimitExcess
        Every limit that is exceeded.
    """

    def __init__(self, motion_name: str, excesses: tuple[LimitExcess, ...]):
        self.excesses = excesses
        parts = "; ".join(
            f"{e.limit}: needs {e.needed:.4g} {e.unit}, the table has {e.available:.4g} {e.unit}" for e in excesses
        )
        super().__init__(
            f"ground motion {motion_name!r} exceeds the table's limits ({parts}). "
            "Lower pga_g, shorten or compress differently (time_scale), or check the table limits in the profile"
        )


def table_excesses(motion: GroundMotion, limits: TableLimits) -> tuple[LimitExcess, ...]:
    """Every table limit the motion exceeds (empty when it fits)."""
    checks = (
        ("stroke (peak |x_0|)", motion.pgd_m, limits.stroke_limit_m, "m"),
        ("velocity (peak |xd_0|)", motion.pgv_m_s, limits.velocity_limit_m_s, "m/s"),
        ("acceleration (peak |xdd_0|)", motion.pga_g, limits.acceleration_limit_g, "g"),
    )
    return tuple(LimitExcess(name, needed, available, unit) for name, needed, available, unit in checks if needed > available)


def check_table_limits(motion: GroundMotion, limits: TableLimits) -> None:
    """Refuse a motion the table cannot follow.

    Raises
    ------
    TableLimitError
        (a :class:`~harness.errors.RecordError`) naming each exceeded limit, the
        figure the motion needs and the one the table has.
    """
    excesses = table_excesses(motion, limits)
    if excesses:
        raise TableLimitError(motion.name, excesses)


def largest_fitting_pga_g(motion: GroundMotion, limits: TableLimits) -> tuple[float, str]:
    """The largest PGA (g) at which ``motion`` fits the table, and the limit that sets it.

    Processing is linear in the target PGA (one scale factor for acceleration, velocity and
    displacement, and a linear baseline correction), so each peak scales with the PGA and the
    tightest ratio of limit to peak gives the answer.

    Returns
    -------
    (float, str)
        The PGA (g) and the name of the binding limit (``"stroke"``, ``"velocity"``, ``"acceleration"``).
    """
    ratios = {
        "stroke": limits.stroke_limit_m / motion.pgd_m if motion.pgd_m > 0 else math.inf,
        "velocity": limits.velocity_limit_m_s / motion.pgv_m_s if motion.pgv_m_s > 0 else math.inf,
        "acceleration": limits.acceleration_limit_g / motion.pga_g if motion.pga_g > 0 else math.inf,
    }
    binding = min(ratios, key=lambda name: ratios[name])
    return motion.pga_g * ratios[binding], binding
