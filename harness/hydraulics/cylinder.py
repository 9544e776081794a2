"""Servo-hydraulic cylinders: the control actuator in force control, the table in displacement control.

The standard model of a servo-valve driven, double-acting cylinder (Merritt, Hydraulic
Control Systems, 1967), as used for control-structure interaction on the same kind of
quarter-scale model by Dyke, Spencer, Quast & Sain (J. Eng. Mech. 121(2), 1995)::

    valve flow (turbulent orifice):  q = q_nl x_v sqrt((p_s - sign(x_v) p_L) / p_s),  |x_v| <= 1
    oil column (continuity):         (V_t / (4 beta_e)) dp_L/dt = q - A xdot - C_l p_L
    force on the load:               F = A p_L
    spool (servo-valve):             x_v'' + 2 zeta_v w_v x_v' + w_v^2 x_v = w_v^2 i,   |i| <= 1

``x_v`` and ``i`` are normalized (1 = full opening, full rated current), so ``q_nl`` is
the valve's no-load flow at full opening with the whole supply pressure across it and
``q_nl / A`` the fastest the piston can move. The relief (and anti-cavitation) valves hold
``|p_L|`` at ``p_s``: beyond it they pass ``q_r = C_r (|p_L| - p_s)``, with ``C_r`` sized to
pass the valve's whole flow ``q_nl`` at 2 % over-pressure, which bounds the force at
``A p_s`` (to 2 %) without a discontinuity the integrator would stumble on.

In force terms ``dF/dt = (4 beta_e A / V_t)(q - C_l F / A) - k_h xdot`` with the hydraulic
stiffness ``k_h = 4 beta_e A^2 / V_t``: the last term is the natural velocity feedback.
Any motion of the piston bleeds force unless the valve supplies the matching flow. The
loop's linearised relations (``k_h``, ``K_p``, ``k_h / w_f`` ...) are written once, in
:mod:`harness.hydraulics.linear`; the configurations here call them.

The two servo loops:

- control actuator (table to base mat), force loop on the load cell with velocity
  feed-forward (SPEC 7a', :func:`force_loop_current`, the one place the law is written):
  ``i = K_p (u_cmd - A p_L) + i_ff``, with ``K_p`` set so that the loop on a blocked piston
  has the bandwidth ``w_f``: ``K_p = w_f V_t / (4 beta_e A q_nl)``, and ``i_ff = alpha A v_s /
  q_nom`` the feed-forward current from the stroke LVDT's filtered derivative
  (:mod:`harness.hydraulics.servo_controller`), held over a sub-step in the packed parameters.
  Disabled (tripped or not armed), the spool is centred and the cross-port bypass opens,
  so the pressure decays with the drive's decay time constant.
- shaking table, three-variable control of the platform (mass ``m_t``): the flow demand is
  the drive's velocity plus the displacement error through the position loop, less a
  differential-pressure (Delta-P) feedback about the pressure that accelerates the bare
  platform, ``q_cmd = A (v_d + w_x (x_d - x_0)) - C_dp (p_L - m_t a_d / A)``, and
  ``i = q_cmd / q_nl``. ``C_dp`` gives the bare table's oil-column mode the damping ratio
  ``zeta_dp``: ``C_dp = 2 zeta_dp w_oil V_t / (4 beta_e)``, ``w_oil = sqrt(k_h / m_t)``.

The compiled functions take the parameters packed in one float array
(:func:`pack_rig`), as the bearing's do, so the integration kernel evaluates the rig's
hydraulics in the same derivative as the building.
"""

from __future__ import annotations

import math

import numba
import numpy as np

from harness.hydraulics import linear
from harness.hydraulics.config import HydraulicActuatorConfig, TableConfig

# ------------------------------------------------------------ packed parameters
#: Flags: the table is a servo-hydraulic platform; the control actuator is servo-hydraulic;
#: the base mat is held to the table; the control actuator's drive is enabled (set per sub-step).
TABLE_DYNAMIC, ACTUATOR_HYDRAULIC, BASE_PINNED, ENABLED = range(4)
#: Offsets of one cylinder's parameters from its block's start.
AREA, SUPPLY, PRESSURE_GAIN, LEAKAGE, VALVE_FLOW, VALVE_OMEGA, VALVE_ZETA, RELIEF = range(8)
_CYLINDER_SIZE = 8
#: Block starts of the control actuator's and the table's cylinders.
ACTUATOR_CYLINDER = 4
ACTUATOR_GAIN = ACTUATOR_CYLINDER + _CYLINDER_SIZE  # K_p, 1/N
ACTUATOR_BYPASS = ACTUATOR_GAIN + 1  # bypass leakage while disabled, m^3/(s Pa)
ACTUATOR_FEEDFORWARD = ACTUATOR_BYPASS + 1  # the servo controller's feed-forward current, held over a sub-step
TABLE_CYLINDER = ACTUATOR_FEEDFORWARD + 1
TABLE_MASS = TABLE_CYLINDER + _CYLINDER_SIZE  # m_t, kg
TABLE_POSITION_GAIN = TABLE_MASS + 1  # w_x, 1/s
TABLE_PRESSURE_FEEDBACK = TABLE_POSITION_GAIN + 1  # C_dp, m^3/(s Pa)
BASE_MASS = TABLE_PRESSURE_FEEDBACK + 1  # m_b, kg
RIG_PARAMETERS = BASE_MASS + 1

# ----------------------------------------------------------- the rig's states
#: Offsets of the rig's states after ``(Z, nu)``: table displacement and velocity, then
#: each cylinder's load pressure, spool position and spool velocity.
TABLE_X, TABLE_V, TABLE_PRESSURE, TABLE_SPOOL, TABLE_SPOOL_RATE, ACTUATOR_PRESSURE, ACTUATOR_SPOOL, ACTUATOR_SPOOL_RATE = range(8)
RIG_STATES = 8


def pack_rig(
    actuator: HydraulicActuatorConfig | None, table: TableConfig, base_mass_kg: float, base_pinned: bool,
    decay_time_constant_s: float,
) -> np.ndarray:
    """The rig's parameters for the compiled derivative.

    Parameters
    ----------
    actuator : HydraulicActuatorConfig or None
        The control actuator's hydraulics; None when the actuator is a force source.
    table : TableConfig
    base_mass_kg : float
        m_b (kg), for the pinned base mat riding on a dynamic table.
    base_pinned : bool
        The base mat is held to the table (blocked actuator).
    decay_time_constant_s : float
        The drive's force decay while disabled (s): sets the bypass that dumps the pressure.
    """
    rig = np.zeros(RIG_PARAMETERS)
    rig[TABLE_DYNAMIC] = 1.0 if table.model == "servo_hydraulic" else 0.0
    rig[BASE_PINNED] = 1.0 if base_pinned else 0.0
    rig[ENABLED] = 0.0
    if actuator is not None:
        rig[ACTUATOR_HYDRAULIC] = 1.0
        rig[ACTUATOR_CYLINDER : ACTUATOR_CYLINDER + _CYLINDER_SIZE] = actuator.cylinder.packed()
        rig[ACTUATOR_GAIN] = actuator.force_gain_per_N()
        # Blocked piston, spool centred: dp/dt = -(4 beta / V_t) C_bypass p decays with the drive's time constant.
        rig[ACTUATOR_BYPASS] = 1.0 / (decay_time_constant_s * actuator.cylinder.pressure_gain_Pa_per_m3)
    rig[TABLE_CYLINDER : TABLE_CYLINDER + _CYLINDER_SIZE] = table.cylinder.packed()
    rig[TABLE_MASS] = table.platform_mass_kg
    rig[TABLE_POSITION_GAIN] = linear.angular_frequency_rad_s(table.position_loop_bandwidth_hz)
    rig[TABLE_PRESSURE_FEEDBACK] = table.pressure_feedback_m3_per_s_Pa()
    rig[BASE_MASS] = base_mass_kg
    return rig


def rig_atol(pressure_Pa: float = 1.0, spool: float = 1e-7, spool_rate_per_s: float = 1e-4,
             displacement_m: float = 1e-9, velocity_m_s: float = 1e-8) -> np.ndarray:
    """Absolute tolerances of the rig's states (order of TABLE_X ... ACTUATOR_SPOOL_RATE)."""
    cylinder = (pressure_Pa, spool, spool_rate_per_s)
    return np.array((displacement_m, velocity_m_s, *cylinder, *cylinder))


@numba.njit(cache=True, nogil=True)
def force_loop_current(gain_per_N: float, command_N: float, measured_N: float, feedforward: float) -> float:
    """The servo controller's law (SPEC 7a'): ``i = K_p (u_cmd - u_meas) + i_ff`` (normalized current).

    ``i_ff = alpha A v_s / q_nom`` is the velocity feed-forward
    (:class:`harness.hydraulics.servo_controller.StrokeVelocityFeedforward`), 0 for a plain loop.
    """
    return gain_per_N * (command_N - measured_N) + feedforward


@numba.njit(cache=True, nogil=True)
def valve_flow(spool: float, load_pressure: float, rig: np.ndarray, block: int) -> float:
    """Orifice flow (m^3/s) through the valve of the cylinder at ``block`` (spool clipped to its stops)."""
    opening = min(max(spool, -1.0), 1.0)
    supply = rig[block + SUPPLY]
    drop = supply - load_pressure if opening >= 0.0 else supply + load_pressure
    if drop <= 0.0:
        return 0.0
    return rig[block + VALVE_FLOW] * opening * math.sqrt(drop / supply)


@numba.njit(cache=True, nogil=True)
def cylinder_rates(
    y: np.ndarray, out: np.ndarray, first: int, current: float, piston_velocity: float, extra_leakage: float,
    rig: np.ndarray, block: int,
) -> None:
    """Rates of one cylinder's ``(p_L, x_v, x_v')`` at ``y[first:first + 3]`` into ``out``.

    ``current`` is the normalized valve current (clipped to +-1, the amplifier's range),
    ``piston_velocity`` the piston's velocity relative to the cylinder (m/s) and
    ``extra_leakage`` an added cross-port leakage (m^3/(s Pa), the bypass).
    """
    pressure, spool, spool_rate = y[first], y[first + 1], y[first + 2]
    flow = valve_flow(spool, pressure, rig, block)
    rate = rig[block + PRESSURE_GAIN] * (
        flow - rig[block + AREA] * piston_velocity - (rig[block + LEAKAGE] + extra_leakage) * pressure
    )
    excess = abs(pressure) - rig[block + SUPPLY]
    if excess > 0.0:  # the relief valves
        rate -= rig[block + PRESSURE_GAIN] * rig[block + RELIEF] * math.copysign(excess, pressure)
    out[first] = rate
    omega = rig[block + VALVE_OMEGA]
    command = min(max(current, -1.0), 1.0)
    out[first + 1] = spool_rate
    out[first + 2] = omega * omega * (command - spool) - 2.0 * rig[block + VALVE_ZETA] * omega * spool_rate
