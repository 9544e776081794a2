"""The servo-hydraulic equipment's settings (``rig.actuator.hydraulics``, ``rig.table``): settings only.

The cylinder, the servo controller's force loop and velocity feed-forward, and the table's
servo, as a profile states them; :mod:`harness.hydraulics.cylinder` packs them for the
compiled plant and :mod:`harness.hydraulics.linear` holds the relations the methods here use.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from harness.config.schema import quantity
from harness.hydraulics import linear

#: The relief valves pass the valve's whole no-load flow at this over-pressure (share of p_s).
RELIEF_OVERPRESSURE = 0.02


@dataclass(frozen=True)
class StrokeLvdtConfig:
    """The actuator's own stroke LVDT as its servo controller reads it."""

    noise_std_m: float = quantity(3.0e-6, unit="m", ge=0.0, le=1.0e-3, doc="white noise std of the stroke reading")
    quantization_m: float = quantity(3.1e-6, unit="m", ge=0.0, le=1.0e-3, doc="conditioning's step (0: none)")
    delay_s: float = quantity(5.0e-4, unit="s", ge=0.0, le=0.05, doc="conversion and demodulation delay")


@dataclass(frozen=True)
class VelocityFeedforwardConfig:
    """``rig.actuator.hydraulics.feedforward``: the servo controller's velocity feed-forward."""

    gain: float = quantity(1.0, ge=0.0, le=1.5, doc="alpha, fraction of nominal cancellation A / (K_q K_v) (0: none)")
    velocity_filter_hz: float = quantity(
        50.0, unit="Hz", gt=0.0, le=2000.0, doc="corner of the first-order low-pass on the LVDT's derivative",
    )
    lvdt: StrokeLvdtConfig = field(default_factory=StrokeLvdtConfig)


@dataclass(frozen=True)
class CylinderConfig:
    """A servo-valve driven, double-acting cylinder (defaults: a 15 kN laboratory actuator).

    The defaults are the class of equipment of the control actuator between a shaking table
    and a quarter-scale model's base mat; ``profiles/nceer_4dof.yaml`` derives each value.
    """

    supply_pressure_Pa: float = quantity(20.7e6, unit="Pa", gt=0.0, doc="p_s, supply pressure")
    piston_area_m2: float = quantity(7.25e-4, unit="m^2", gt=0.0, doc="A, effective piston area")
    oil_volume_m3: float = quantity(1.78e-4, unit="m^3", gt=0.0, doc="V_t, trapped oil of both chambers, manifold and hoses")
    bulk_modulus_Pa: float = quantity(1.0e9, unit="Pa", gt=0.0, doc="beta_e, effective bulk modulus (oil, hoses, air)")
    leakage_m3_per_s_Pa: float = quantity(4.0e-14, unit="m^3/s/Pa", ge=0.0, doc="C_l, cross-piston leakage")
    valve_flow_m3_per_s: float = quantity(9.5e-4, unit="m^3/s", gt=0.0, doc="q_nl, no-load flow at full opening")
    valve_bandwidth_hz: float = quantity(75.0, unit="Hz", gt=0.0, doc="servo-valve natural frequency")
    valve_damping_ratio: float = quantity(0.7, gt=0.0, le=2.0, doc="servo-valve damping ratio")

    @property
    def hydraulic_stiffness_N_per_m(self) -> float:
        """``k_h = 4 beta_e A^2 / V_t`` (N/m): the oil column's stiffness, blocked valve."""
        return linear.hydraulic_stiffness_N_per_m(self.bulk_modulus_Pa, self.piston_area_m2, self.oil_volume_m3)

    @property
    def force_capacity_N(self) -> float:
        """``A p_s`` (N): the largest force, with the whole supply across the piston."""
        return self.piston_area_m2 * self.supply_pressure_Pa

    @property
    def pressure_gain_Pa_per_m3(self) -> float:
        """``4 beta_e / V_t`` (Pa/m^3)."""
        return linear.pressure_gain_Pa_per_m3(self.bulk_modulus_Pa, self.oil_volume_m3)

    def packed(self) -> tuple[float, ...]:
        """The cylinder's block of :func:`pack_rig` (order of the offsets AREA ... RELIEF)."""
        return (
            self.piston_area_m2, self.supply_pressure_Pa, self.pressure_gain_Pa_per_m3, self.leakage_m3_per_s_Pa,
            self.valve_flow_m3_per_s, linear.angular_frequency_rad_s(self.valve_bandwidth_hz), self.valve_damping_ratio,
            self.valve_flow_m3_per_s / (RELIEF_OVERPRESSURE * self.supply_pressure_Pa),
        )


def _table_cylinder() -> CylinderConfig:
    return CylinderConfig(
        piston_area_m2=1.18e-2, oil_volume_m3=4.0e-3, leakage_m3_per_s_Pa=4.0e-13,
        valve_flow_m3_per_s=1.55e-2, valve_bandwidth_hz=50.0,
    )


@dataclass(frozen=True)
class HydraulicActuatorConfig:
    """The control actuator's cylinder and its force loop (``rig.actuator.hydraulics``)."""

    cylinder: CylinderConfig = field(default_factory=CylinderConfig)
    force_loop_bandwidth_hz: float = quantity(
        20.0, unit="Hz", gt=0.0, le=200.0, doc="force loop bandwidth on a blocked piston; sets K_p",
    )
    feedforward: VelocityFeedforwardConfig = field(default_factory=VelocityFeedforwardConfig)

    def bandwidth_rad_s(self) -> float:
        """``w_f = 2 pi force_loop_bandwidth_hz`` (rad/s): the force loop's bandwidth on a blocked piston."""
        return linear.angular_frequency_rad_s(self.force_loop_bandwidth_hz)

    def force_gain_per_N(self) -> float:
        """``K_p = w_f V_t / (4 beta_e A q_nl)`` (1/N): normalized valve current per newton of force error."""
        c = self.cylinder
        return linear.force_gain_per_N(self.bandwidth_rad_s(), c.pressure_gain_Pa_per_m3, c.piston_area_m2, c.valve_flow_m3_per_s)

    def loop_damping_Ns_per_m(self) -> float:
        """``k_h / w_f`` (N s/m): the force loop's parasitic damping between table and base mat.

        At frequencies well below the force loop's bandwidth the actuator's force is
        ``u_cmd - (k_h / w_f) xdot_b``: the natural velocity feedback, which the proportional
        force loop reduces only by its own gain.
        """
        return linear.loop_damping_Ns_per_m(self.cylinder.hydraulic_stiffness_N_per_m, self.bandwidth_rad_s())

    def feedforward_current_per_m_s(self) -> float:
        """``A / q_nl`` (s/m): the normalized valve current that passes the flow of 1 m/s of stroke at no load."""
        return linear.feedforward_current_per_m_s(self.cylinder.piston_area_m2, self.cylinder.valve_flow_m3_per_s)

    def velocity_feedback_Ns_per_m(self) -> float:
        """``c_eff = (1 - alpha) k_h / w_f`` (N s/m): the velocity feedback left at no load with the feed-forward.

        The force lost per m/s of stroke at low frequency and zero load pressure, the feed-forward
        acting on the nominal valve gain (SPEC 7a'); :func:`harness.hydraulics.servo_controller.steady_bleed_N`
        gives it at a load pressure.
        """
        return linear.velocity_feedback_Ns_per_m(
            self.cylinder.hydraulic_stiffness_N_per_m, self.bandwidth_rad_s(), self.feedforward.gain,
        )

    def feedback_stiffness_N_per_m(self) -> float:
        """``(1 - alpha) k_h = c_eff w_f`` (N/m): the gain on the stroke velocity in the first-order model (A1) (SPEC 7a')."""
        return linear.velocity_feedback_stiffness_N_per_m(self.velocity_feedback_Ns_per_m(), self.bandwidth_rad_s())


@dataclass(frozen=True)
class TableConfig:
    """The shaking table under its payload (``rig.table``).

    ``motion_source``: the table follows the drive exactly (the rig of earlier versions).
    ``servo_hydraulic``: a platform of ``platform_mass_kg`` on its own cylinder under
    three-variable control; it feels the bearings', springs' and control actuator's reactions.
    """

    model: Literal["motion_source", "servo_hydraulic"] = quantity("motion_source", doc="table dynamics")
    platform_mass_kg: float = quantity(6000.0, unit="kg", gt=0.0, doc="m_t, moving mass of platform and actuator pistons")
    position_loop_bandwidth_hz: float = quantity(5.0, unit="Hz", gt=0.0, le=100.0, doc="w_x / 2 pi, displacement loop")
    pressure_feedback_damping_ratio: float = quantity(
        0.4, ge=0.0, le=2.0, doc="Delta-P feedback's damping of the bare table's oil column",
    )
    cylinder: CylinderConfig = field(default_factory=_table_cylinder)

    def oil_column_hz(self) -> float:
        """Oil-column frequency of the bare platform, ``sqrt(k_h / m_t) / 2 pi`` (Hz)."""
        return math.sqrt(self.cylinder.hydraulic_stiffness_N_per_m / self.platform_mass_kg) / (2.0 * math.pi)

    def pressure_feedback_m3_per_s_Pa(self) -> float:
        """``C_dp = 2 zeta_dp w_oil V_t / (4 beta_e)`` (m^3/(s Pa))."""
        omega_oil = linear.angular_frequency_rad_s(self.oil_column_hz())
        return 2.0 * self.pressure_feedback_damping_ratio * omega_oil / self.cylinder.pressure_gain_Pa_per_m3
