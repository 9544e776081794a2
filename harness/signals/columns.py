"""The per-sample columns of every run: each column's name, unit and place, defined once.

One row per loop tick (or per simulated sample) is one line of a run folder's
``signals.csv``. This module is the only place that spells a column name or decides a
column order; every writer and reader uses the names below:

- the control loop (:class:`harness.loop.tick.ControlTick`) fills :data:`CONTROL_ROW`
  through positions looked up here by name, once; ``harness run`` and ``harness dry-run``
  record that row as ``signals.csv``, in that order;
- the plant (:meth:`harness.model.plant.Plant.responses`) derives :func:`plant_columns`;
- the offline simulator (:func:`harness.simulation.case.run_case`) adds what the controller
  computed: :func:`simulation_columns`;
- the rig twin (:func:`harness.simulation.twin.run_rig_twin`) records what a dry run measures:
  :data:`TWIN_COLUMNS`;
- readers and reports find stories and units with :func:`count_stories` and :func:`unit_of`.

Why a module of its own, in a package that imports nothing: the model, the loop, the twin and the
recorder all need the names, and none should import another's package for them (importing
:mod:`harness.recording` starts the recorder's machinery; the model is pure). This module
imports nothing. The recording package re-exports its names for run-folder users.

Every name ends in its unit (``_m``, ``_m_s``, ``_m_s2``, ``_N``, ``_s``) or is
dimensionless. Stories are numbered from 1 at the bottom (story 1 sits on the base mat).
A run may lack any column except ``t_s``.

Two columns hold the bearings' hysteretic variable nu (dimensionless): ``hysteretic_nu``
is the plant's own state (simulation and twin: the model's truth) and ``estimated_nu`` the
friction estimator's (the control loop's row: all a rig can know).
"""

from __future__ import annotations

from typing import Final

#: Stories the CAN protocol's story messages carry (STORY_DRIFTS: drift_1..3, FLOOR_ACCELS:
#: accel_1..3 in drivers/protocol/rig.dbc): the loop's row, the rig and its twin have this many.
PROTOCOL_STORIES: Final = 3

# ---------------------------------------------------------------------------- names
TIME: Final = "t_s"
STATE: Final = "state"  #: the supervisor's lifecycle state code (harness.safety.lifecycle.State)

TABLE_DISPLACEMENT: Final = "table_displacement_m"
TABLE_VELOCITY: Final = "table_velocity_m_s"
TABLE_ACCELERATION: Final = "table_acceleration_m_s2"
BASE_DISPLACEMENT: Final = "base_displacement_m"
BASE_VELOCITY: Final = "base_velocity_m_s"
BASE_ACCELERATION: Final = "base_acceleration_m_s2"
SLIDING_DISPLACEMENT: Final = "sliding_displacement_m"
SLIDING_VELOCITY: Final = "sliding_velocity_m_s"

FRICTION_FORCE: Final = "friction_force_N"  #: the plant's bearing friction (N)
HYSTERETIC_NU: Final = "hysteretic_nu"  #: the plant's hysteretic variable nu (-)
ESTIMATED_NU: Final = "estimated_nu"  #: the friction estimator's nu (-)
FRICTION_ESTIMATE: Final = "friction_estimate_N"
SLIDING_VARIABLE: Final = "sliding_variable_m_s"
EQUIVALENT_FORCE: Final = "equivalent_force_N"
FORCE_RAW: Final = "force_raw_N"  #: the controller's force, before the supervisor
FORCE_COMMAND: Final = "force_command_N"  #: the supervised (or, offline, applied) command
FORCE_MEASURED: Final = "force_measured_N"  #: the actuator's force

DRIVE_ENABLED: Final = "drive_enabled"
DRIVE_STATE: Final = "drive_state"
INTERLOCK_FLAGS: Final = "interlock_flags"

LATENESS: Final = "lateness_s"
COMPUTE: Final = "compute_s"
OVERRUN: Final = "overrun"  #: missed periods before the tick (harness.signals.timing_counts)

E2E_REJECTS: Final = "e2e_rejects"
ERROR_FRAMES: Final = "error_frames"
SEND_FAILURES: Final = "send_failures"


def drift(story: int) -> str:
    """Column name of story ``story``'s interstory drift (m), stories from 1."""
    return f"drift_{story}_m"


def floor_acceleration(floor: int) -> str:
    """Column name of floor ``floor``'s absolute acceleration (m/s^2), floors from 1."""
    return f"floor_acceleration_{floor}_m_s2"


# ---------------------------------------------------------------------------- groups
TABLE: Final[tuple[str, ...]] = (TABLE_DISPLACEMENT, TABLE_VELOCITY, TABLE_ACCELERATION)
BASE: Final[tuple[str, ...]] = (BASE_DISPLACEMENT, BASE_VELOCITY, BASE_ACCELERATION)
SLIDING: Final[tuple[str, ...]] = (SLIDING_DISPLACEMENT, SLIDING_VELOCITY)
BEARING: Final[tuple[str, ...]] = (FRICTION_FORCE, HYSTERETIC_NU)
CONTROLLER: Final[tuple[str, ...]] = (
    FRICTION_ESTIMATE, SLIDING_VARIABLE, EQUIVALENT_FORCE, FORCE_RAW, FORCE_COMMAND, FORCE_MEASURED,
)
SUPERVISOR: Final[tuple[str, ...]] = (DRIVE_ENABLED, STATE, INTERLOCK_FLAGS)
TIMING: Final[tuple[str, ...]] = (LATENESS, COMPUTE, OVERRUN)
BUS: Final[tuple[str, ...]] = (E2E_REJECTS, ERROR_FRAMES, SEND_FAILURES)


def story_columns(n_stories: int) -> tuple[str, ...]:
    """Every story's drift (m), then every floor's absolute acceleration (m/s^2), from story 1 up."""
    stories = range(1, n_stories + 1)
    return (*(drift(j) for j in stories), *(floor_acceleration(j) for j in stories))


def motion_columns(n_stories: int) -> tuple[str, ...]:
    """Time, table, base mat, sliding (base minus table) and story columns: the motion of a run."""
    return (TIME, *TABLE, *BASE, *SLIDING, *story_columns(n_stories))


# ---------------------------------------------------------------------------- what each writer records
#: The signals the rig's sensor messages carry (TABLE_SENSORS, BASE_SENSORS, STORY_DRIFTS,
#: FLOOR_ACCELS), in message order: the order of :data:`harness.rig.sensors.SIGNALS`.
SENSOR_COLUMNS: Final[tuple[str, ...]] = (*TABLE, *BASE, *story_columns(PROTOCOL_STORIES))

#: The control loop's row, one per tick: ``signals.csv`` of ``harness run`` and ``harness dry-run``.
CONTROL_ROW: Final[tuple[str, ...]] = (
    TIME,
    STATE,
    *TABLE,
    *BASE,
    *SLIDING,
    *story_columns(PROTOCOL_STORIES),
    ESTIMATED_NU,
    FRICTION_ESTIMATE,
    SLIDING_VARIABLE,
    EQUIVALENT_FORCE,
    FORCE_RAW,
    FORCE_COMMAND,
    DRIVE_ENABLED,
    FORCE_MEASURED,
    DRIVE_STATE,
    INTERLOCK_FLAGS,
    *TIMING,
    *BUS,
)

#: Column name -> position in :data:`CONTROL_ROW`.
CONTROL_ROW_INDEX: Final[dict[str, int]] = {name: i for i, name in enumerate(CONTROL_ROW)}

#: What the offline simulator records per sample of a controlled case, after the plant's columns.
SIMULATED_CONTROL: Final[tuple[str, ...]] = (SLIDING_VARIABLE, EQUIVALENT_FORCE, FRICTION_ESTIMATE, FORCE_RAW)

#: What the rig twin records per sample besides the sensors (``force_measured_N`` is the actuator's force).
TWIN_CONTROL: Final[tuple[str, ...]] = (SLIDING_VARIABLE, FRICTION_ESTIMATE, FORCE_RAW, FORCE_COMMAND, FORCE_MEASURED)

#: The rig twin's columns: measured motion as a dry run records it, the plant's true bearing state, the control.
TWIN_COLUMNS: Final[tuple[str, ...]] = (*motion_columns(PROTOCOL_STORIES), *BEARING, *TWIN_CONTROL)


def plant_columns(n_stories: int) -> tuple[str, ...]:
    """The columns :meth:`harness.model.plant.Plant.responses` derives, in order: motion, then bearing."""
    return (*motion_columns(n_stories), *BEARING)


def simulation_columns(n_stories: int, controlled: bool) -> tuple[str, ...]:
    """The columns of an offline simulated case, in ``signals.csv`` order.

    Parameters
    ----------
    n_stories : int
        Stories of the building.
    controlled : bool
        The case has a controller (its internals are recorded); otherwise it is passive.
    """
    return (*plant_columns(n_stories), *(SIMULATED_CONTROL if controlled else ()), FORCE_COMMAND)


def canonical_columns(n_stories: int, *, timing: bool = True) -> tuple[str, ...]:
    """The columns a report reads for an ``n_stories`` building, in the recommended order.

    Parameters
    ----------
    n_stories : int
        Number of stories (>= 1).
    timing : bool
        Include the loop-timing columns (real-time runs).

    Returns
    -------
    tuple of str
    """
    if n_stories < 1:
        raise ValueError(f"found n_stories={n_stories}, expected at least 1")
    names = (*motion_columns(n_stories), *BEARING, *CONTROLLER, *SUPERVISOR)
    return names + (TIMING if timing else ())


# ---------------------------------------------------------------------------- reading names back
#: Suffix -> SI unit, longest suffix first so ``_m_s2`` wins over ``_m``.
_SUFFIX_UNITS: Final[tuple[tuple[str, str], ...]] = (
    ("_m_s2", "m/s^2"),
    ("_m_s", "m/s"),
    ("_m", "m"),
    ("_N", "N"),
    ("_s", "s"),
)


def count_stories(columns: tuple[str, ...] | list[str]) -> int:
    """Number of stories with a drift column: the largest ``j`` with ``drift_j_m`` present (0 if none)."""
    highest = 0
    for name in columns:
        if name.startswith("drift_") and name.endswith("_m"):
            middle = name[len("drift_") : -len("_m")]
            if middle.isdigit():
                highest = max(highest, int(middle))
    return highest


def unit_of(name: str) -> str:
    """SI unit a column name carries (``"1"`` for dimensionless names such as ``state``)."""
    for suffix, unit in _SUFFIX_UNITS:
        if name.endswith(suffix):
            return unit
    return "1"
