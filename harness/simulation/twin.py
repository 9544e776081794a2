"""The rig twin: ``harness simulate --rig-effects``, the offline simulation with the virtual rig's imperfections.

The same models the virtual rig serves on the bus, without the bus and without a
clock: the table and plant (:class:`~harness.rig.table.TablePlant`), the sensors
(noise, bias, quantization, delay: :class:`~harness.rig.sensors.SensorModel`), the
servo actuator (transport delay, dynamics, force and rate limits:
:class:`~harness.rig.actuator.ServoActuator`) on the rig's physics sub-step, and the
safety supervisor between the controller and the actuator (force clamp, rate limit,
stroke fade; trips end the case). Each sample runs the loop's tick's step,
:func:`harness.loop.step.control_step`: an exception in the estimator, the controller, the
compensator or the supervisor trips the case (``tick_exception``) as it trips a dry run. This
is what a dry run should reproduce within its statistics, and what a lab engineer checks an
experiment design against.

A controller reads what the rig measures: the table and base-mat sensors, and the actuator's
force (``Measurements.actuator_force_N``, the load cell). With ``offline_true_state`` a
full-state controller also reads the twin's true plant state Z: an offline design study
that no rig can run (a rig does not measure the drifts).
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from harness.control.compensation import Compensator
from harness.control.controllers import Controller
from harness.control.estimator import FrictionEstimator
from harness.control.factory import make_compensator, make_friction_estimator
from harness.errors import ModelError
from harness.loop.ending import run_ending
from harness.loop.step import StepValues, control_step
from harness.profile import Profile
from harness.rig.actuator import make_actuator
from harness.rig.faults import SEIZE, FaultSet, schedule_from
from harness.rig.parts import RigParts
from harness.rig.sensors import MESSAGE_COLUMNS, SIGNALS, SensorModel
from harness.rig.table import TablePlant
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import SupervisedCommand, Supervisor
from harness.signals import columns as layout
from harness.signals.peaks import peak_responses
from harness.simulation.sampled import CaseResult, CaseSamples, case_result

_MAX_SENSOR_DELAY_S = 1.0

#: The sensor messages, by their place in :data:`harness.rig.sensors.MESSAGE_COLUMNS`.
_TABLE_MESSAGE, _BASE_MESSAGE, _DRIFT_MESSAGE, _ACCEL_MESSAGE = range(len(MESSAGE_COLUMNS))
#: What the twin records per sample: every sensor reading (the rig's ring order is
#: :data:`harness.signals.columns.SENSOR_COLUMNS`'s) and the control.
_RECORDED = (*layout.SENSOR_COLUMNS, *layout.TWIN_CONTROL)
#: Repeated over the row after the last sample: everything sampled; the actuator force is the one acting then.
_HELD = tuple(name for name in _RECORDED if name != layout.FORCE_MEASURED)


def run_rig_twin(
    profile: Profile, motion, rate_hz: float, controller: Controller, seed: int | None = None, asynchronous_delay_s: float = 0.0,
    story_rate_hz: float | None = None, lockstep: bool = False, duration_s: float | None = None,
    offline_true_state: bool = False, compensator: Compensator | None = None, after_trip_s: float = 0.0,
) -> CaseResult:
    """Simulate the controlled case through the rig's sensor, actuator and safety models.

    Parameters
    ----------
    profile : Profile
        Its ``rig`` section gives the sensors, actuator and physics sub-step, and with ``rig.truth``
        the plant's true building and bearing; ``safety`` the limits. The friction estimator
        and the supervisor use the design (``structure``, ``bearing``).
    motion : GroundMotion
        The processed record (the table plays it from t = 0).
    rate_hz : float
        Controller sample rate (a whole number of physics sub-steps per sample).
    controller : object
        ``update(t, dt, meas, friction_N, state) -> force`` (a rig controller: measured signals only).
    seed : int, optional
        Noise seed (default ``rig.seed``).
    asynchronous_delay_s : float
        Extra delay of every sensor (s). A real-time dry run samples frames the rig
        published up to one period earlier, and the rig applies a command at its next
        service, up to one period later: on average one period in all. 0 matches lockstep.
    story_rate_hz : float, optional
        Rate of the story sensors (drifts, floor accelerations); default the profile's CAN rate, or
        ``rate_hz`` on the CAN FD protocol (``can.fd``: the whole sensor set comes every period).
    lockstep : bool
        Round sensor delays to whole controller steps, as the rig does in lockstep.
    duration_s : float, optional
        Simulate only this much of the record (s), e.g. the span a tripped dry run ran;
        default the whole record.
    offline_true_state : bool
        Hand the controller the plant's true Z at each sample (offline design studies of
        full-state controllers only; a rig cannot). Without it the controller gets None.
    compensator : Compensator, optional
        Between the controller's force and the supervisor, as in the loop's tick; default the
        profile's ``control.compensation`` (:func:`harness.control.factory.make_compensator`).
    after_trip_s : float
        After a trip, the rig goes on this long (s) under the tripped command (zero force, drive
        disabled), recorded like the rest, as the virtual rig's plant goes on after a dry run
        trips: what the load cell carries while the drive lets go (e.g. a seized base mat). 0
        (default) ends the case at the trip.

    Returns
    -------
    CaseResult
        Columns :data:`harness.signals.columns.TWIN_COLUMNS`, as a dry run records them: measured
        signals (with the sensors' noise, quantization and delay, story signals held between
        their samples), the plant's true bearing state, the supervised command
        ``force_command_N`` and the actuator force ``force_measured_N``; peaks of those;
        ``extra["outcome"]``, ``extra["trip_reason"]`` and the true responses
        (``extra["true_peaks"]``); the table's true motion at each sample (``extra["true_table"]``:
        displacement m, velocity m/s, acceleration m/s^2, by column name); ``extra["state_source"]``
        says what the controller read.

    Raises
    ------
    ModelError
        A full-state controller without ``offline_true_state``.
    """
    if controller.needs_full_state and not offline_true_state:
        raise ModelError("a full-state controller on the rig twin needs offline_true_state (a rig measures no drifts)")
    started = time.perf_counter()
    period = 1.0 / rate_hz
    rig = _TwinRig(profile, motion, period, seed, asynchronous_delay_s, lockstep)
    estimator = make_friction_estimator(profile)
    supervisor = Supervisor(profile.safety, period_s=period)
    health = TickHealth()
    if compensator is None:
        compensator = make_compensator(profile)
    rig.start()
    controller.reset()
    compensator.reset()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    span_s = motion.duration_s if duration_s is None else min(duration_s, motion.duration_s)
    samples = CaseSamples(int(round(span_s * rate_hz)), rig.table.y.size, _RECORDED)
    story_rate = story_rate_hz or (rate_hz if profile.can.fd else profile.can.story_sensor_rate_hz)
    story_every = max(1, int(round(rate_hz / story_rate)))
    true_state = profile.structure.n_stories * 2 + 2 if offline_true_state else 0
    samples.run(rig.table, _twin_sample(rig, controller, compensator, estimator, supervisor, health, samples.values, period,
                                        story_every, true_state, int(round(after_trip_s / period))))
    samples.close(rig.table.y, ending={layout.FORCE_MEASURED: rig.actuator.force_N}, held=_HELD)
    result = _twin_result(rig, samples, period, supervisor, profile.structure.total_weight_N, started)
    result.extra["state_source"] = "true plant state (offline design study)" if offline_true_state else "measured"
    result.extra["compensation"] = compensator.name
    return result


class _TwinRig:
    """The virtual rig's models without a bus or a clock: table and plant, sensors, servo actuator.

    Parameters
    ----------
    profile : Profile
    motion : GroundMotion
    period_s : float
        Controller sample period (s), a whole number of physics sub-steps.
    seed : int or None
        Noise seed (None: ``rig.seed``).
    asynchronous_delay_s : float
        Extra delay of every sensor (s).
    lockstep : bool
        Round sensor delays to whole controller steps.
    """

    def __init__(self, profile: Profile, motion, period_s: float, seed: int | None, asynchronous_delay_s: float,
                 lockstep: bool):
        rig = profile.rig
        self.substep_s = rig.physics_substep_s
        self.substeps_per_sample = int(round(period_s / self.substep_s))
        parts = RigParts.from_profile(profile)  # as the virtual rig: its true structure and bearing, not the design
        self.table = TablePlant(parts.building, parts.bearing, motion, parts.rtol, rig)
        rng = np.random.default_rng(rig.seed if seed is None else seed)
        self.sensors = SensorModel(rig.sensors, self.substep_s, _MAX_SENSOR_DELAY_S, rng)
        self.sensors.set_delays(asynchronous_delay_s, self.substeps_per_sample if lockstep else None)
        self.actuator = make_actuator(rig, self.substep_s, self.table, seed)
        #: The profile's scheduled faults (``rig.faults``): the twin has no bus, so it acts on the plant's only (seize).
        self.faults = FaultSet(schedule_from(rig.faults))
        self.truth = np.zeros(len(SIGNALS))
        #: The latest reading of each sensor message (SI, DBC signal order); story readings hold between their samples.
        self.readings = tuple([0.0] * len(columns) for columns in MESSAGE_COLUMNS)
        #: Physics sub-steps taken.
        self.substeps = 0

    def start(self) -> None:
        """The rig at rest with every sensor's history filled, the table playing the record."""
        self.table.truth(self.truth, 0.0)
        self.sensors.reset(self.truth)
        self.table.start()

    def read(self, stories: bool) -> None:
        """Read the table and base-mat messages, and the story messages when ``stories``, into :attr:`readings`."""
        messages = (_TABLE_MESSAGE, _BASE_MESSAGE, _DRIFT_MESSAGE, _ACCEL_MESSAGE) if stories else (_TABLE_MESSAGE, _BASE_MESSAGE)
        for message in messages:
            self.sensors.read(MESSAGE_COLUMNS[message], self.readings[message])

    def advance(self, t: float, command: SupervisedCommand) -> None:
        """Advance actuator, plant and sensors over one sample from ``t`` (s), sub-step by sub-step."""
        h, actuator, table, sensors, truth = self.substep_s, self.actuator, self.table, self.sensors, self.truth
        for j in range(self.substeps_per_sample):
            if self.faults.schedule:  # as the virtual rig's fault schedule, on record time, each sub-step
                self.faults.update(t + j * h)
                table.set_seized(self.faults.is_on(SEIZE))
            plant_input = actuator.plant_input(actuator.substep(command.force_N, command.enable))
            table.advance(t + j * h, h, plant_input)
            table.truth(truth, plant_input)
            sensors.push(truth)
        self.substeps += self.substeps_per_sample


def _twin_sample(
    rig: _TwinRig, controller: Controller, compensator: Compensator, estimator: FrictionEstimator, supervisor: Supervisor,
    health: TickHealth, values: dict[str, np.ndarray], period: float, story_every: int, true_state: int = 0,
    after_trip_samples: int = 0,
) -> Callable[[int], bool]:
    """One controller sample of the twin: read the sensors, the tick's step (estimate, control, compensate, supervise:
    :func:`harness.loop.step.control_step`), record, advance.

    The returned ``sample(k)`` is False when the supervisor tripped ``after_trip_samples`` samples
    ago (the case ends there; the rig advances under the tripped command until then).
    ``true_state`` > 0 hands the controller the first ``true_state`` entries of the plant's
    true state (Z, an offline design study); 0 hands it None, as on a rig.
    """
    meas, actuator = health.meas, rig.actuator
    table_read, base_read = rig.readings[_TABLE_MESSAGE], rig.readings[_BASE_MESSAGE]
    reading_slots = tuple(  # (column array, message reading, position in it) of every sensor reading
        (values[layout.SENSOR_COLUMNS[column]], rig.readings[message], i)
        for message, columns in enumerate(MESSAGE_COLUMNS)
        for i, column in enumerate(columns)
    )
    sliding_variable, friction_estimate = values[layout.SLIDING_VARIABLE], values[layout.FRICTION_ESTIMATE]
    raw_force, command_force = values[layout.FORCE_RAW], values[layout.FORCE_COMMAND]
    actuator_force = values[layout.FORCE_MEASURED]
    tripped_at = [-1]  # the sample of the trip
    step = StepValues()

    def sample(k: int) -> bool:
        t = k * period
        actuator_force[k] = actuator.force_N
        rig.read(stories=k % story_every == 0)
        for column, reading, i in reading_slots:
            column[k] = reading[i]
        meas.set(table_read[0], table_read[1], base_read[0], base_read[1])
        meas.actuator_force_N = health.measured_force_N = actuator.force_N
        # the loop's tick's step: an exception trips the case as it trips a dry run (tick_exception)
        command = control_step(t, period, health, estimator, controller, compensator, supervisor, step,
                               rig.table.y[:true_state] if true_state else None)
        raw_force[k], command_force[k] = step.raw_N, command.force_N
        sliding_variable[k], friction_estimate[k] = controller.sliding_variable, step.friction_N
        if supervisor.state is State.TRIPPED:
            if tripped_at[0] < 0:
                tripped_at[0] = k
            if k - tripped_at[0] >= after_trip_samples:
                return False
        rig.advance(t, command)
        return True

    return sample


def _twin_result(
    rig: _TwinRig, samples: CaseSamples, period: float, supervisor: Supervisor, total_weight_N: float, started_s: float,
) -> CaseResult:
    """The twin's :class:`CaseResult`: measured columns, the plant's true bearing state, the control; true peaks."""
    rows = samples.rows
    times = np.arange(rows) * period
    plant = rig.table.record
    true_columns = plant.responses(times, samples.states[:rows], samples.values[layout.FORCE_MEASURED][:rows])
    columns = _measured_columns(times, samples)
    columns.update({name: true_columns[name] for name in layout.BEARING})
    columns.update(samples.columns(layout.TWIN_CONTROL))
    ending = run_ending(supervisor, record_ended=True)  # as a dry run's: a check's safe stop is "stopped", with the check's name
    extra: dict[str, object] = {
        "outcome": ending.outcome, "trip_reason": ending.reason, "true_peaks": peak_responses(true_columns, total_weight_N),
        "true_table": {name: true_columns[name] for name in layout.TABLE},
    }
    if rig.table.seized:  # a seize fault (rig.faults): the sliding velocity it stopped
        extra["seized_at_velocity_m_s"] = rig.table.seized_at_velocity_m_s
    return case_result("rig twin", columns, total_weight_N, plant.steps + rig.substeps, started_s, extra)


def _measured_columns(times: np.ndarray, samples: CaseSamples) -> dict[str, np.ndarray]:
    """The motion columns from the sensor readings, as the loop records a dry run (sliding = base - table)."""
    measured = samples.columns(layout.SENSOR_COLUMNS)
    measured[layout.TIME] = times
    measured[layout.SLIDING_DISPLACEMENT] = measured[layout.BASE_DISPLACEMENT] - measured[layout.TABLE_DISPLACEMENT]
    measured[layout.SLIDING_VELOCITY] = measured[layout.BASE_VELOCITY] - measured[layout.TABLE_VELOCITY]
    return {name: measured[name] for name in layout.motion_columns(layout.PROTOCOL_STORIES)}
