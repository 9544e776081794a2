"""Lockstep closed loop through CAN on the virtual bus reproduces the offline simulator.

With noise, quantization, delays off and an ideal actuator, the harness side
written here (poll until RIG_STATUS step k, fill the measurements, friction
estimator, phi controller, command) must give the peaks of ``run_study`` for the
same profile and record at the same rate within 1 %. What remains different is
only the CAN resolution (1 um, 10 um/s, 1 N) and sub-stepping of the integration.
"""

from __future__ import annotations

import dataclasses
import time
import uuid

import numpy as np
import pytest

from drivers.measurements import Measurements
from drivers.protocol.protocol_values import DriveState, RigCommand
from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness, open_rig
from harness.control.factory import make_controller, make_friction_estimator
from harness.profile import load_profile
from harness.rig.config import ActuatorConfig, DriveConfig, RigConfig, SensorsConfig
from harness.rig.virtual_rig import RigParts, VirtualRig
from harness.runs.options import StudyOptions, prepare_motion
from harness.runs.simulate import run_study
from harness.signals.peaks import peak_responses
from tests.conftest import PROFILES

STEP_TIMEOUT_S = 5.0


def _ideal_parts(profile) -> RigParts:
    rig = RigConfig(
        physics_substep_s=0.0005,
        sensors=SensorsConfig(),  # no noise, bias, quantization or delay
        actuator=ActuatorConfig(model="ideal", delay_s=0.0, force_limit_N=30_000.0, force_rate_limit_N_per_s=1e12),
        drive=DriveConfig(watchdog_timeout_s=60.0),  # a slow CI machine must not trip it
        history_s=40.0,
    )
    return RigParts(profile.structure, profile.bearing, rig, profile.simulation.rtol)


def _wait_for_step(reader, k: int) -> None:
    status = reader.sample("RIG_STATUS")
    index = status.index("step_index")
    deadline = time.monotonic() + STEP_TIMEOUT_S
    while True:
        reader.poll(time.monotonic())
        if status.count and int(status.values[index]) == k:
            return
        if time.monotonic() > deadline:
            raise AssertionError(f"no RIG_STATUS with step_index {k} within {STEP_TIMEOUT_S} s; last {status.values}")
        time.sleep(0)


def _closed_loop(profile, motion, rate_hz: float) -> dict:
    """Run the lockstep loop over CAN; return the rig's record columns."""
    period = 1.0 / rate_hz
    n_steps = int(round(motion.duration_s * rate_hz))
    can_config = CanConfig(channel=f"equiv-{uuid.uuid4().hex[:8]}")
    controller = make_controller(profile, "phi")
    estimator = make_friction_estimator(profile)
    meas = Measurements()
    with open_rig(can_config) as rig_link, open_harness(can_config) as link:
        rig = VirtualRig(_ideal_parts(profile), motion, rig_link, step_period_s=period)
        rig.start_thread(poll_timeout_s=0.001)
        try:
            writer, reader = link.writer, link.reader
            writer.heartbeat(1, time.monotonic())
            writer.rig_control(RigCommand.START_TABLE, True, time.monotonic())  # lockstep on, start the table
            for k in range(n_steps):
                _wait_for_step(reader, k)
                reader.fill(meas)
                t = k * period
                friction = estimator.update(t, period, meas.sliding_velocity_m_s)
                force = controller.update(t, period, meas, friction)
                if k % 10 == 0:
                    writer.heartbeat(1, time.monotonic())
                assert writer.command(force, True, time.monotonic())
            _wait_for_step(reader, n_steps)
            assert reader.drive_state == DriveState.ENABLED, "the drive must have stayed enabled"
        finally:
            rig.stop()
        return rig.record_columns()


def _compare(profile, options: StudyOptions) -> None:
    study = run_study(profile, dataclasses.replace(options, controller="phi"))
    reference = study.cases["controlled"].columns
    motion = prepare_motion(profile, options)
    columns = _closed_loop(profile, motion, study.settings.rate_hz)
    n = int(round(motion.duration_s * study.settings.rate_hz))
    assert columns["t_s"].size == n, "one history row per step of the record"
    np.testing.assert_allclose(columns["t_s"], reference["t_s"][:n], atol=1e-9)
    weight = profile.structure.total_weight_N
    ours = peak_responses(columns, weight).flatten()
    theirs = peak_responses({k: v[:n] for k, v in reference.items()}, weight).flatten()
    assert theirs["sliding_displacement_m"] > 1e-3 and theirs["peak_force_pct_weight"] > 1.0, "a run that does something"
    for name, expected in theirs.items():
        assert ours[name] == pytest.approx(expected, rel=0.01), name


@pytest.fixture(scope="module")
def profile():
    return load_profile(PROFILES / "nceer_4dof.yaml")


def test_lockstep_over_can_reproduces_run_study_synthetic(profile):
    _compare(profile, StudyOptions(record="synthetic", duration_s=10.0))


def test_lockstep_over_can_reproduces_run_study_el_centro(profile, records_dir):
    _compare(profile, StudyOptions(record="el_centro", records_dir=str(records_dir), pga_g=0.34, time_scale=2.0))  # 30 s
