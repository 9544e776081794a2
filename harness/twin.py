"""The rig twin: ``harness simulate --rig-effects``, the offline simulation with the virtual rig's imperfections.

The same models the virtual rig serves on the bus, without the bus and without a
clock: the table and plant (:class:`~harness.rig.table.TablePlant`), the sensors
(noise, bias, quantization, delay: :class:`~harness.rig.sensors.SensorModel`), the
servo actuator (transport delay, dynamics, force and rate limits:
:class:`~harness.rig.actuator.ServoActuator`) on the rig's physics sub-step, and the
safety supervisor between the controller and the actuator (force clamp, rate limit,
stroke fade; trips end the case). This is what a dry run should reproduce within its
statistics, and what a lab engineer checks an experiment design against.
"""

from __future__ import annotations

import time

import numpy as np

from harness.control.estimator import FrictionEstimator
from harness.peaks import peak_responses
from harness.profile import Profile
from harness.rig.actuator import ServoActuator
from harness.rig.sensors import MESSAGE_COLUMNS, SIGNALS, SensorModel
from harness.rig.table import TablePlant
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor
from harness.simulation import CaseResult

_MAX_SENSOR_DELAY_S = 1.0


def run_rig_twin(
    profile: Profile, motion, rate_hz: float, controller, seed: int | None = None, asynchronous_delay_s: float = 0.0,
    story_rate_hz: float | None = None, lockstep: bool = False, duration_s: float | None = None,
) -> CaseResult:
    """Simulate the controlled case through the rig's sensor, actuator and safety models.

    Parameters
    ----------
    profile : Profile
        Its ``rig`` section gives the sensors, actuator and physics sub-step; ``safety`` the limits.
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
        Rate of the story sensors (drifts, floor accelerations); default the profile's CAN rate.
    lockstep : bool
        Round sensor delays to whole controller steps, as the rig does in lockstep.
    duration_s : float, optional
        Simulate only this much of the record (s), e.g. the span a tripped dry run ran;
        default the whole record.

    Returns
    -------
    CaseResult
        Columns as a dry run records them: measured signals (with the sensors' noise,
        quantization and delay, story signals held between their samples), the supervised
        command ``force_command_N`` and the actuator force ``force_measured_N``; peaks of
        those; ``extra["outcome"]``, ``extra["trip_reason"]`` and the true responses
        (``extra["true_peaks"]``).
    """
    started = time.perf_counter()
    rig = profile.rig
    h = rig.physics_substep_s
    period = 1.0 / rate_hz
    n_sub = int(round(period / h))
    table = TablePlant(profile.structure, profile.bearing, motion, profile.simulation.rtol)
    rng = np.random.default_rng(rig.seed if seed is None else seed)
    sensors = SensorModel(rig.sensors, h, _MAX_SENSOR_DELAY_S, rng)
    sensors.set_delays(asynchronous_delay_s, n_sub if lockstep else None)
    actuator = ServoActuator(rig.actuator, h, rig.drive.decay_time_constant_s)
    estimator = FrictionEstimator(profile.bearing, profile.structure.total_weight_N)
    supervisor = Supervisor(profile.safety, period_s=period)
    health = TickHealth()
    meas = health.meas
    truth = np.zeros(len(SIGNALS))
    table.truth(truth, 0.0)
    sensors.reset(truth)
    table.start()
    controller.reset()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    span_s = motion.duration_s if duration_s is None else min(duration_s, motion.duration_s)
    n_samples = int(round(span_s * rate_hz))
    states = np.zeros((n_samples + 1, table.y.size))
    applied, raw_force, command_force = (np.zeros(n_samples + 1) for _ in range(3))
    sliding_variable, friction_estimate = np.zeros(n_samples + 1), np.zeros(n_samples + 1)
    measured = np.zeros((n_samples + 1, 12))  # x0 xd0 xdd0 yb ydb yddb d1 d2 d3 a1 a2 a3, as received
    table_read, base_read, drift_read, accel_read = [0.0] * 3, [0.0] * 3, [0.0] * 3, [0.0] * 3
    story_every = max(1, int(round(rate_hz / (story_rate_hz or profile.can.story_sensor_rate_hz))))
    steps = 0
    for k in range(n_samples):
        t = k * period
        states[k] = table.y
        applied[k] = actuator.force_N
        sensors.read(MESSAGE_COLUMNS[0], table_read)
        sensors.read(MESSAGE_COLUMNS[1], base_read)
        if k % story_every == 0:
            sensors.read(MESSAGE_COLUMNS[2], drift_read)
            sensors.read(MESSAGE_COLUMNS[3], accel_read)
        measured[k, 0:3], measured[k, 3:6] = table_read, base_read
        measured[k, 6:9], measured[k, 9:12] = drift_read, accel_read
        meas.set(table_read[0], table_read[1], base_read[0], base_read[1])
        health.measured_force_N = actuator.force_N
        friction = estimator.update(t, period, meas.sliding_velocity_m_s)
        raw = controller.update(t, period, meas, friction, None)
        command = supervisor.update(t, period, health, raw)
        raw_force[k], command_force[k] = raw, command.force_N
        sliding_variable[k], friction_estimate[k] = controller.sliding_variable, friction
        if supervisor.state is State.TRIPPED:
            n_samples = k + 1
            break
        for j in range(n_sub):
            force = actuator.substep(command.force_N, command.enable)
            table.advance(t + j * h, h, force)
            table.truth(truth, force)
            sensors.push(truth)
            steps += 1
    states[n_samples] = table.y
    applied[n_samples] = actuator.force_N
    measured[n_samples] = measured[n_samples - 1]
    raw_force[n_samples], command_force[n_samples] = raw_force[n_samples - 1], command_force[n_samples - 1]
    sliding_variable[n_samples], friction_estimate[n_samples] = sliding_variable[n_samples - 1], friction_estimate[n_samples - 1]
    end = n_samples + 1
    times = np.arange(end) * period
    true_columns = table.record.responses(times, states[:end], applied[:end])
    columns = _measured_columns(times, measured[:end])
    columns["friction_force_N"] = true_columns["friction_force_N"]
    columns["hysteretic_nu"] = true_columns["hysteretic_nu"]
    columns["sliding_variable_m_s"] = sliding_variable[:end]
    columns["friction_estimate_N"] = friction_estimate[:end]
    columns["force_raw_N"] = raw_force[:end]
    columns["force_command_N"] = command_force[:end]
    columns["force_measured_N"] = applied[:end]
    peaks = peak_responses(columns, profile.structure.total_weight_N)
    extra = {"outcome": "tripped" if supervisor.state is State.TRIPPED else "completed",
             "trip_reason": supervisor.command.trip_reason,
             "true_peaks": peak_responses(true_columns, profile.structure.total_weight_N)}
    return CaseResult("rig twin", columns, peaks, table.record.steps + steps, time.perf_counter() - started, extra)


def _measured_columns(times: np.ndarray, measured: np.ndarray) -> dict[str, np.ndarray]:
    """Canonical columns from the sensor readings, as the loop records a dry run."""
    columns = {
        "t_s": times,
        "table_displacement_m": measured[:, 0],
        "table_velocity_m_s": measured[:, 1],
        "table_acceleration_m_s2": measured[:, 2],
        "base_displacement_m": measured[:, 3],
        "base_velocity_m_s": measured[:, 4],
        "base_acceleration_m_s2": measured[:, 5],
        "sliding_displacement_m": measured[:, 3] - measured[:, 0],
        "sliding_velocity_m_s": measured[:, 4] - measured[:, 1],
    }
    for j in range(3):
        columns[f"drift_{j + 1}_m"] = measured[:, 6 + j]
    for j in range(3):
        columns[f"floor_acceleration_{j + 1}_m_s2"] = measured[:, 9 + j]
    return columns
