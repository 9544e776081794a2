"""The per-tick row of a control run: column names and their positions (one layout, one place)."""

from __future__ import annotations

N_STORIES = 3  # the protocol's story messages carry three stories (drivers/rig.dbc)

COLUMNS: tuple[str, ...] = (
    "t_s",
    "state",
    "table_displacement_m",
    "table_velocity_m_s",
    "table_acceleration_m_s2",
    "base_displacement_m",
    "base_velocity_m_s",
    "base_acceleration_m_s2",
    "sliding_displacement_m",
    "sliding_velocity_m_s",
    *(f"drift_{j}_m" for j in range(1, N_STORIES + 1)),
    *(f"floor_acceleration_{j}_m_s2" for j in range(1, N_STORIES + 1)),
    "hysteretic_nu",
    "friction_estimate_N",
    "sliding_variable_m_s",
    "equivalent_force_N",
    "force_raw_N",
    "force_command_N",
    "drive_enabled",
    "force_measured_N",
    "drive_state",
    "interlock_flags",
    "lateness_s",
    "compute_s",
    "overrun",
    "e2e_rejects",
    "error_frames",
    "send_failures",
)

#: Column name -> position in the row.
INDEX = {name: i for i, name in enumerate(COLUMNS)}
