"""When the rig publishes: message periods on the sub-step grid (real time) and per step (lockstep).

Rates come from the profile's CAN section (:class:`~harness.canbus.config.CanConfig`).
Each period is rounded to whole physics sub-steps (at least one); a message is
due when the rig's sub-step count reaches its next due count, which then moves on
by one period (or past ``now`` when the rig fell behind, so nothing bursts).
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.canbus.config import CanConfig

MAX_CATCH_UP_S = 0.2


@dataclass
class Due:
    """Which message groups are due now."""

    sensors: bool = False
    stories: bool = False
    status: bool = False
    rig_status: bool = False


class PublishSchedule:
    """Message periods in sub-steps and their next due sub-step counts.

    Parameters
    ----------
    can : CanConfig
        ``sensor_frame_rate_hz``, ``story_sensor_rate_hz``, ``status_rate_hz``, ``rig_status_rate_hz``.
    substep_s : float
        Physics sub-step (s).
    step_period_s : float
        Lockstep period (s), for :attr:`story_every_steps`.
    """

    def __init__(self, can: CanConfig, substep_s: float, step_period_s: float):
        def period(rate_hz: float) -> int:
            return max(1, int(round(1.0 / (rate_hz * substep_s))))

        self.periods = (
            period(can.sensor_frame_rate_hz), period(can.story_sensor_rate_hz),
            period(can.status_rate_hz), period(can.rig_status_rate_hz),
        )
        self.story_every_steps = max(1, int(round(1.0 / (can.story_sensor_rate_hz * step_period_s))))
        self.sensor_period_s = self.periods[0] * substep_s
        self.rig_status_period_s = 1.0 / can.rig_status_rate_hz
        self.max_catch_up = int(MAX_CATCH_UP_S / substep_s)
        self.late_services = 0
        self._next = [0, 0, 0, 0]
        self._due = Due()

    def reset(self, n: int) -> None:
        """Everything due at sub-step ``n``."""
        self._next = [n, n, n, n]

    def any_due(self, n: int) -> bool:
        """True when some message is due at sub-step count ``n``."""
        return n >= min(self._next)

    def due(self, n: int) -> Due:
        """Flags of the messages due at ``n``, and move their due counts on."""
        flags = [False, False, False, False]
        for i, period in enumerate(self.periods):
            if n >= self._next[i]:
                flags[i] = True
                self._next[i] += period
                if self._next[i] <= n:
                    self._next[i] = n + period
        due = self._due
        due.sensors, due.stories, due.status, due.rig_status = flags
        return due
