"""harness.signals.columns: the one definition of every run's columns, and the orders files keep."""

from __future__ import annotations

import pytest

import harness.recording as recording
from drivers.protocol.codec import load_protocol
from harness.recording.layout import check_columns
from harness.rig.sensors import SIGNALS
from harness.signals import columns as layout

#: signals.csv of a run or dry run, column by column, as written before the layout moved here
#: (``estimated_nu`` was then called ``hysteretic_nu``). Reordering it breaks readers' scripts.
CONTROL_ROW_ORDER = (
    "t_s", "state", "table_displacement_m", "table_velocity_m_s", "table_acceleration_m_s2",
    "base_displacement_m", "base_velocity_m_s", "base_acceleration_m_s2", "sliding_displacement_m",
    "sliding_velocity_m_s", "drift_1_m", "drift_2_m", "drift_3_m", "floor_acceleration_1_m_s2",
    "floor_acceleration_2_m_s2", "floor_acceleration_3_m_s2", "estimated_nu", "friction_estimate_N",
    "sliding_variable_m_s", "equivalent_force_N", "force_raw_N", "force_command_N", "drive_enabled",
    "force_measured_N", "drive_state", "interlock_flags", "lateness_s", "compute_s", "overrun", "e2e_rejects",
    "error_frames", "send_failures",
)
MOTION_3 = CONTROL_ROW_ORDER[:1] + CONTROL_ROW_ORDER[2:16]


def test_the_control_row_keeps_its_column_order():
    assert layout.CONTROL_ROW == CONTROL_ROW_ORDER
    assert [layout.CONTROL_ROW_INDEX[name] for name in CONTROL_ROW_ORDER] == list(range(len(CONTROL_ROW_ORDER)))


def test_simulation_and_twin_orders():
    assert layout.motion_columns(3) == MOTION_3
    assert layout.plant_columns(3) == (*MOTION_3, "friction_force_N", "hysteretic_nu")
    assert layout.simulation_columns(3, controlled=False) == (*layout.plant_columns(3), "force_command_N")
    assert layout.simulation_columns(3, controlled=True) == (
        *layout.plant_columns(3), "sliding_variable_m_s", "equivalent_force_N", "friction_estimate_N", "force_raw_N",
        "force_command_N",
    )
    assert layout.TWIN_COLUMNS == (
        *layout.plant_columns(3), "sliding_variable_m_s", "friction_estimate_N", "force_raw_N", "force_command_N",
        "force_measured_N",
    )


@pytest.mark.parametrize("columns", [
    layout.CONTROL_ROW, layout.TWIN_COLUMNS, layout.simulation_columns(8, True), layout.canonical_columns(8),
])
def test_every_layout_is_a_valid_signals_header(columns):
    assert check_columns(columns) == columns
    assert columns[0] == layout.TIME


def test_the_protocol_carries_protocol_stories():
    protocol = load_protocol()
    drifts = [s for s in protocol["STORY_DRIFTS"].signal_names if s.startswith("drift_")]
    accels = [s for s in protocol["FLOOR_ACCELS"].signal_names if s.startswith("accel_")]
    assert len(drifts) == len(accels) == layout.PROTOCOL_STORIES


def test_sensor_columns_follow_the_rigs_signal_order():
    rig_names = {"x_0": "table_displacement_m", "xdot_0": "table_velocity_m_s", "xddot_0": "table_acceleration_m_s2",
                 "y_b": "base_displacement_m", "ydot_b": "base_velocity_m_s", "yddot_b": "base_acceleration_m_s2"}
    for j in range(1, layout.PROTOCOL_STORIES + 1):
        rig_names[f"drift_{j}"] = layout.drift(j)
        rig_names[f"accel_{j}"] = layout.floor_acceleration(j)
    assert layout.SENSOR_COLUMNS == tuple(rig_names[name] for name in SIGNALS)


def test_both_nu_columns_are_dimensionless_and_distinct():
    assert layout.ESTIMATED_NU != layout.HYSTERETIC_NU
    assert layout.unit_of(layout.ESTIMATED_NU) == layout.unit_of(layout.HYSTERETIC_NU) == "1"
    assert layout.HYSTERETIC_NU not in layout.CONTROL_ROW


def test_count_stories_inverts_drift():
    assert layout.count_stories(layout.CONTROL_ROW) == layout.PROTOCOL_STORIES
    assert layout.count_stories(layout.plant_columns(8)) == 8


def test_the_recording_package_exports_the_same_definitions():
    for name in ("canonical_columns", "drift", "floor_acceleration", "unit_of"):
        assert getattr(recording, name) is getattr(layout, name)
