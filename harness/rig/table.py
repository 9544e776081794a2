"""The shaking table and the plant on it, advanced one physics sub-step at a time.

Two :class:`~harness.model.plant.Plant` objects integrate the same building: one
on the processed record (while the table plays it, the plant's time is the record
time), one on a table held still at ``hold_m`` (before the start, after a stop or
the end of the record). The state is copied across when the table starts or stops,
so at any time exactly one of them is live. Both use the compiled kernel.

With ``rig.table.model: servo_hydraulic`` the record is the table's drive: the
platform's own servo loop tracks it under the payload's reactions, and the achieved
motion is part of the plant's state (SPEC 7b). With ``rig.actuator.model:
servo_hydraulic`` the control actuator's cylinder is too (SPEC 7a). Both plants share
one parameter array, so the drive's enable flag reaches whichever is live.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from harness.errors import ModelError
from harness.hydraulics.cylinder import BASE_PINNED, pack_rig
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig, acceleration_maps
from harness.model.plant import Plant, TableMotion
from harness.rig.truth import true_hydraulics

if TYPE_CHECKING:
    from harness.motions import GroundMotion
    from harness.rig.config import RigConfig


def rig_params_for(rig: RigConfig | None, building: BuildingConfig) -> np.ndarray | None:
    """The packed hydraulics of ``rig`` for the plant, or None where the rig has none.

    None (the plant of earlier versions, bit for bit) when the actuator is a force
    source, the table a motion source and the base mat free.
    """
    if rig is None:
        return None
    hydraulic = rig.actuator.model == "servo_hydraulic"
    if not hydraulic and rig.table.model == "motion_source" and not rig.base_pinned:
        return None
    return pack_rig(
        true_hydraulics(rig.actuator.hydraulics, rig.truth.actuator) if hydraulic else None, rig.table,
        building.base_mass_kg, rig.base_pinned,
        rig.drive.decay_time_constant_s,
    )


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
    rig : RigConfig, optional
        The rig's actuator, table and pinning (see :func:`rig_params_for`); default none.
    """

    def __init__(
        self, building: BuildingConfig, bearing: BearingConfig, motion: GroundMotion, rtol: float, rig: RigConfig | None = None,
    ):
        self.motion = motion
        params = rig_params_for(rig, building)
        self.record = Plant(building, bearing, TableMotion.from_motion(motion), rtol, params)
        self.rig_params = self.record.rig_params
        self._hold = np.zeros(2)
        held_table = TableMotion(1.0, np.zeros(2), np.zeros(2), self._hold)
        self.held = Plant(building, bearing, held_table, rtol, params)
        self.duration_s = float(motion.duration_s)
        model = self.record.model
        self._i_yb, self._i_vb = model.i_base_displacement, model.i_base_velocity
        floor_map, _ = acceleration_maps(building)
        self._floor_map = np.ascontiguousarray(floor_map[:3])
        self._size = model.size
        self._floor_acc = np.zeros(3)
        #: The plant couples the rig's hydraulics (packed rig parameters): only then can its bearings seize.
        self.can_seize = self.rig_params is not None and self.rig_params.size > BASE_PINNED
        self._pinned_by_profile = float(self.rig_params[BASE_PINNED]) if self.can_seize else 0.0
        #: The bearings are seized (the ``seize`` fault): the base mat moves with the table.
        self.seized = False
        #: The sliding velocity the last seize stopped (m/s; NaN before any).
        self.seized_at_velocity_m_s = float("nan")
        self.reset()

    def reset(self) -> None:
        """Plant at rest, table held at the record's first displacement, not running."""
        self.record.reset()
        self.live = self.held
        self._hold[:] = float(self.motion.displacement_m[0])
        self.held.reset()  # after the hold is set: a dynamic table starts at its drive
        self.running = False
        self.record_time_s = 0.0
        self._held_time_s = 0.0
        self._input = 0.0
        self.started = False
        self.set_seized(False)

    def set_seized(self, seized: bool) -> None:
        """Seize the bearings (the sliding stops at once) or free them again; nothing while unchanged.

        A seize is a stop: the base mat takes the table's velocity at once (the floors keep their
        own, so the first story's drift rate takes the step) and from then on moves with the table,
        as the pinned base mat of the rig's kernel (SPEC 7a, 7b; ``rig.base_pinned``). The control
        actuator's piston, which strokes at the sliding velocity, is blocked while it strokes.

        Raises
        ------
        ModelError
            If the plant has no rig parameters (a force-source actuator on a motion-source table).
        """
        if seized == self.seized:
            return
        params = self.rig_params
        if not self.can_seize:
            raise ModelError("a seized bearing needs the rig's coupled plant: a servo-hydraulic actuator or table")
        if seized:
            y = self.live.y
            _, table_velocity = self.live.table_now(self.time_s)
            step = y[self._i_vb] - table_velocity
            y[self._i_vb] = table_velocity
            self.seized_at_velocity_m_s = float(step)
            y[self._size // 2] += step  # xdot_1 = (floor 1 - base mat)': floor 1 keeps its velocity
        params[BASE_PINNED] = 1.0 if seized else self._pinned_by_profile
        self.seized = seized

    @property
    def y(self) -> np.ndarray:
        """State ``(Z, nu[, rig states])`` of the live plant (do not keep across start/stop)."""
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
        x, _ = self.live.table_now(self.record_time_s)
        self._hold[:] = x
        self.held.y[:] = self.live.y
        self.live = self.held
        self.running = False

    def advance(self, t_s: float, h_s: float, force_N: float) -> None:
        """Advance the live plant over one sub-step ``[t_s, t_s + h_s)`` of rig time with the force held."""
        self._input = force_N
        if self.running:
            r = self.record_time_s
            self.record.advance(r, r + h_s, force_N)
            self.record_time_s = r + h_s
            if self.record_time_s >= self.duration_s - 1e-12:
                self.stop()
        else:
            self.held.advance(t_s, t_s + h_s, force_N)
            self._held_time_s = t_s + h_s

    @property
    def time_s(self) -> float:
        """The live plant's time (s): record time while the table plays, else the rig's."""
        return self.record_time_s if self.running else self._held_time_s

    def stroke_m(self) -> float:
        """The control actuator's stroke now, the sliding displacement ``x_b = y_b - x_0`` (m)."""
        x0, _ = self.live.table_now(self.time_s)
        return float(self.live.y[self._i_yb] - x0)

    def _motion(self, force_N: float) -> tuple[float, float, float, float]:
        """Achieved table ``(x_0, xd_0, xdd_0)`` and the base mat's acceleration now, ``force_N`` as in :meth:`advance`."""
        live, t = self.live, self.time_s
        x0, v0 = live.table_now(t)
        table_acc, base_acc = live.accelerations(t, force_N)
        return x0, v0, table_acc, base_acc

    def table_truth(self) -> tuple[float, float, float]:
        """Achieved table ``(x_0, xd_0, xdd_0)`` now (m, m/s, m/s^2), with the plant's last input held."""
        return self._motion(self._input)[:3]

    def truth(self, out: np.ndarray, force_N: float) -> None:
        """The twelve true signals of :data:`harness.rig.sensors.SIGNALS` into ``out`` (SI).

        ``force_N`` is what the plant integrates with now (:meth:`advance`): the actuator
        force, or a servo-hydraulic actuator's command.
        """
        y = self.live.y
        out[0], out[1], out[2], out[5] = self._motion(force_N)
        out[3], out[4] = y[self._i_yb], y[self._i_vb]
        out[6], out[7], out[8] = y[0], y[1], y[2]
        np.dot(self._floor_map, y[: self._size], out=self._floor_acc)
        out[9:12] = self._floor_acc
