"""The compiled integration kernel for the building on friction bearings.

The state integrated is ``y = (Z, nu)``: the building state of
:mod:`harness.model.building` followed by the Bouc-Wen variable. Between two
controller samples the actuator force ``u`` is constant (zero-order hold, SPEC 3),
and the table motion follows the piecewise-linear-acceleration rule of
:mod:`harness.motions` exactly, so the kernel reproduces the table's displacement
and velocity between record samples without any extra interpolation error.

Eq. 5 is stiff: with D_y of tens of micrometres nu swings from -1 to +1 within a
fraction of a millisecond. The kernel is an adaptive embedded Runge-Kutta 5(4)
(Dormand-Prince) compiled with numba; its step-size control follows the fast nu
transitions with sub-millisecond steps and takes long steps in between. It is
checked against ``scipy.integrate.solve_ivp`` at rtol 1e-9 in the tests and in
``benchmarks/``.
"""

from __future__ import annotations

import numba
import numpy as np

from harness.hydraulics import cylinder as hy
from harness.model.bearing import friction_force, hysteretic_rate

#: The first step from a reset state (s). Long enough to cost nothing, short enough that a
#: state started far from equilibrium (the table already sliding fast under the base mat)
#: cannot overflow nu in one trial step, where the error test, relative to the overflowed
#: value, would accept it.
_FIRST_STEP_S = 1e-4

# Dormand-Prince 5(4) tableau.
_C2, _C3, _C4, _C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
_A21 = 1.0 / 5.0
_A31, _A32 = 3.0 / 40.0, 9.0 / 40.0
_A41, _A42, _A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
_A51, _A52, _A53, _A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
_A61, _A62, _A63, _A64, _A65 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0
_B1, _B3, _B4, _B5, _B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
_E1, _E3, _E4, _E5, _E6, _E7 = (
    71.0 / 57600.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
)


@numba.njit(cache=True, nogil=True)
def table_state(t: float, accel: np.ndarray, velocity: np.ndarray, displacement: np.ndarray, dt: float):
    """Table displacement and velocity at time ``t`` (piecewise-linear acceleration between samples).

    Before the record the table is at its first sample; after the record it rests at its last
    displacement.
    """
    last = accel.shape[0] - 1
    if t <= 0.0:
        return displacement[0], velocity[0]
    k = int(t / dt)
    if k >= last:
        return displacement[last], 0.0
    tau = t - k * dt
    a0 = accel[k]
    da = (accel[k + 1] - a0) / dt
    v = velocity[k] + a0 * tau + 0.5 * da * tau * tau
    x = displacement[k] + velocity[k] * tau + 0.5 * a0 * tau * tau + da * tau * tau * tau / 6.0
    return x, v


@numba.njit(cache=True, nogil=True)
def table_drive(t: float, accel: np.ndarray, velocity: np.ndarray, displacement: np.ndarray, dt: float):
    """Drive displacement, velocity and acceleration at ``t`` (the rule of :func:`table_state`)."""
    x, v = table_state(t, accel, velocity, displacement, dt)
    last = accel.shape[0] - 1
    if t <= 0.0:
        return x, v, accel[0]
    k = int(t / dt)
    if k >= last:
        return x, v, 0.0
    return x, v, accel[k] + (accel[k + 1] - accel[k]) * (t - k * dt) / dt


@numba.njit(cache=True, nogil=True)
def derivative(
    t: float,
    y: np.ndarray,
    out: np.ndarray,
    u: float,
    a_matrix: np.ndarray,
    b_vector: np.ndarray,
    restoring_stiffness: float,
    bearing: np.ndarray,
    accel: np.ndarray,
    velocity: np.ndarray,
    displacement: np.ndarray,
    record_dt: float,
    rig: np.ndarray,
) -> None:
    """``out = dy/dt`` for ``y = (Z, nu[, rig states])`` (Eq. 3-7).

    With an empty ``rig`` the table follows the record exactly and ``u`` is the actuator
    force (N). Otherwise ``rig`` is :func:`harness.hydraulics.cylinder.pack_rig`'s array, ``y``
    carries the rig's states after ``nu`` and, with a servo-hydraulic actuator, ``u`` is
    the force command (N) of its force loop.
    """
    size: int = a_matrix.shape[0]  # numpy's stubs give shape entries no type
    coupled = rig.shape[0] > 0
    first = size + 1
    x_d = v_d = a_d = 0.0  # the table's drive (the record, or the hold), with the rig's hydraulics
    if coupled:
        x_d, v_d, a_d = table_drive(t, accel, velocity, displacement, record_dt)
        if rig[hy.TABLE_DYNAMIC] > 0.0:
            x0, v0 = y[first + hy.TABLE_X], y[first + hy.TABLE_V]
        else:
            x0, v0 = x_d, v_d
    else:
        x0, v0 = table_state(t, accel, velocity, displacement, record_dt)
    sliding_velocity = y[size - 1] - v0
    nu = y[size]
    friction = friction_force(sliding_velocity, nu, bearing)
    actuator_force = u
    if coupled and rig[hy.ACTUATOR_HYDRAULIC] > 0.0:
        actuator_force = rig[hy.ACTUATOR_CYLINDER + hy.AREA] * y[first + hy.ACTUATOR_PRESSURE]
    force = actuator_force - friction + restoring_stiffness * x0
    for i in range(size):
        acc = 0.0
        for j in range(size):
            acc += a_matrix[i, j] * y[j]
        out[i] = acc + b_vector[i] * force
    out[size] = hysteretic_rate(sliding_velocity, nu, bearing)
    if coupled:
        reaction = restoring_stiffness * (y[size // 2 - 1] - x0) + friction - actuator_force
        _rig_rates(y, out, size, u, reaction, x0, v0, sliding_velocity, rig, x_d, v_d, a_d)


@numba.njit(cache=True, nogil=True)
def _rig_rates(
    y: np.ndarray, out: np.ndarray, size: int, u: float, reaction: float, x0: float, v0: float,
    sliding_velocity: float, rig: np.ndarray, x_d: float, v_d: float, a_d: float,
) -> None:
    """Rates of the rig's states, and the pinned base mat (SPEC 7a, 7b).

    ``reaction`` is what the payload puts on the table: springs, bearing friction and the
    control actuator's reaction, ``k_b x_b + f - u`` (N); ``x_d, v_d, a_d`` the drive the table's servo tracks.
    """
    first = size + 1
    if rig[hy.ACTUATOR_HYDRAULIC] > 0.0:
        if rig[hy.ENABLED] > 0.0:
            area = rig[hy.ACTUATOR_CYLINDER + hy.AREA]
            current = hy.force_loop_current(
                rig[hy.ACTUATOR_GAIN], u, area * y[first + hy.ACTUATOR_PRESSURE], rig[hy.ACTUATOR_FEEDFORWARD],
            )
            bypass = 0.0
        else:
            current, bypass = 0.0, rig[hy.ACTUATOR_BYPASS]
        hy.cylinder_rates(y, out, first + hy.ACTUATOR_PRESSURE, current, sliding_velocity, bypass, rig, hy.ACTUATOR_CYLINDER)
    else:
        for k in range(3):
            out[first + hy.ACTUATOR_PRESSURE + k] = 0.0
    table_acceleration = a_d
    if rig[hy.TABLE_DYNAMIC] > 0.0:
        mass, area = rig[hy.TABLE_MASS], rig[hy.TABLE_CYLINDER + hy.AREA]
        pressure = y[first + hy.TABLE_PRESSURE]
        table_acceleration = (area * pressure + reaction) / mass
        flow = area * (v_d + rig[hy.TABLE_POSITION_GAIN] * (x_d - x0)) - rig[hy.TABLE_PRESSURE_FEEDBACK] * (
            pressure - mass * a_d / area
        )
        current = flow / rig[hy.TABLE_CYLINDER + hy.VALVE_FLOW]
        hy.cylinder_rates(y, out, first + hy.TABLE_PRESSURE, current, v0, 0.0, rig, hy.TABLE_CYLINDER)
    else:
        for k in range(3):
            out[first + hy.TABLE_PRESSURE + k] = 0.0
    if rig[hy.BASE_PINNED] > 0.0:
        base_acceleration = out[size - 1]
        if rig[hy.TABLE_DYNAMIC] > 0.0:  # platform and base mat move as one: the internal forces cancel
            mass = rig[hy.TABLE_MASS]
            table_acceleration = (mass * table_acceleration + rig[hy.BASE_MASS] * base_acceleration) / (mass + rig[hy.BASE_MASS])
        out[size - 1] = table_acceleration
        out[size // 2] += base_acceleration - table_acceleration  # xddot_1 = a_1 - yddot_b
    out[first + hy.TABLE_X] = v0
    out[first + hy.TABLE_V] = table_acceleration


@numba.njit(cache=True, nogil=True)
def advance(
    y: np.ndarray,
    t0: float,
    t1: float,
    u: float,
    a_matrix: np.ndarray,
    b_vector: np.ndarray,
    restoring_stiffness: float,
    bearing: np.ndarray,
    accel: np.ndarray,
    velocity: np.ndarray,
    displacement: np.ndarray,
    record_dt: float,
    atol: np.ndarray,
    rtol: float,
    work: np.ndarray,
    rig: np.ndarray,
) -> int:
    """Integrate ``y`` in place from ``t0`` to ``t1`` with the actuator force held at ``u``.

    Parameters
    ----------
    y : ndarray (N + 1,)
        State ``(Z, nu)``, overwritten with the state at ``t1``.
    t0, t1 : float
        Interval (s).
    u : float
        Actuator force held over the interval (N).
    a_matrix, b_vector, restoring_stiffness : model of Eq. 6-7.
    bearing : ndarray
        Packed bearing parameters (:meth:`BearingConfig.packed`).
    accel, velocity, displacement : ndarray
        Table motion samples, consistent under the piecewise-linear rule.
    record_dt : float
        Their sample step (s).
    atol : ndarray (N + 1,)
        Absolute tolerance per component.
    rtol : float
        Relative tolerance.
    work : ndarray (9 * len(y) + 1,)
        Scratch space; ``work[0]`` carries the last accepted step size between calls.
    rig : ndarray
        The rig's packed parameters (:func:`harness.hydraulics.cylinder.pack_rig`), or empty.

    Returns
    -------
    int
        Number of accepted steps.
    """
    n = y.shape[0]
    k1 = work[1 : 1 + n]
    k2 = work[1 + n : 1 + 2 * n]
    k3 = work[1 + 2 * n : 1 + 3 * n]
    k4 = work[1 + 3 * n : 1 + 4 * n]
    k5 = work[1 + 4 * n : 1 + 5 * n]
    k6 = work[1 + 5 * n : 1 + 6 * n]
    k7 = work[1 + 6 * n : 1 + 7 * n]
    ytmp = work[1 + 7 * n : 1 + 8 * n]
    ynew = work[1 + 8 * n : 1 + 9 * n]
    t = t0
    h = work[0]
    if h <= 0.0:  # the first call from rest: a short first step, which the controller then grows
        h = min(t1 - t0, _FIRST_STEP_S)
    accepted = 0
    derivative(t, y, k1, u, a_matrix, b_vector, restoring_stiffness, bearing, accel, velocity, displacement, record_dt, rig)
    while t < t1:
        remaining = t1 - t
        truncated = h >= remaining
        step = remaining if truncated else h
        for i in range(n):
            ytmp[i] = y[i] + step * _A21 * k1[i]
        derivative(
            t + _C2 * step, ytmp, k2, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        for i in range(n):
            ytmp[i] = y[i] + step * (_A31 * k1[i] + _A32 * k2[i])
        derivative(
            t + _C3 * step, ytmp, k3, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        for i in range(n):
            ytmp[i] = y[i] + step * (_A41 * k1[i] + _A42 * k2[i] + _A43 * k3[i])
        derivative(
            t + _C4 * step, ytmp, k4, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        for i in range(n):
            ytmp[i] = y[i] + step * (_A51 * k1[i] + _A52 * k2[i] + _A53 * k3[i] + _A54 * k4[i])
        derivative(
            t + _C5 * step, ytmp, k5, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        for i in range(n):
            ytmp[i] = y[i] + step * (_A61 * k1[i] + _A62 * k2[i] + _A63 * k3[i] + _A64 * k4[i] + _A65 * k5[i])
        derivative(
            t + step, ytmp, k6, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        for i in range(n):
            ynew[i] = y[i] + step * (_B1 * k1[i] + _B3 * k3[i] + _B4 * k4[i] + _B5 * k5[i] + _B6 * k6[i])
        derivative(
            t + step, ynew, k7, u, a_matrix, b_vector, restoring_stiffness, bearing,
            accel, velocity, displacement, record_dt, rig,
        )
        error = 0.0
        for i in range(n):
            e = step * (_E1 * k1[i] + _E3 * k3[i] + _E4 * k4[i] + _E5 * k5[i] + _E6 * k6[i] + _E7 * k7[i])
            ratio = abs(e) / (atol[i] + rtol * max(abs(y[i]), abs(ynew[i])))
            if not ratio <= error:  # a NaN (a trial step that overflowed) counts as the largest error
                error = ratio
        if error <= 1.0:
            t = t1 if truncated else t + step
            for i in range(n):
                y[i] = ynew[i]
                k1[i] = k7[i]
            accepted += 1
            proposal = step * (5.0 if error == 0.0 else min(5.0, 0.9 * error ** -0.2))
            h = max(h, proposal) if truncated else proposal
        else:  # rejected; a NaN or infinite error (an overflowed trial step) shrinks the step the most
            h = step * (max(0.2, 0.9 * error ** -0.2) if error < 1e30 else 0.2)
            if h < 1e-14 * max(1.0, abs(t)):
                raise RuntimeError("integration step size underflow")
    work[0] = h
    return accepted


def make_work(state_size: int) -> np.ndarray:
    """Scratch array for :func:`advance` with a state of ``state_size`` (N + 1) entries."""
    return np.zeros(9 * state_size + 1)


def default_atol(n_stories: int, displacement_m: float = 1e-9, velocity_m_s: float = 1e-8, nu: float = 1e-7) -> np.ndarray:
    """Absolute tolerances for (Z, nu): displacements, velocities, hysteretic variable."""
    size = 2 * n_stories + 2
    atol = np.empty(size + 1)
    atol[: size // 2] = displacement_m
    atol[size // 2 : size] = velocity_m_s
    atol[size] = nu
    return atol
