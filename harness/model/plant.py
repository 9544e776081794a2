"""The plant: building, bearings and table motion advanced by the compiled kernel.

Used alike by ``harness simulate`` (offline) and the virtual rig (in real time or
lockstep), so both integrate the same equations the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from drivers.measurements import Measurements
from harness.hydraulics import cylinder as hy
from harness.model.bearing import BearingConfig, friction_force
from harness.model.building import (
    BuildingConfig,
    StateSpace,
    acceleration_maps,
    state_space,
)
from harness.model.integrator import advance, default_atol, derivative, make_work, table_drive, table_state
from harness.signals import columns as layout


@dataclass(frozen=True)
class TableMotion:
    """Table acceleration, velocity and displacement samples, consistent under the
    piecewise-linear-acceleration rule (see :mod:`harness.motions`)."""

    dt_s: float
    accel_m_s2: np.ndarray
    velocity_m_s: np.ndarray
    displacement_m: np.ndarray

    @classmethod
    def from_motion(cls, motion) -> TableMotion:
        """From any object with ``dt_s``, ``accel_m_s2``, ``velocity_m_s``, ``displacement_m``."""
        return cls(
            float(motion.dt_s),
            np.ascontiguousarray(motion.accel_m_s2, dtype=float),
            np.ascontiguousarray(motion.velocity_m_s, dtype=float),
            np.ascontiguousarray(motion.displacement_m, dtype=float),
        )

    @classmethod
    def at_rest(cls, duration_s: float = 1.0, dt_s: float = 0.01) -> TableMotion:
        """A table that does not move."""
        n = int(round(duration_s / dt_s)) + 1
        zeros = np.zeros(n)
        return cls(dt_s, zeros, zeros.copy(), zeros.copy())

    @property
    def duration_s(self) -> float:
        """Length of the motion (s)."""
        return (len(self.accel_m_s2) - 1) * self.dt_s

    def state(self, t: float) -> tuple[float, float]:
        """Table displacement (m) and velocity (m/s) at ``t``."""
        return table_state(t, self.accel_m_s2, self.velocity_m_s, self.displacement_m, self.dt_s)

    def states(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Table displacement (m) and velocity (m/s) at many times, by the same rule as :meth:`state`."""
        times = np.asarray(times, dtype=float)
        last = len(self.accel_m_s2) - 1
        index = np.clip((times / self.dt_s).astype(np.int64), 0, max(last - 1, 0))
        tau = np.clip(times - index * self.dt_s, 0.0, None)
        a0 = self.accel_m_s2[index]
        da = (self.accel_m_s2[np.minimum(index + 1, last)] - a0) / self.dt_s
        v = self.velocity_m_s[index] + a0 * tau + 0.5 * da * tau**2
        x = self.displacement_m[index] + self.velocity_m_s[index] * tau + 0.5 * a0 * tau**2 + da * tau**3 / 6.0
        after = times >= last * self.dt_s
        x[after], v[after] = self.displacement_m[last], 0.0
        before = times <= 0.0
        x[before], v[before] = self.displacement_m[0], self.velocity_m_s[0]
        return x, v

    def acceleration(self, t: np.ndarray) -> np.ndarray:
        """Table acceleration (m/s^2) at times ``t`` (linear between samples, zero after the end)."""
        times = np.arange(len(self.accel_m_s2)) * self.dt_s
        return np.interp(t, times, self.accel_m_s2, left=self.accel_m_s2[0], right=0.0)


class Plant:
    """Building on friction bearings on a moving table; state ``y = (Z, nu[, rig states])``.

    Parameters
    ----------
    building : BuildingConfig
    bearing : BearingConfig
    table : TableMotion
        The table's motion, or with a servo-hydraulic table the drive its servo loop tracks.
    rtol : float
        Relative tolerance of the kernel (absolute tolerances scale with it).
    rig_params : ndarray, optional
        The rig's hydraulics (:func:`harness.hydraulics.cylinder.pack_rig`); the state then
        carries the table's and the cylinders' states after ``nu`` (SPEC 7a, 7b). An array
        shared between plants (the rig's held and record plants) shares its enable flag.
    """

    def __init__(
        self, building: BuildingConfig, bearing: BearingConfig, table: TableMotion, rtol: float = 1e-6,
        rig_params: np.ndarray | None = None,
    ):
        self.building = building
        self.bearing = bearing
        self.table = table
        self.model: StateSpace = state_space(building)
        self.bearing_params = bearing.packed(building.total_weight_N)
        self.rtol = float(rtol)
        self.rig_params = np.zeros(0) if rig_params is None else rig_params
        self.coupled = self.rig_params.size > 0
        #: Index of nu in the state; the rig's states follow it.
        self.i_nu = self.model.size
        atol = default_atol(building.n_stories)
        if self.coupled:
            atol = np.concatenate((atol, hy.rig_atol()))
        self.atol = atol * (self.rtol / 1e-6)
        self.y = np.zeros(atol.size)
        self._work = make_work(atol.size)
        self._rates = np.zeros(atol.size)
        self.steps = 0
        m, t = self.model, table
        self._table_args = (
            m.A, m.B, m.restoring_stiffness_N_per_m, self.bearing_params,
            t.accel_m_s2, t.velocity_m_s, t.displacement_m, t.dt_s,
        )
        self._kernel_args = (*self._table_args, self.atol, self.rtol, self._work, self.rig_params)

    @property
    def table_dynamic(self) -> bool:
        """The table is a servo-hydraulic platform whose motion is part of the state."""
        return self.coupled and self.rig_params[hy.TABLE_DYNAMIC] > 0.0

    @property
    def actuator_hydraulic(self) -> bool:
        """The control actuator is servo-hydraulic: its force is part of the state."""
        return self.coupled and self.rig_params[hy.ACTUATOR_HYDRAULIC] > 0.0

    def reset(self) -> None:
        """Back to rest: all displacements, velocities, nu and pressures zero; a dynamic table at its drive's start."""
        self.y[:] = 0.0
        self._work[:] = 0.0
        self.steps = 0
        if self.table_dynamic:
            self.y[self.i_nu + 1 + hy.TABLE_X] = self.table.state(0.0)[0]

    def advance(self, t0: float, t1: float, force_N: float) -> None:
        """Integrate from ``t0`` to ``t1`` (s) with ``force_N`` held: the actuator force, or a
        servo-hydraulic actuator's force command (N)."""
        if t1 > t0:
            self.steps += advance(self.y, t0, t1, force_N, *self._kernel_args)

    def table_now(self, t: float) -> tuple[float, float]:
        """Table displacement (m) and velocity (m/s) of the current state at ``t``."""
        if self.table_dynamic:
            first = self.i_nu + 1
            return float(self.y[first + hy.TABLE_X]), float(self.y[first + hy.TABLE_V])
        return self.table.state(t)

    def actuator_force(self, force_N: float) -> float:
        """The control actuator's force now (N): ``A p_L`` when servo-hydraulic, else ``force_N``."""
        if self.actuator_hydraulic:
            return float(self.rig_params[hy.ACTUATOR_CYLINDER + hy.AREA] * self.y[self.i_nu + 1 + hy.ACTUATOR_PRESSURE])
        return force_N

    def accelerations(self, t: float, force_N: float) -> tuple[float, float]:
        """Table and base-mat absolute accelerations (m/s^2) of the current state at ``t``.

        ``force_N`` as in :meth:`advance`. With a motion-source table the table's is the record's.
        """
        rates = self._rates
        derivative(t, self.y, rates, force_N, *self._table_args, self.rig_params)
        base = float(rates[self.model.i_base_velocity])
        if self.coupled:
            return float(rates[self.i_nu + 1 + hy.TABLE_V]), base
        return float(table_drive(t, *self._table_args[4:])[2]), base

    def measure(self, t: float, out: Measurements, table_x: float | None = None, table_v: float | None = None) -> Measurements:
        """Write the exact (noise-free) table and base-mat signals at ``t`` into ``out``.

        ``table_x`` and ``table_v`` may be given when already known (precomputed at sample times).
        """
        if table_x is None or table_v is None:
            table_x, table_v = self.table.state(t)
        out.set(table_x, table_v, self.y[self.model.i_base_displacement], self.y[self.model.i_base_velocity])
        return out

    def friction_force(self, t: float, table_v: float | None = None) -> float:
        """The bearing friction force of the current state at ``t`` (N).

        ``table_v`` (the record's table velocity, when the caller has it) is used only where the
        table follows its record; a servo-hydraulic table's velocity is its state's.
        """
        v0 = self.table_now(t)[1] if table_v is None or self.table_dynamic else table_v
        return friction_force(self.y[self.model.i_base_velocity] - v0, self.y[self.i_nu], self.bearing_params)

    def responses(self, times: np.ndarray, states: np.ndarray, forces: np.ndarray) -> dict[str, np.ndarray]:
        """Derived time series from sampled states.

        Parameters
        ----------
        times : ndarray (K,)
            Sample times (s).
        states : ndarray (K, N + 1)
            ``(Z, nu)`` at ``times`` (SI).
        forces : ndarray (K,)
            Actuator force applied from each sample on (N).

        Returns
        -------
        dict
            The columns :func:`harness.signals.columns.plant_columns` names, in that order (SI):
            table motion, base-mat motion and absolute acceleration, sliding displacement
            and velocity, drifts, absolute floor accelerations, friction force, nu.
        """
        m = self.model
        if self.coupled:
            table_x, table_v, table_acc, base_acc = self._rig_motion(times, states, forces)
        else:
            table_x, table_v = self.table.states(times)
            table_acc = self.table.acceleration(times)
        sliding_v = states[:, m.i_base_velocity] - table_v
        params = self.bearing_params
        mu = params[0] - params[1] * np.exp(-params[2] * np.abs(sliding_v))
        friction = mu * params[3] * states[:, self.i_nu]
        floor_map, base_map = acceleration_maps(self.building)
        z = states[:, : m.size]
        if not self.coupled:
            base_acc = z @ base_map + (m.restoring_stiffness_N_per_m * table_x - friction + forces) / m.base_mass_kg
        floor_acc = z @ floor_map.T
        stories = range(self.building.n_stories)
        return {
            layout.TIME: times,
            layout.TABLE_DISPLACEMENT: table_x,
            layout.TABLE_VELOCITY: table_v,
            layout.TABLE_ACCELERATION: table_acc,
            layout.BASE_DISPLACEMENT: states[:, m.i_base_displacement],
            layout.BASE_VELOCITY: states[:, m.i_base_velocity],
            layout.BASE_ACCELERATION: base_acc,
            layout.SLIDING_DISPLACEMENT: states[:, m.i_base_displacement] - table_x,
            layout.SLIDING_VELOCITY: sliding_v,
            **{layout.drift(j + 1): states[:, j] for j in stories},  # Z begins with the drifts, story 1 first
            **{layout.floor_acceleration(j + 1): floor_acc[:, j] for j in stories},
            layout.FRICTION_FORCE: friction,
            layout.HYSTERETIC_NU: states[:, self.i_nu],
        }

    def _rig_motion(self, times: np.ndarray, states: np.ndarray, forces: np.ndarray):
        """Table displacement, velocity, acceleration and base-mat acceleration of sampled coupled states."""
        count = len(times)
        table_acc, base_acc = np.empty(count), np.empty(count)
        rates = self._rates
        for k in range(count):
            derivative(float(times[k]), states[k], rates, float(forces[k]), *self._table_args, self.rig_params)
            table_acc[k], base_acc[k] = rates[self.i_nu + 1 + hy.TABLE_V], rates[self.model.i_base_velocity]
        if self.table_dynamic:
            first = self.i_nu + 1
            return states[:, first + hy.TABLE_X], states[:, first + hy.TABLE_V], table_acc, base_acc
        table_x, table_v = self.table.states(times)
        return table_x, table_v, table_acc, base_acc
