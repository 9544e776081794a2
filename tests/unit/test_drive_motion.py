"""The table motion a run achieved as the twin's drive (harness/simulation/drive.py), on hand-made run folders.

A lockstep run's ticks are on the period grid and are kept as recorded; a real-time run that
missed periods is filled in between its ticks; a gap in the table's readings is refused.
tests/integration/test_drive_from.py drives the twin from a real dry run's folder.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from harness.recording import RunFolder, canonical_columns, load_run
from harness.simulation.drive import DriveFromError, achieved_motion, driven_profile

PERIOD_S = 0.002


def _run(parent: Path, times: np.ndarray, displacement: np.ndarray, velocity: np.ndarray) -> Path:
    columns = canonical_columns(3)
    run = RunFolder.create(parent, "p", "dry-run", {}, columns, metadata={"rate_hz": 1.0 / PERIOD_S}, with_can=False)
    run.start()
    for t, x, v in zip(times, displacement, velocity, strict=True):
        run.record_row([t, x, v] + [0.0] * (len(columns) - 3))
    run.finish("completed")
    return run.path


def test_a_lockstep_runs_samples_are_the_drives_and_its_acceleration_their_velocitys_derivative(tmp_path):
    times = np.arange(50) * PERIOD_S
    x, v = 0.01 * np.sin(20 * times), 0.2 * np.cos(20 * times)
    folder = _run(tmp_path, times, x, v)
    recorded = load_run(folder)  # signals.csv keeps the digits the sensors have, not every bit of these
    motion = achieved_motion(folder, 1.0 / PERIOD_S)
    np.testing.assert_array_equal(motion.displacement_m, recorded["table_displacement_m"])
    np.testing.assert_array_equal(motion.velocity_m_s, recorded["table_velocity_m_s"])
    np.testing.assert_allclose(motion.accel_m_s2, np.gradient(recorded["table_velocity_m_s"], PERIOD_S))
    assert motion.dt_s == PERIOD_S and motion.duration_s == pytest.approx(49 * PERIOD_S)


def test_a_real_time_runs_missed_periods_are_filled_between_its_ticks(tmp_path):
    times = np.delete(np.arange(20) * PERIOD_S, [7, 8])  # tick 6's wait took three periods
    x, v = np.delete(1e-3 * np.arange(20.0), [7, 8]), np.ones(18)
    motion = achieved_motion(_run(tmp_path, times, x, v), 1.0 / PERIOD_S)
    np.testing.assert_allclose(motion.displacement_m, 1e-3 * np.arange(20.0), atol=1e-15)
    np.testing.assert_array_equal(motion.t_s, np.arange(20) * PERIOD_S)


def test_a_tick_without_a_table_reading_is_refused(tmp_path):
    times = np.arange(10) * PERIOD_S
    x = np.zeros(10)
    x[4] = np.nan
    with pytest.raises(DriveFromError, match=r"found 1 ticks whose table_displacement_m .* row 5"):
        achieved_motion(_run(tmp_path, times, x, np.zeros(10)), 1.0 / PERIOD_S)


def test_a_run_without_its_rate_falls_back_on_its_profile_and_a_bad_rate_is_refused(tmp_path):
    folder = _run(tmp_path, np.arange(10) * PERIOD_S, np.zeros(10), np.zeros(10))
    metadata = json.loads((folder / "metadata.json").read_text())
    metadata.pop("rate_hz")
    (folder / "metadata.json").write_text(json.dumps(metadata))
    (folder / "profile.yaml").write_text("control: {rate_hz: 1000}\n")
    with pytest.raises(DriveFromError, match="found a run at 1000 Hz, expected the twin's rate 500 Hz"):
        achieved_motion(folder, 500.0)
    (folder / "profile.yaml").write_text("{}\n")
    with pytest.raises(DriveFromError, match="found loop rate None"):
        achieved_motion(folder, 500.0)


def test_the_driven_profiles_table_follows_its_drive():
    from harness.profile import load_profile

    profile = load_profile()
    assert profile.rig.table.model == "servo_hydraulic"  # the shipped rig's table answers its payload
    driven = driven_profile(profile)
    assert driven.rig.table.model == "motion_source" and driven.rig.actuator == profile.rig.actuator
