"""The servo-hydraulic actuator: transport delay, dynamics, force and rate limits.

Advanced once per physics sub-step ``h``. :meth:`ServoActuator.substep` takes the
latest commanded force, delays it by whole sub-steps, and returns the force held
on the plant over the coming sub-step:

- ``ideal``: the delayed command itself;
- ``first_order``: ``tau dF/dt = F_c - F``, exact over each sub-step (the force held
  is the state at the sub-step's start);
- ``second_order``: ``F'' + 2 zeta w F' + w^2 F = w^2 F_c`` (``w = 2 pi bandwidth``),
  exact zero-order-hold discretization.

Every model then obeys ``|dF/dt| <= force_rate_limit_N_per_s`` and
``|F| <= force_limit_N``. When the drive is not enabled the force decays to zero
with ``decay_time_constant_s`` whatever the model.

``servo_hydraulic`` (:class:`HydraulicActuator`) is not a force source: the cylinder's
pressure is part of the plant's state (:mod:`harness.hydraulics.cylinder`), so its force
depends on how the base mat moves. The actuator object then delays the command, limits
it as the servo controller's command range does, and sets the drive's enable flag that
the plant's force loop reads.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import expm

from harness.hydraulics import cylinder as hy
from harness.hydraulics.servo_controller import StrokeVelocityFeedforward
from harness.rig.config import ActuatorConfig, RigConfig
from harness.rig.grid import half_up
from harness.rig.truth import true_hydraulics

if TYPE_CHECKING:
    from harness.rig.table import TablePlant


def slew_and_clamp(previous: float, target: float, max_step: float, limit: float) -> float:
    """``target`` moved at most ``max_step`` from ``previous``, then held inside ``[-limit, limit]``."""
    step = target - previous
    if step > max_step:
        target = previous + max_step
    elif step < -max_step:
        target = previous - max_step
    return limit if target > limit else -limit if target < -limit else target


class DelayLine:
    """A transport delay of whole sub-steps.

    Parameters
    ----------
    delay_substeps : int
        The delay, in sub-steps (0: none).
    """

    def __init__(self, delay_substeps: int):
        self.delay_substeps = int(delay_substeps)
        self._line = np.zeros(self.delay_substeps + 1)
        self._head = 0

    def reset(self) -> None:
        """Zero the line."""
        self._line[:] = 0.0
        self._head = 0

    def push(self, value: float) -> float:
        """Put ``value`` in; return the value put in ``delay_substeps`` sub-steps ago."""
        line = self._line
        self._head = (self._head + 1) % line.size
        line[self._head] = value
        return float(line[(self._head - self.delay_substeps) % line.size])


class ServoActuator:
    """Actuator force state on the sub-step grid.

    Parameters
    ----------
    config : ActuatorConfig
    substep_s : float
        Physics sub-step h (s).
    decay_time_constant_s : float
        Decay of the force to zero while the drive is not enabled (s).
    """

    def __init__(self, config: ActuatorConfig, substep_s: float, decay_time_constant_s: float):
        self.config = config
        self.substep_s = float(substep_s)
        self.force_N = 0.0
        self.rate_N_s = 0.0
        self._max_step_N = config.force_rate_limit_N_per_s * self.substep_s
        self._decay = math.exp(-self.substep_s / decay_time_constant_s)
        self._lag = 1.0 - math.exp(-self.substep_s / config.time_constant_s)
        w = 2.0 * math.pi * config.bandwidth_hz
        a = np.array([[0.0, 1.0], [-w * w, -2.0 * config.damping_ratio * w]])
        phi = expm(a * self.substep_s)
        gamma = np.linalg.solve(a, (phi - np.eye(2)) @ np.array([0.0, w * w]))
        self._phi = tuple(float(v) for v in phi.ravel())
        self._gamma = (float(gamma[0]), float(gamma[1]))
        self._delay = DelayLine(half_up(config.delay_s / self.substep_s))
        self.delay_substeps = self._delay.delay_substeps

    def reset(self) -> None:
        """Zero force, rate and delay line."""
        self.force_N = 0.0
        self.rate_N_s = 0.0
        self._delay.reset()

    def plant_input(self, held_N: float) -> float:
        """What the plant integrates with over the sub-step: the force held (N)."""
        return held_N

    def _limit(self, previous: float, target: float) -> float:
        return slew_and_clamp(previous, target, self._max_step_N, self.config.force_limit_N)

    def substep(self, command_N: float, enabled: bool) -> float:
        """Advance one sub-step; return the force held on the plant over it (N).

        Parameters
        ----------
        command_N : float
            Latest commanded force (N), before the transport delay.
        enabled : bool
            The drive is enabled (otherwise the force decays to zero).
        """
        command = self._delay.push(command_N)
        previous = self.force_N
        if not enabled:
            held = previous
            self.force_N = previous * self._decay
            self.rate_N_s = (self.force_N - previous) / self.substep_s
            return held
        model = self.config.model
        if model == "ideal":
            self.force_N = self._limit(previous, command)
            self.rate_N_s = 0.0
            return self.force_N
        held = previous
        if model == "first_order":
            target = previous + (command - previous) * self._lag
            rate = (target - previous) / self.substep_s
        else:
            p00, p01, p10, p11 = self._phi
            target = p00 * previous + p01 * self.rate_N_s + self._gamma[0] * command
            rate = p10 * previous + p11 * self.rate_N_s + self._gamma[1] * command
        limited = self._limit(previous, target)
        if limited != target:
            rate = (limited - previous) / self.substep_s
        self.force_N = limited
        self.rate_N_s = rate
        return held


class HydraulicActuator:
    """The servo-hydraulic control actuator: command delay and range, drive enable; force from the plant.

    Parameters
    ----------
    config : ActuatorConfig
        ``model: servo_hydraulic``; ``delay_s`` and ``force_limit_N`` act on the command.
    substep_s : float
        Physics sub-step h (s).
    table : TablePlant
        The table and plant whose state holds the cylinder (built with this actuator's hydraulics).
    """

    def __init__(self, config: ActuatorConfig, substep_s: float, table: TablePlant,
                 feedforward: StrokeVelocityFeedforward | None = None):
        self.config = config
        self.substep_s = float(substep_s)
        self.table = table
        self._delay = DelayLine(half_up(config.delay_s / self.substep_s))
        self.delay_substeps = self._delay.delay_substeps
        self._max_step_N = config.force_rate_limit_N_per_s * self.substep_s
        self.command_N = 0.0
        #: The servo controller's velocity feed-forward (SPEC 7a'); None: a plain force loop.
        self.feedforward = feedforward
        self._primed = False

    def reset(self) -> None:
        """Zero the command and the delay line (the plant's reset zeroes the pressure)."""
        self.command_N = 0.0
        self._delay.reset()
        self._primed = False
        self.table.rig_params[hy.ACTUATOR_FEEDFORWARD] = 0.0

    @property
    def force_N(self) -> float:
        """The cylinder's force on the base mat now, ``A p_L`` (N)."""
        return self.table.live.actuator_force(self.command_N)

    def plant_input(self, held_N: float) -> float:
        """What the plant integrates with: the force command of the force loop (N)."""
        return self.command_N

    def substep(self, command_N: float, enabled: bool) -> float:
        """Take the latest command for the coming sub-step; return the force acting at its start (N).

        The command is delayed by ``delay_s``, rate limited and clamped to ``force_limit_N``
        (the servo controller's command range); ``enabled`` sets the drive's enable flag.
        """
        command = slew_and_clamp(self.command_N, self._delay.push(command_N), self._max_step_N, self.config.force_limit_N)
        self.command_N = command if enabled else 0.0
        params = self.table.rig_params
        params[hy.ENABLED] = 1.0 if enabled else 0.0
        if self.feedforward is not None:  # the servo controller samples its stroke LVDT every sub-step, enabled or not
            stroke = self.table.stroke_m()
            if not self._primed:
                self.feedforward.reset(stroke)
                self._primed = True
            current = self.feedforward.update(stroke)
            params[hy.ACTUATOR_FEEDFORWARD] = current if enabled else 0.0
        return self.force_N


def make_feedforward(config: RigConfig, substep_s: float, seed: int | None = None) -> StrokeVelocityFeedforward | None:
    """The rig's servo controller's velocity feed-forward, or None when its true gain is 0.

    The gain is the rig's (``rig.truth.actuator.feedforward_gain`` over the believed one), the
    nominal valve gain ``A / q_nl`` the believed cylinder's (SPEC 7a'). The LVDT's noise has
    its own stream of ``seed`` (default ``rig.seed``), apart from the sensors'.
    """
    believed = config.actuator.hydraulics
    true = true_hydraulics(believed, config.truth.actuator)
    if true.feedforward.gain == 0.0:
        return None
    rng = np.random.default_rng(np.random.SeedSequence(config.seed if seed is None else seed).spawn(3)[2])
    return StrokeVelocityFeedforward(true.feedforward, believed.feedforward_current_per_m_s(), substep_s, rng)


def make_actuator(config: RigConfig, substep_s: float, table: TablePlant,
                  seed: int | None = None) -> ServoActuator | HydraulicActuator:
    """The rig's actuator model: a force source, or the servo-hydraulic cylinder in ``table``'s plant."""
    if config.actuator.model == "servo_hydraulic":
        return HydraulicActuator(config.actuator, substep_s, table, make_feedforward(config, substep_s, seed))
    return ServoActuator(config.actuator, substep_s, config.drive.decay_time_constant_s)
