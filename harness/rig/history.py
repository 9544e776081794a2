"""The rig's exact history: one preallocated row per physics sub-step, kept in a ring.

Columns: rig time (s), record time (s, NaN while the table is held), the actuator
force held over the sub-step (N), then the plant state ``(Z, nu)`` at the
sub-step's start. For tests and post-run checks; never read by the rig itself.
"""

from __future__ import annotations

import math

import numpy as np

from harness.model.plant import Plant
from harness.realtime.memory import prefaulted_zeros

RIG_TIME, RECORD_TIME, FORCE, STATE = 0, 1, 2, 3


class History:
    """A ring of the newest ``capacity`` rows.

    Parameters
    ----------
    capacity : int
        Rows kept (0 disables recording).
    state_size : int
        Length of ``(Z, nu)``.
    """

    def __init__(self, capacity: int, state_size: int):
        self.capacity = int(capacity)
        self.data = prefaulted_zeros((max(self.capacity, 1), STATE + state_size))
        self.count = 0

    def clear(self) -> None:
        """Forget every row."""
        self.count = 0

    def append(self, rig_time_s: float, record_time_s: float | None, force_N: float, state: np.ndarray) -> None:
        """Store one row (overwrites the oldest when full)."""
        if self.capacity == 0:
            return
        row = self.data[self.count % self.capacity]
        row[RIG_TIME] = rig_time_s
        row[RECORD_TIME] = math.nan if record_time_s is None else record_time_s
        row[FORCE] = force_N
        row[STATE:] = state
        self.count += 1

    def rows(self) -> np.ndarray:
        """The kept rows, oldest first (a copy)."""
        n = min(self.count, self.capacity)
        if self.count <= self.capacity:
            return self.data[:n].copy()
        start = self.count % self.capacity
        return np.concatenate((self.data[start:], self.data[:start]))


def record_columns(history: History, plant: Plant, step_period_s: float) -> dict[str, np.ndarray]:
    """Canonical run columns from ``history``, at the step boundaries of the record run.

    Parameters
    ----------
    history : History
    plant : Plant
        The plant on the record's table (for :meth:`~harness.model.plant.Plant.responses`).
    step_period_s : float
        Step period (s): rows whose record time is a whole number of periods are kept.

    Returns
    -------
    dict
        The columns of :meth:`~harness.model.plant.Plant.responses`, plus
        ``force_command_N``, the force held from each row on (N).
    """
    rows = history.rows()
    record_time = rows[:, RECORD_TIME]
    steps = record_time / step_period_s
    rows = rows[np.isfinite(record_time) & (np.abs(steps - np.round(steps)) < 1e-6)]
    times, forces = rows[:, RECORD_TIME], rows[:, FORCE]
    columns = plant.responses(times, np.ascontiguousarray(rows[:, STATE:]), forces)
    columns["force_command_N"] = forces
    return columns
