"""The shaking table and the plant on it, advanced one physics sub-step at a time.

Two :class:`~harness.model.plant.Plant` objects integrate the same building: one
on the processed record (while the table plays it, the plant's time is the record
time), one on a table held still at ``hold_m`` (before the start, after a stop or
the end of the record). The state is copied across when the table starts or stops,
so at any time exactly one of them is live. Both use the compiled kernel.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from harness.model.bearing import BearingConfig, friction_force
from harness.model.building import BuildingConfig, acceleration_maps
from harness.model.plant import Plant, TableMotion

if TYPE_CHECKING:
    from harness.motions import GroundMotion


class TablePlant:
    """Table phases (held / running) and the live plant.

    Parameters
    ----------
    building, bearing
        The profile's ``structure`` and ``bearing``.
    motion
        The processed ground motion (``dt_s``, ``accel_m_s2``, ``velocity_m_s``,
        ``displacement_m`` and ``sample(t) -> (x, v, a)``).
    rtol : float
        Kernel tolerance.
    """

    def __init__(self, building: BuildingConfig, bearing: BearingConfig, motion: GroundMotion, rtol: float):
        self.motion = motion
        self.record = Plant(building, bearing, TableMotion.from_motion(motion), rtol)
        self._hold = np.zeros(2)
        held_table = TableMotion(1.0, np.zeros(2), np.zeros(2), self._hold)
        self.held = Plant(building, bearing, held_table, rtol)
        self.duration_s = float(motion.duration_s)
        model = self.record.model
        self._n = building.n_stories
        self._i_yb, self._i_vb = model.i_base_displacement, model.i_base_velocity
        self._mb = model.base_mass_kg
        self._kb = model.restoring_stiffness_N_per_m
        self._params = self.record.bearing_params
        floor_map, base_map = acceleration_maps(building)
        self._floor_map = np.ascontiguousarray(floor_map[:3])
        self._base_map = base_map
        self._floor_acc = np.zeros(3)
        self.reset()

    def reset(self) -> None:
        """Plant at rest, table held at the record's first displacement, not running."""
        self.record.reset()
        self.held.reset()
        self.live = self.held
        self._hold[:] = float(self.motion.displacement_m[0])
        self.running = False
        self.record_time_s = 0.0
        self.started = False

    @property
    def y(self) -> np.ndarray:
        """State ``(Z, nu)`` of the live plant (do not keep across start/stop)."""
        return self.live.y

    def start(self) -> None:
        """Play the record from record time 0 (from the live state)."""
        self.record.y[:] = self.live.y
        self.live = self.record
        self.running = True
        self.started = True
        self.record_time_s = 0.0

    def stop(self) -> None:
        """Hold the table where it is now (velocity zero)."""
        if not self.running:
            return
        x, _, _ = self.motion.sample(self.record_time_s)
        self._hold[:] = x
        self.held.y[:] = self.live.y
        self.live = self.held
        self.running = False

    def advance(self, t_s: float, h_s: float, force_N: float) -> None:
        """Advance the live plant over one sub-step ``[t_s, t_s + h_s)`` of rig time with the force held."""
        if self.running:
            r = self.record_time_s
            self.record.advance(r, r + h_s, force_N)
            self.record_time_s = r + h_s
            if self.record_time_s >= self.duration_s - 1e-12:
                self.stop()
        else:
            self.held.advance(t_s, t_s + h_s, force_N)

    def table_truth(self) -> tuple[float, float, float]:
        """Table ``(x_0, xd_0, xdd_0)`` now (m, m/s, m/s^2)."""
        if self.running:
            return self.motion.sample(self.record_time_s)
        return float(self._hold[0]), 0.0, 0.0

    def truth(self, out: np.ndarray, force_N: float) -> None:
        """The twelve true signals of :data:`harness.rig.sensors.SIGNALS` into ``out`` (SI).

        ``force_N`` is the actuator force acting now (for the base-mat acceleration).
        """
        y = self.live.y
        x0, v0, a0 = self.table_truth()
        yb, vb = y[self._i_yb], y[self._i_vb]
        z = y[:-1]
        friction = friction_force(vb - v0, y[-1], self._params)
        out[0], out[1], out[2] = x0, v0, a0
        out[3], out[4] = yb, vb
        out[5] = float(self._base_map @ z) + (self._kb * x0 - friction + force_N) / self._mb
        out[6], out[7], out[8] = y[0], y[1], y[2]
        np.dot(self._floor_map, z, out=self._floor_acc)
        out[9:12] = self._floor_acc
