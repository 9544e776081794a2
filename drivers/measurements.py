"""The decoded control sample: the measured signals the drivers hand to the estimator, controller and supervisor.

The harness-side reader fills it from TABLE_SENSORS and BASE_SENSORS
(:meth:`drivers.reader.HarnessReader.fill`); the offline simulation fills it from its
plant. One :class:`Measurements` object is allocated before a run and updated in place
every tick, so the tick allocates nothing. All values are SI.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Measurements:
    """The latest sample of every signal the controller may use (SI units).

    Attributes
    ----------
    table_displacement_m : float
        ``x_0``, table absolute displacement (m).
    table_velocity_m_s : float
        ``xdot_0``, table absolute velocity (m/s).
    base_displacement_m : float
        ``y_b``, base-mat absolute displacement (m).
    base_velocity_m_s : float
        ``ydot_b``, base-mat absolute velocity (m/s).
    actuator_force_N : float
        ``u``, the control actuator's force from its load cell (N); 0 where the source has none.
        Not touched by :meth:`set`: whoever reads the load cell fills it.
    """

    table_displacement_m: float = 0.0
    table_velocity_m_s: float = 0.0
    base_displacement_m: float = 0.0
    base_velocity_m_s: float = 0.0
    actuator_force_N: float = 0.0

    @property
    def sliding_displacement_m(self) -> float:
        """``x_b = y_b - x_0``, the bearing stroke (m)."""
        return self.base_displacement_m - self.table_displacement_m

    @property
    def sliding_velocity_m_s(self) -> float:
        """``xdot_b = ydot_b - xdot_0`` (m/s)."""
        return self.base_velocity_m_s - self.table_velocity_m_s

    def set(self, x0: float, xd0: float, yb: float, ydb: float) -> None:
        """Overwrite all four signals in place."""
        self.table_displacement_m = x0
        self.table_velocity_m_s = xd0
        self.base_displacement_m = yb
        self.base_velocity_m_s = ydb
