"""The ``rig:`` section of a profile: the virtual rig's sensors, actuator, drive and faults.

Every field names its unit. Sensor imperfections are set per signal group
(displacement, velocity, acceleration); the actuator is ideal, a first-order lag
or a second-order servo; scheduled faults use the ids of :mod:`harness.rig.faults`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any, Literal

from harness.config.input_limits import MAX_SEED
from harness.config.schema import quantity
from harness.hydraulics.config import CylinderConfig, HydraulicActuatorConfig, TableConfig, VelocityFeedforwardConfig
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.rig.faults import fault_id_for

FaultKind = Literal[
    "dropout", "stuck", "spike", "noise_burst", "corrupt_crc", "repeat_counter", "skip_counter",
    "extra_delay", "bus_silence", "drive_fault", "pressure_lost", "estop", "sign_flip", "polarity", "seize",
]
FaultTarget = Literal["", "TABLE_SENSORS", "BASE_SENSORS", "STORY_DRIFTS", "FLOOR_ACCELS", "ACTUATOR_STATUS", "RIG_STATUS"]


def _like(design: type, name: str) -> Any:
    """An optional override field: no value by default, with the design field's unit, range and doc."""
    metadata = next(f.metadata for f in dataclasses.fields(design) if f.name == name)
    return field(default=None, metadata=metadata)


@dataclass(frozen=True)
class StructureTruth:
    """``rig.truth.structure``: the fields of ``structure`` (:class:`BuildingConfig`), each optional."""

    floor_masses_kg: tuple[float, ...] | None = _like(BuildingConfig, "floor_masses_kg")
    base_mass_kg: float | None = _like(BuildingConfig, "base_mass_kg")
    story_stiffness_N_per_m: tuple[float, ...] | None = _like(BuildingConfig, "story_stiffness_N_per_m")
    story_damping_Ns_per_m: tuple[float, ...] | None = _like(BuildingConfig, "story_damping_Ns_per_m")
    first_mode_damping_ratio: float | None = _like(BuildingConfig, "first_mode_damping_ratio")
    restoring_stiffness_N_per_m: float | None = _like(BuildingConfig, "restoring_stiffness_N_per_m")
    assumptions: str | None = _like(BuildingConfig, "assumptions")


@dataclass(frozen=True)
class BearingTruth:
    """``rig.truth.bearing``: the fields of ``bearing`` (:class:`BearingConfig`), each optional."""

    mu_max: float | None = _like(BearingConfig, "mu_max")
    mu_delta: float | None = _like(BearingConfig, "mu_delta")
    a_mu_s_per_m: float | None = _like(BearingConfig, "a_mu_s_per_m")
    yield_displacement_m: float | None = _like(BearingConfig, "yield_displacement_m")
    alpha: float | None = _like(BearingConfig, "alpha")
    beta: float | None = _like(BearingConfig, "beta")
    gamma: float | None = _like(BearingConfig, "gamma")
    eta: float | None = _like(BearingConfig, "eta")


@dataclass(frozen=True)
class ActuatorTruth:
    """``rig.truth.actuator``: the control actuator's hydraulics as the rig really has them, each optional.

    ``rig.actuator`` is what the lab believes of its actuator (the class of equipment, or an
    identification's overlay); these values are the rig's, hidden from everything but the
    virtual rig's plant and ``simulate --rig-effects``' twin. The force loop's gain ``K_p``
    follows the true cylinder: a lab tunes it on its rig to ``force_loop_bandwidth_hz``. The
    servo controller's velocity feed-forward keeps the believed nominal valve gain ``A / q_nl``
    (SPEC 7a'): ``feedforward_gain`` is the fraction the rig's controller is really set to, and
    a true ``valve_flow_m3_per_s`` that differs leaves the mismatch in the plant.
    """

    force_loop_bandwidth_hz: float | None = _like(HydraulicActuatorConfig, "force_loop_bandwidth_hz")
    feedforward_gain: float | None = _like(VelocityFeedforwardConfig, "gain")
    valve_flow_m3_per_s: float | None = _like(CylinderConfig, "valve_flow_m3_per_s")
    bulk_modulus_Pa: float | None = _like(CylinderConfig, "bulk_modulus_Pa")
    valve_bandwidth_hz: float | None = _like(CylinderConfig, "valve_bandwidth_hz")
    valve_damping_ratio: float | None = _like(CylinderConfig, "valve_damping_ratio")
    leakage_m3_per_s_Pa: float | None = _like(CylinderConfig, "leakage_m3_per_s_Pa")


@dataclass(frozen=True)
class TruthConfig:
    """``rig.truth``: the virtual rig's own structure, bearing and actuator values; empty = the rig is the design."""

    structure: StructureTruth = field(default_factory=StructureTruth)
    bearing: BearingTruth = field(default_factory=BearingTruth)
    actuator: ActuatorTruth = field(default_factory=ActuatorTruth)


@dataclass(frozen=True)
class DisplacementSensorConfig:
    """LVDTs and story-drift sensors: x_0, y_b, drift_1..3."""

    noise_std_m: float = quantity(0.0, unit="m", ge=0.0, doc="Gaussian noise standard deviation")
    bias_m: float = quantity(0.0, unit="m", doc="constant offset")
    quantization_m: float = quantity(0.0, unit="m", ge=0.0, doc="quantization step; 0 = none")
    delay_s: float = quantity(0.0, unit="s", ge=0.0, le=1.0, doc="transport delay")

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(noise std, bias, quantization step, delay) in SI."""
        return self.noise_std_m, self.bias_m, self.quantization_m, self.delay_s


@dataclass(frozen=True)
class VelocitySensorConfig:
    """Velocity transducers: xdot_0, ydot_b."""

    noise_std_m_s: float = quantity(0.0, unit="m/s", ge=0.0, doc="Gaussian noise standard deviation")
    bias_m_s: float = quantity(0.0, unit="m/s", doc="constant offset")
    quantization_m_s: float = quantity(0.0, unit="m/s", ge=0.0, doc="quantization step; 0 = none")
    delay_s: float = quantity(0.0, unit="s", ge=0.0, le=1.0, doc="transport delay")

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(noise std, bias, quantization step, delay) in SI."""
        return self.noise_std_m_s, self.bias_m_s, self.quantization_m_s, self.delay_s


@dataclass(frozen=True)
class AccelerationSensorConfig:
    """Accelerometers: xddot_0, yddot_b, floor accelerations 1..3."""

    noise_std_m_s2: float = quantity(0.0, unit="m/s^2", ge=0.0, doc="Gaussian noise standard deviation")
    bias_m_s2: float = quantity(0.0, unit="m/s^2", doc="constant offset")
    quantization_m_s2: float = quantity(0.0, unit="m/s^2", ge=0.0, doc="quantization step; 0 = none")
    delay_s: float = quantity(0.0, unit="s", ge=0.0, le=1.0, doc="transport delay")

    def as_tuple(self) -> tuple[float, float, float, float]:
        """(noise std, bias, quantization step, delay) in SI."""
        return self.noise_std_m_s2, self.bias_m_s2, self.quantization_m_s2, self.delay_s


@dataclass(frozen=True)
class SensorsConfig:
    """The three sensor groups."""

    displacement: DisplacementSensorConfig = field(default_factory=DisplacementSensorConfig)
    velocity: VelocitySensorConfig = field(default_factory=VelocitySensorConfig)
    acceleration: AccelerationSensorConfig = field(default_factory=AccelerationSensorConfig)


@dataclass(frozen=True)
class ActuatorConfig:
    """The actuator between table and base mat.

    ``ideal``, ``first_order`` and ``second_order`` are force sources: the force follows the
    command whatever the base mat does. ``servo_hydraulic`` is the cylinder of SPEC 7a under
    its force loop (``hydraulics``): its force bleeds with the sliding velocity (the natural
    velocity feedback) and saturates with pressure and flow.
    """

    model: Literal["ideal", "first_order", "second_order", "servo_hydraulic"] = quantity("first_order", doc="servo dynamics")
    time_constant_s: float = quantity(0.01, unit="s", gt=0.0, doc="first-order lag time constant")
    bandwidth_hz: float = quantity(30.0, unit="Hz", gt=0.0, doc="second-order natural frequency")
    damping_ratio: float = quantity(0.7, gt=0.0, le=2.0, doc="second-order damping ratio")
    delay_s: float = quantity(0.0, unit="s", ge=0.0, le=1.0, doc="command transport delay")
    force_limit_N: float = quantity(20_000.0, unit="N", gt=0.0, le=30_000.0, doc="largest |force| the actuator delivers")
    force_rate_limit_N_per_s: float = quantity(1.0e6, unit="N/s", gt=0.0, doc="largest |dF/dt|")
    force_noise_N: float = quantity(0.0, unit="N", ge=0.0, doc="load-cell noise std in ACTUATOR_STATUS")
    hydraulics: HydraulicActuatorConfig = field(default_factory=HydraulicActuatorConfig)


@dataclass(frozen=True)
class DriveConfig:
    """Drive-side enable logic and watchdog (wall clock).

    In lockstep the harness paces the rig: a step waits for the harness's command, so a
    host that is merely slow (a busy machine, a debugger) is not a dead harness. The
    watchdog then uses ``lockstep_watchdog_timeout_s`` instead: still wall clock, so a
    harness that died is caught, but long enough that host timing never trips a lockstep
    dry run (no hardware moves in lockstep: the rig is virtual).
    """

    watchdog_timeout_s: float = quantity(0.05, unit="s", gt=0.0, doc="commands/heartbeats older than this trip the drive")
    lockstep_watchdog_timeout_s: float = quantity(
        2.0, unit="s", gt=0.0, le=60.0, doc="the same watchdog in lockstep, where the harness paces the rig"
    )
    decay_time_constant_s: float = quantity(0.02, unit="s", gt=0.0, doc="force decay to zero when the drive is not enabled")


@dataclass(frozen=True)
class FaultSpec:
    """One scheduled fault; times are record time (from table start), see :mod:`harness.rig.faults`."""

    kind: FaultKind = quantity(doc="fault kind")
    target: FaultTarget = quantity("", doc="message the fault acts on (message faults only)")
    start_s: float = quantity(0.0, unit="s", ge=0.0, doc="onset, record time")
    duration_s: float = quantity(0.0, unit="s", ge=0.0, doc="length; 0 = until reset")
    param: float = quantity(0.0, doc="parameter in the SI unit the kind defines")

    def __post_init__(self) -> None:
        fault_id_for(self.kind, self.target)  # a target where one belongs, none elsewhere


@dataclass(frozen=True)
class RigConfig:
    """The virtual rig (profile section ``rig``)."""

    physics_substep_s: float = quantity(0.0005, unit="s", gt=0.0, le=0.01, doc="actuator/plant sub-step; divides the step period")
    seed: int = quantity(0, ge=0, le=MAX_SEED, doc="seed of every random draw (noise)")
    lockstep: bool = field(default=False, metadata={"doc": "start in lockstep mode"})
    base_pinned: bool = field(
        default=False, metadata={"doc": "the base mat is held to the table (blocked actuator), for identification"}
    )
    history_s: float = quantity(60.0, unit="s", ge=0.0, le=3600.0, doc="length of the exact history ring")
    sensors: SensorsConfig = field(default_factory=SensorsConfig)
    actuator: ActuatorConfig = field(default_factory=ActuatorConfig)
    table: TableConfig = field(default_factory=TableConfig)
    drive: DriveConfig = field(default_factory=DriveConfig)
    faults: tuple[FaultSpec, ...] = quantity((), doc="scheduled faults")
    truth: TruthConfig = field(default_factory=TruthConfig, metadata={"doc": "the rig's own structure and bearing values"})
