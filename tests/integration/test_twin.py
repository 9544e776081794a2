"""The rig twin (harness simulate --rig-effects): its columns, its last row, and a trip ending the case."""

from __future__ import annotations

import numpy as np

from harness.control.factory import build_controller_for_rig
from harness.motions import load_motion
from harness.profile import load_profile
from harness.signals import columns as layout
from harness.simulation.twin import run_rig_twin
from tests.conftest import PROFILES

RATE_HZ = 500.0


def _twin(overrides: tuple[str, ...] = (), duration_s: float = 2.0, variant: str | None = None):
    profile = load_profile(PROFILES / "nceer_4dof.yaml", variant=variant, overrides=overrides)
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=duration_s)
    return motion, run_rig_twin(profile, motion, RATE_HZ, build_controller_for_rig(profile, "phi"))


def test_twin_columns_follow_the_row_layout_and_hold_the_last_sample():
    motion, result = _twin()
    columns = result.columns
    assert tuple(columns) == layout.TWIN_COLUMNS
    assert len(columns["t_s"]) == round(motion.duration_s * RATE_HZ) + 1
    np.testing.assert_array_equal(columns["sliding_displacement_m"],
                                  columns["base_displacement_m"] - columns["table_displacement_m"])
    for name in (*layout.SENSOR_COLUMNS, layout.FORCE_COMMAND, layout.FORCE_RAW):
        assert columns[name][-1] == columns[name][-2], name
    assert result.extra["outcome"] == "completed" and result.extra["true_peaks"]


def test_a_trip_ends_the_twin_after_the_tripping_sample():
    stroke = ("safety.stroke.hard_limit_m=0.012", "safety.stroke.soft_limit_m=0.008",
              "safety.stroke.fade_band_m=0.002", "safety.stroke.arm_tolerance_m=0.001")
    motion, result = _twin(stroke, duration_s=6.0, variant="force_source")  # its stroke follows the table
    assert result.extra["outcome"] == "tripped" and result.extra["trip_reason"]
    t = result.columns["t_s"]
    assert len(t) < round(motion.duration_s * RATE_HZ) + 1
    assert result.columns["force_command_N"][-1] == result.columns["force_command_N"][-2]
