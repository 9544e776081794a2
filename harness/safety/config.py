"""Configuration of the safety layer: the profile's ``safety:`` section.

Every limit is a frozen dataclass field declared with :func:`harness.config.schema.quantity`,
so it carries its unit (named in the key) and its range. Defaults fit the NCEER
quarter-scale rig (SPEC 6b): total weight about 39.5 kN, peak control
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

from harness.config.input_limits import MAX_EVENT_CAPACITY, MAX_WINDOW_COUNT
from harness.config.schema import quantity

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

    max_force_N: float = quantity(
        10_000.0, unit="N", gt=0, doc="largest |force| the harness asks for (the setpoint, before harness-side compensation)",
    )
    # The flow term a harness-side compensator adds on top of the setpoint has its own bound, and the
    # load cell is watched against its own (docs/SAFETY.md, "What max_force_N must bound").
    max_flow_term_N: float = quantity(
        5_000.0, unit="N", gt=0, le=1.0e6,
        doc="largest |command - setpoint| a harness-side compensator may add (its flow term and correction)",
    )
    load_cell_limit_N: float = quantity(
        12_500.0, unit="N", gt=0, le=1.0e7, doc="|load-cell force| beyond which, held load_cell_limit_time_s, the run trips",
    )
    load_cell_limit_time_s: float = quantity(
        0.01, unit="s", gt=0, le=1.0, doc="how long the load cell may stay beyond load_cell_limit_N",
    )
    max_force_rate_N_per_s: float = quantity(400_000.0, unit="N/s", gt=0, doc="largest |d force / dt| commanded")
    tracking_tolerance_N: float = quantity(1_500.0, unit="N", gt=0, doc="|measured - expected force| allowed")
    tracking_time_s: float = quantity(0.1, unit="s", gt=0, doc="how long the tracking error may persist")
    actuator_time_constant_s: float = quantity(0.01, unit="s", ge=0, doc="first-order lag of the actuator (0: none)")
    velocity_feedback_Ns_per_m: float = quantity(
        0.0, unit="N*s/m", ge=0, le=1.0e6,
        doc="force the actuator loses per m/s of sliding velocity (k_h / w_f of a servo-hydraulic force loop; 0: a force source)",
    )
    velocity_feedforward_gain: float = quantity(
        0.0, ge=0.0, le=1.5,
        doc="share alpha of velocity_feedback_Ns_per_m the servo controller's velocity feed-forward cancels (0: none)",
    )
    supply_force_N: float | None = quantity(
        None, unit="N", gt=0,
        doc="A p_s of the actuator, where the valve's pressure drop vanishes (null: the orifice's dependence left out)",
    )
    tracking_action: DetectorActionName = field(default="trip", metadata={"doc": "action on a force-tracking fault"})
    actuator_rating_N: float | None = quantity(
        None, unit="N", gt=0, doc="rated force of the real rig's actuator; max_force_N may not exceed it (null: not declared)",
    )
    # A sustained oscillation of the force above the controller's band: a limit cycle of the force loop
    # (docs/SAFETY.md, "Sustained oscillation" derives the corner, the window and the limit).
    oscillation_corner_hz: float = quantity(
        30.0, unit="Hz", gt=0, le=1000.0,
        doc="corner of the 2nd-order high-pass on the commanded and measured force: above the controller's band",
    )
    oscillation_window_s: float = quantity(
        0.5, unit="s", gt=0, le=10.0, doc="time constant of the running mean square of the high-passed force",
    )
    oscillation_limit_N: float = quantity(
        475.0, unit="N", gt=0, le=1.0e6,
        doc="RMS of the high-passed commanded or measured force above which the force oscillates (fatigue cut-off)",
    )
    oscillation_action: DetectorActionName = field(
        default="safe_stop", metadata={"doc": "action on a sustained force oscillation"},
    )


@dataclass(frozen=True)
class SensorConfig:
    """Plausibility limits on the four control measurements ``x_0, xdot_0, y_b, ydot_b``."""

    max_sensor_age_s: float = quantity(0.02, unit="s", gt=0, doc="oldest sensor sample the loop may use")
    displacement_range_m: float = quantity(0.2, unit="m", gt=0, doc="|x_0| and |y_b| beyond this are faults")
    velocity_range_m_s: float = quantity(1.5, unit="m/s", gt=0, doc="|xdot_0| and |ydot_b| beyond this are faults")
    jump_limit_m: float = quantity(0.005, unit="m", gt=0, doc="largest displacement change between samples")
    jump_limit_m_s: float = quantity(0.2, unit="m/s", gt=0, doc="largest velocity change between samples")
    # A stuck channel trips at rest too: sensor noise through the conditioning always moves the last
    # bits. 50 samples keep a healthy channel's false-alarm rate below 1e-9 per run while its noise
    # std is at least 0.8 of its quantization step (docs/SAFETY.md, "Stuck sensors" derives it).
    stuck_samples: int = quantity(
        50, ge=2, le=1_000_000, doc="consecutive bit-identical fresh samples that mean a stuck sensor (at rest too)"
    )
    disagree_tolerance_m_s: float = quantity(0.05, unit="m/s", gt=0, doc="|filtered dx/dt - filtered v| allowed")
    disagree_time_s: float = quantity(0.05, unit="s", gt=0, doc="how long the disagreement may persist")
    disagree_filter_s: float = quantity(0.02, unit="s", gt=0, doc="time constant of the low-pass on both signals")
    sign_flip_floor_m_s: float = quantity(
        0.002, unit="m/s", gt=0, le=1.0,
        doc="|filtered dx/dt| and |filtered v| above which opposite signs count as a sign flip",
    )
    sign_flip_time_s: float = quantity(
        0.02, unit="s", gt=0, le=1.0, doc="how long opposite signs (both above the floor) may persist",
    )
    # A polarity fault the sign check cannot see: a damper on the wrong sensor holds the base mat
    # below sign_flip_floor_m_s (docs/SAFETY.md, "A sign flip held below the floor: sensor_polarity").
    polarity_floor_m_s: float = quantity(
        0.00025, unit="m/s", gt=0, le=1.0,
        doc="sqrt of -mean(filtered dx/dt * filtered v) beyond which a pair's polarity is wrong",
    )
    polarity_window_s: float = quantity(
        0.5, unit="s", gt=0, le=10.0, doc="time constant of the running mean of filtered dx/dt * filtered v",
    )


@dataclass(frozen=True)
class CommsConfig:
    """Rates of CAN faults tolerated, each as "more than N in a sliding window"."""

    # Each window preallocates max+1 slots: MAX_WINDOW_COUNT caps them (harness/config/input_limits.py says why).
    max_e2e_rejects: int = quantity(5, ge=0, le=MAX_WINDOW_COUNT, doc="counter/CRC rejections allowed per window")
    e2e_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for E2E rejections")
    max_error_frames: int = quantity(10, ge=0, le=MAX_WINDOW_COUNT, doc="bus error frames allowed per window")
    error_frame_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for error frames")
    error_frame_action: DetectorActionName = field(default="safe_stop", metadata={"doc": "action on too many error frames"})
    error_passive_action: DetectorActionName = field(default="safe_stop", metadata={"doc": "action on error-passive"})
    max_send_failures: int = quantity(2, ge=0, le=MAX_WINDOW_COUNT, doc="failed sends (ENOBUFS) allowed per window")
    send_failure_window_s: float = quantity(1.0, unit="s", gt=0, doc="sliding window for failed sends")


@dataclass(frozen=True)
class ActuatorConfig:
    """Health of the actuator's servo controller, from its status frames."""

    max_status_age_s: float = quantity(0.05, unit="s", gt=0, doc="oldest actuator status frame accepted")


@dataclass(frozen=True)
class RunConfig:
    """Lifecycle and loop-health settings."""

    stopping_ramp_s: float = quantity(0.5, unit="s", gt=0, doc="time over which STOPPING ramps the force to zero")
    max_stall_s: float = quantity(
        0.02, unit="s", gt=0, le=1.0,
        doc="longest time the loop may go without writing a command; a longer stall trips (docs/SAFETY.md derives it)",
    )
    event_capacity: int = quantity(256, ge=8, le=MAX_EVENT_CAPACITY, doc="size of the preallocated event ring")


#: What a trip may do besides zeroing the force: ``disable`` (zero force, drive disabled; always),
#: ``estop`` (assert the ESTOP frame, source 4 supervisor, repeated while TRIPPED), ``stop_table``
#: (RIG_CONTROL stop to the table controller, where the run has a table link).
TripActionName = Literal["disable", "estop", "stop_table"]
#: The classes of checks a trip action is configured for (see :data:`TRIP_CLASS_OF`).
TRIP_CLASSES: tuple[str, ...] = ("stroke", "sensor", "comms", "actuator", "loop", "operator", "internal")
#: Check name -> class of check, for every check that can trip.
TRIP_CLASS_OF: dict[str, str] = {
    "stroke_hard": "stroke", "stroke_predictive": "stroke",
    "sensor_invalid": "sensor", "sensor_stale": "sensor", "sensor_jump": "sensor", "sensor_stuck": "sensor",
    "sensor_disagree": "sensor", "sensor_sign_flip": "sensor",
    "e2e_rejects": "comms", "bus_error_frames": "comms", "bus_error_passive": "comms", "bus_off": "comms",
    "bus_send_failures": "comms", "bus_gone": "comms", "foreign_command": "comms",
    "drive_fault": "actuator", "hydraulic_pressure": "actuator", "actuator_status_stale": "actuator",
    "force_tracking": "actuator", "compensation_fault": "actuator", "force_oscillation": "actuator",
    "load_cell_limit": "actuator", "sensor_polarity": "sensor",
    "loop_stall": "loop", "loop_timing": "loop",
    "estop": "operator", "estop_lost": "operator", "operator_stop": "operator", "operator_trip": "operator",
    "tick_exception": "internal", "controller_output": "internal",
}
_DISABLE_ONLY: tuple[TripActionName, ...] = ("disable",)


def _actions(doc: str) -> tuple[TripActionName, ...]:
    return quantity(_DISABLE_ONLY, min_len=1, doc=doc)


@dataclass(frozen=True)
class TripActionsConfig:
    """What a trip does beyond the controller, per class of check (the profile's ``safety.trip_actions``).

    Each class takes a list from ``disable``, ``estop``, ``stop_table``, as the limit
    detectors of an MTS controller do. ``disable`` (zero force and drive disable, sent first
    in the trip tick) is the default and the minimum: :func:`check_config` refuses a list
    without it. ``estop`` sends the ESTOP frame (source 4, supervisor) in the trip tick,
    after the disable command, and repeats it at ``can.estop_rate_hz`` while TRIPPED.
    ``stop_table`` sends RIG_CONTROL stop in the trip tick where the run has a table link
    (docs/SAFETY.md, "From a trip to each device").
    """

    stroke: tuple[TripActionName, ...] = _actions("on stroke_hard, stroke_predictive")
    sensor: tuple[TripActionName, ...] = _actions("on the sensor_* checks")
    comms: tuple[TripActionName, ...] = _actions("on the e2e_rejects, bus_* and foreign_command checks")
    actuator: tuple[TripActionName, ...] = _actions(
        "on drive_fault, hydraulic_pressure, actuator_status_stale, force_tracking, compensation_fault, "
        "load_cell_limit (force_oscillation when its action trips)"
    )
    loop: tuple[TripActionName, ...] = _actions("on loop_stall, loop_timing")
    operator: tuple[TripActionName, ...] = _actions("on estop, estop_lost, operator_trip (operator_stop when its action trips)")
    internal: tuple[TripActionName, ...] = _actions("on tick_exception, controller_output")

    def for_check(self, name: str) -> tuple[TripActionName, ...]:
        """The actions of the check called ``name`` (``disable`` alone for a name of no class)."""
        group = TRIP_CLASS_OF.get(name)
        return getattr(self, group) if group is not None else _DISABLE_ONLY


@dataclass(frozen=True)
class EStopConfig:
    """The operator E-stop panel's liveness (the profile's ``safety.estop``).

    The panel sends ESTOP frames (source 3) with ``active=0`` at ``can.estop_panel_rate_hz``
    while not pressed, so a panel that is unplugged or dead is told from one that is not
    pressed. 0.2 s is four periods at 20 Hz: three lost frames in a row, plus one period of
    scheduling, are ridden through (docs/SAFETY.md, "E-stop panel liveness").
    """

    panel_required: bool = field(
        default=True,
        metadata={"doc": "a live E-stop panel is required to arm and to run; false is a weakening the run records"},
    )
    max_panel_age_s: float = quantity(
        0.2, unit="s", gt=0, le=10.0, doc="oldest panel ESTOP frame accepted; older trips estop_lost",
    )


@dataclass(frozen=True)
class SafetyConfig:
    """The whole safety layer's configuration (the profile's ``safety:`` section)."""

    stroke: StrokeConfig = field(default_factory=StrokeConfig)
    force: ForceConfig = field(default_factory=ForceConfig)
    sensors: SensorConfig = field(default_factory=SensorConfig)
    comms: CommsConfig = field(default_factory=CommsConfig)
    actuator: ActuatorConfig = field(default_factory=ActuatorConfig)
    run: RunConfig = field(default_factory=RunConfig)
    trip_actions: TripActionsConfig = field(default_factory=TripActionsConfig)
    estop: EStopConfig = field(default_factory=EStopConfig)


def _positive_problems(config: SafetyConfig) -> list[str]:
    """Zero, negative or non-finite values, for configurations built without the schema."""
    problems = []
    groups = {
        "stroke": config.stroke, "force": config.force, "sensors": config.sensors,
        "comms": config.comms, "actuator": config.actuator, "run": config.run, "estop": config.estop,
    }
    may_be_zero = {
        "stop_time_s", "actuator_time_constant_s", "velocity_feedback_Ns_per_m", "velocity_feedforward_gain",
        "max_e2e_rejects", "max_error_frames",
        "max_send_failures",
    }
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


def _stall_problems(config: SafetyConfig) -> list[str]:
    """The stall budget must fit the predictive stroke limit's look-ahead (docs/SAFETY.md, "Stall budget").

    The predictive limit trips when ``x_b + xdot_b * stop_time_s`` reaches the hard limit, so it
    covers a blind time of ``stop_time_s`` minus the actuator's lag. A stall of the loop and the
    age of the newest sensor sample both add blind time, so together they must fit inside it.
    """
    stroke, sensors, run = config.stroke, config.sensors, config.run
    cover_s = stroke.stop_time_s - config.force.actuator_time_constant_s
    blind_s = run.max_stall_s + sensors.max_sensor_age_s
    if blind_s > cover_s * (1.0 + 1e-9):
        return [
            f"run.max_stall_s ({run.max_stall_s * 1e3:.1f} ms) + sensors.max_sensor_age_s "
            f"({sensors.max_sensor_age_s * 1e3:.1f} ms) = {blind_s * 1e3:.1f} ms of blind time exceeds what the "
            f"predictive stroke limit covers, stroke.stop_time_s - force.actuator_time_constant_s = {cover_s * 1e3:.1f} ms: "
            "lower the stall budget or the sensor age, or lengthen stop_time_s (docs/SAFETY.md, Stall budget)"
        ]
    return []


#: Fewest cycles at the oscillation corner the window must hold (docs/SAFETY.md, "Sustained oscillation").
MIN_OSCILLATION_CYCLES = 3.0


def _force_problems(force: ForceConfig, run: RunConfig) -> list[str]:
    problems = []
    cycles = force.oscillation_window_s * force.oscillation_corner_hz
    if cycles < MIN_OSCILLATION_CYCLES:
        problems.append(
            f"force.oscillation_window_s ({force.oscillation_window_s:g} s) holds {cycles:g} cycles at "
            f"force.oscillation_corner_hz ({force.oscillation_corner_hz:g} Hz), expected at least "
            f"{MIN_OSCILLATION_CYCLES:g}: a shorter window takes a transient for an oscillation"
        )
    if force.tracking_tolerance_N >= 2 * force.max_force_N:
        problems.append(
            f"force.tracking_tolerance_N ({force.tracking_tolerance_N:g} N) is at least twice force.max_force_N "
            f"({force.max_force_N:g} N): the tracking detector could never act"
        )
    healthy_N = force.max_force_N + force.tracking_tolerance_N
    if force.load_cell_limit_N <= healthy_N:
        problems.append(
            f"force.load_cell_limit_N ({force.load_cell_limit_N:g} N) is not above force.max_force_N + "
            f"force.tracking_tolerance_N ({healthy_N:g} N): a healthy run at its setpoint limit would trip load_cell_limit"
        )
    if force.supply_force_N is not None and force.max_force_N + force.max_flow_term_N > force.supply_force_N * (1 + 1e-9):
        problems.append(
            f"force.max_force_N + force.max_flow_term_N ({force.max_force_N + force.max_flow_term_N:g} N) exceeds "
            f"force.supply_force_N ({force.supply_force_N:g} N): the command would ask a blocked piston for more than "
            "the cylinder gives, a flow the valve cannot pass (docs/SAFETY.md, What max_force_N must bound)"
        )
    ramp_needed = force.max_force_N / force.max_force_rate_N_per_s
    if run.stopping_ramp_s < ramp_needed:
        problems.append(
            f"run.stopping_ramp_s ({run.stopping_ramp_s:g} s) is shorter than max_force_N / max_force_rate_N_per_s "
            f"({ramp_needed:g} s): the rate limit, not the ramp, would set the stop"
        )
    return problems


def _trip_action_problems(actions: TripActionsConfig) -> list[str]:
    """Every class must keep ``disable``; names must be known and given once."""
    problems = []
    for group in TRIP_CLASSES:
        chosen = getattr(actions, group)
        unknown = [name for name in chosen if name not in ("disable", "estop", "stop_table")]
        if unknown:
            problems.append(f"trip_actions.{group} names {unknown!r}, expected disable, estop or stop_table")
        if "disable" not in chosen:
            problems.append(
                f"trip_actions.{group} is {list(chosen)!r}: disable cannot be removed (a trip always commands "
                "zero force with the drive disabled first)"
            )
        if len(set(chosen)) != len(chosen):
            problems.append(f"trip_actions.{group} is {list(chosen)!r}, expected each action once")
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
    return (
        _stroke_problems(config.stroke, config.sensors) + _force_problems(config.force, config.run)
        + _stall_problems(config) + _trip_action_problems(config.trip_actions)
    )
