"""Configuration of the safety layer: the profile's ``safety:`` section.

Every limit is a frozen dataclass field declared with :func:`harness.schema.quantity`,
so it carries its unit (named in the key) and its range. Defaults fit the NCEER
quarter-scale rig (shared/SPEC.md 6b): total weight about 39.5 kN, peak control
force 12-14 % of it (about 5 kN), so a 10 kN force limit leaves a factor of two;
a bearing stroke of a few centimetres (soft 0.05 m, hard 0.075 m).

Cross-field consistency (soft limit inside the hard limit, fade band inside the
gap, ...) is not checked in ``__post_init__`` but by :func:`check_config`, which
returns every problem at once; :class:`~harness.safety.supervisor.Supervisor`
refuses a configuration with problems.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from harness.schema import quantity

#: Actions a detector with a configurable action may take.
DetectorActionName = Literal["indicate", "safe_stop", "trip"]


@dataclass(frozen=True)
class StrokeConfig:
    """Limits on the sliding (bearing) displacement ``x_b = y_b - x_0``."""

    soft_limit_m: float = quantity(0.05, unit="m", gt=0, doc="|x_b| beyond which outward force fades")
    fade_band_m: float = quantity(0.01, unit="m", gt=0, doc="width over which outward force fades to zero")
    hard_limit_m: float = quantity(0.075, unit="m", gt=0, doc="|x_b| at which the run trips")
    stop_time_s: float = quantity(0.1, unit="s", ge=0, doc="look-ahead of the predictive limit: x_b + xdot_b * stop_time_s")
    arm_tolerance_m: float = quantity(0.005, unit="m", gt=0, doc="|x_b| allowed when arming (stroke near centre)")


@dataclass(frozen=True)
class ForceConfig:
    """Limits on the commanded actuator force and on its tracking."""

    max_force_N: float = quantity(10_000.0, unit="N", gt=0, doc="largest |force| ever commanded")
    max_force_rate_N_per_s: float = quantity(400_000.0, unit="N/s", gt=0, doc="largest |d force / dt| commanded")
    tracking_tolerance_N: float = quantity(1_500.0, unit="N", gt=0, doc="|measured - expected force| allowed")
    tracking_time_s: float = quantity(0.1, unit="s", gt=0, doc="how long the tracking error may persist")
    actuator_time_constant_s: float = quantity(0.01, unit="s", ge=0, doc="first-order lag of the actuator (0: none)")
    tracking_action: DetectorActionName = field(default="trip", metadata={"doc": "action on a force-tracking fault"})


@dataclass(frozen=True)
class SensorConfig:
    """Plausibility limits on the four control measurements ``x_0, xdot_0, y_b, ydot_b``."""

    max_sensor_age_s: float = quantity(0.02, unit="s", gt=0, doc="oldest sensor sample the loop may use")
    displacement_range_m: float = quantity(0.2, unit="m", gt=0, doc="|x_0| and |y_b| beyond this are faults")
    velocity_range_m_s: float = quantity(1.5, unit="m/s", gt=0, doc="|xdot_0| and |ydot_b| beyond this are faults")
    jump_limit_m: float = quantity(0.005, unit="m", gt=0, doc="largest displacement change between samples")
    jump_limit_m_s: float = quantity(0.2, unit="m/s", gt=0, doc="largest velocity change between samples")
    stuck_samples: int = quantity(50, ge=2, doc="consecutive bit-identical samples that mean a stuck sensor")
    stuck_table_speed_m_s: float = quantity(0.01, unit="m/s", gt=0, doc="|xdot_0| above which the table is moving")
    disagree_tolerance_m_s: float = quantity(0.05, unit="m/s", gt=0, doc="|filtered dx/dt - filtered v| allowed")
    disagree_time_s: float = quantity(0.05, unit="s", gt=0, doc="how long the disagreement may persist")
    disagree_filter_s: float = quantity(0.02, unit="s", gt=0, doc="time constant of the low-pass on both signals")


@dataclass(frozen=True)
class CommsConfig:
    """Rates of CAN faults tolerated, each as "more than N in a sliding window"."""

    max_e2e_rejects: int = quantity(5, ge=0, doc="counter/CRC rejections allowed per window")
    e2e_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for E2E rejections")
    max_error_frames: int = quantity(10, ge=0, doc="bus error frames allowed per window")
    error_frame_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for error frames")
    error_frame_action: DetectorActionName = field(default="safe_stop", metadata={"doc": "action on too many error frames"})
    error_passive_action: DetectorActionName = field(default="safe_stop", metadata={"doc": "action on error-passive"})
    max_send_failures: int = quantity(2, ge=0, doc="failed sends (ENOBUFS) allowed per window")
    send_failure_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for failed sends")


@dataclass(frozen=True)
class ActuatorConfig:
    """Health of the actuator's servo controller, from its status frames."""

    max_status_age_s: float = quantity(0.05, unit="s", gt=0, doc="oldest actuator status frame accepted")


@dataclass(frozen=True)
class RunConfig:
    """Lifecycle and loop-health settings."""

    stopping_ramp_s: float = quantity(0.5, unit="s", gt=0, doc="time over which STOPPING ramps the force to zero")
    max_consecutive_overruns: int = quantity(3, ge=1, doc="consecutive loop overruns that trip the run")
    event_capacity: int = quantity(256, ge=8, doc="size of the preallocated event ring")


@dataclass(frozen=True)
class SafetyConfig:
    """The whole safety layer's configuration (the profile's ``safety:`` section)."""

    stroke: StrokeConfig = field(default_factory=StrokeConfig)
    force: ForceConfig = field(default_factory=ForceConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    comms: CommsConfig = field(default_factory=CommsConfig)
    actuator: ActuatorConfig = field(default_factory=ActuatorConfig)
    run: RunConfig = field(default_factory=RunConfig)


def _positive_problems(config: SafetyConfig) -> list[str]:
    """Zero, negative or non-finite values, for configurations built without the schema."""
    problems = []
    groups = {
        "stroke": config.stroke, "force": config.force, "sensors": config.sensors,
        "comms": config.comms, "actuator": config.actuator, "run": config.run,
    }
    may_be_zero = {"stop_time_s", "actuator_time_constant_s", "max_e2e_rejects", "max_error_frames", "max_send_failures"}
    for group_name, group in groups.items():
        for name, value in vars(group).items():
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                continue
            if value != value or value in (float("inf"), float("-inf")):
                problems.append(f"{group_name}.{name} is {value!r}, expected a finite number")
            elif name in may_be_zero and value < 0:
                problems.append(f"{group_name}.{name} is {value:g}, expected >= 0")
            elif name not in may_be_zero and value <= 0:
                problems.append(f"{group_name}.{name} is {value:g}, expected > 0")
    return problems


def _stroke_problems(stroke: StrokeConfig, sensors: SensorConfig) -> list[str]:
    problems = []
    soft, hard, band = stroke.soft_limit_m, stroke.hard_limit_m, stroke.fade_band_m
    if soft >= hard:
        problems.append(f"stroke.soft_limit_m ({soft:g} m) is not inside stroke.hard_limit_m ({hard:g} m)")
    elif band > (hard - soft) * (1.0 + 1e-9):
        problems.append(
            f"stroke.fade_band_m ({band:g} m) is wider than the soft-to-hard gap ({hard - soft:g} m): "
            "force would still push outward at the hard limit"
        )
    if stroke.arm_tolerance_m >= soft:
        problems.append(
            f"stroke.arm_tolerance_m ({stroke.arm_tolerance_m:g} m) is not inside "
            f"stroke.soft_limit_m ({soft:g} m)"
        )
    if sensors.displacement_range_m <= hard:
        problems.append(
            f"sensors.displacement_range_m ({sensors.displacement_range_m:g} m) does not exceed "
            f"stroke.hard_limit_m ({hard:g} m): a valid stroke would read as a sensor fault"
        )
    return problems


def _force_problems(force: ForceConfig, run: RunConfig) -> list[str]:
    problems = []
    if force.tracking_tolerance_N >= 2 * force.max_force_N:
        problems.append(
            f"force.tracking_tolerance_N ({force.tracking_tolerance_N:g} N) is at least twice force.max_force_N "
            f"({force.max_force_N:g} N): the tracking detector could never act"
        )
    ramp_needed = force.max_force_N / force.max_force_rate_N_per_s
    if run.stopping_ramp_s < ramp_needed:
        problems.append(
            f"run.stopping_ramp_s ({run.stopping_ramp_s:g} s) is shorter than max_force_N / max_force_rate_N_per_s "
            f"({ramp_needed:g} s): the rate limit, not the ramp, would set the stop"
        )
    return problems


def check_config(config: SafetyConfig) -> list[str]:
    """Return every consistency problem of a safety configuration (empty when consistent).

    Parameters
    ----------
    config : SafetyConfig
        The configuration to check.

    Returns
    -------
    list of str
        One sentence per problem, naming the keys, what was found and what was expected.
    """
    problems = _positive_problems(config)
    if problems:
        return problems
    return _stroke_problems(config.stroke, config.sensors) + _force_problems(config.force, config.run)
