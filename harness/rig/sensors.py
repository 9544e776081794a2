"""The rig's sensors: true signals delayed, biased, made noisy and quantized, seeded.

The rig pushes the twelve true signals (:data:`SIGNALS`) once per physics sub-step
into a ring; a read returns, per signal, the value ``delay`` sub-steps back plus
bias and Gaussian noise, quantized to the group's step. Delays are whole sub-steps
in real time and whole steps in lockstep (see :meth:`SensorModel.set_delays`).
Noise comes from one seeded generator, drawn in preallocated blocks, so two runs
with the same seed and the same sequence of reads give identical values.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from harness.rig.config import SensorsConfig
from harness.rig.grid import half_up

#: The true signals, in ring order (SI).
SIGNALS = (
    "x_0", "xdot_0", "xddot_0", "y_b", "ydot_b", "yddot_b",
    "drift_1", "drift_2", "drift_3", "accel_1", "accel_2", "accel_3",
)
#: Signal group of each signal: 0 displacement, 1 velocity, 2 acceleration.
GROUP = (0, 1, 2, 0, 1, 2, 0, 0, 0, 2, 2, 2)
#: Ring columns of each sensor message, in DBC signal order.
MESSAGE_COLUMNS = ((0, 1, 2), (3, 4, 5), (6, 7, 8), (9, 10, 11))
_NOISE_BLOCK = 4096


class SensorModel:
    """Delay line and imperfections of every sensor signal.

    Parameters
    ----------
    config : SensorsConfig
    substep_s : float
        Physics sub-step (s): one ring row per sub-step.
    max_delay_s : float
        Longest delay the ring must hold (s), extra-delay faults included.
    rng : numpy.random.Generator
        Seeded source of the noise.
    """

    def __init__(self, config: SensorsConfig, substep_s: float, max_delay_s: float, rng: np.random.Generator):
        groups = (config.displacement.as_tuple(), config.velocity.as_tuple(), config.acceleration.as_tuple())
        self.substep_s = float(substep_s)
        self.noise_std = np.array([groups[g][0] for g in GROUP])
        self.bias = np.array([groups[g][1] for g in GROUP])
        self.quantization = np.array([groups[g][2] for g in GROUP])
        self.group_delay_s = tuple(g[3] for g in groups)
        self.capacity = int(np.ceil(max_delay_s / substep_s)) + 2
        self.ring = np.zeros((self.capacity, len(SIGNALS)))
        self.head = 0
        self.delay_substeps = np.zeros(len(SIGNALS), dtype=np.int64)
        self._delay_key: tuple[float, int | None] | None = None
        self._rng = rng
        self._noise = np.empty(_NOISE_BLOCK)
        self._noise_next = _NOISE_BLOCK

    def reset(self, truth: np.ndarray) -> None:
        """Fill the whole history with ``truth`` (the rig at rest)."""
        self.ring[:] = truth
        self.head = 0

    def push(self, truth: np.ndarray) -> None:
        """Record the true signals of the newest sub-step."""
        self.head = (self.head + 1) % self.capacity
        self.ring[self.head] = truth

    def set_delays(self, extra_delay_s: float, step_substeps: int | None) -> None:
        """Delay of each signal in sub-steps: group delay plus ``extra_delay_s``.

        ``step_substeps`` given (lockstep): rounded to whole steps of that many
        sub-steps; None (real time): rounded to whole sub-steps.
        """
        key = (extra_delay_s, step_substeps)
        if key == self._delay_key:
            return
        self._delay_key = key
        for i, group in enumerate(GROUP):
            delay = self.group_delay_s[group] + extra_delay_s
            if step_substeps is None:
                n = half_up(delay / self.substep_s)
            else:
                n = half_up(delay / (step_substeps * self.substep_s)) * step_substeps
            self.delay_substeps[i] = min(n, self.capacity - 1)

    def true_delayed(self, column: int) -> float:
        """The true value of signal ``column`` as delayed (no noise)."""
        return float(self.ring[(self.head - self.delay_substeps[column]) % self.capacity, column])

    def _gauss(self) -> float:
        if self._noise_next >= _NOISE_BLOCK:
            self._rng.standard_normal(out=self._noise)
            self._noise_next = 0
        value = self._noise[self._noise_next]
        self._noise_next += 1
        return float(value)

    def read(self, columns: Sequence[int], out: list[float], extra_noise_std: float = 0.0) -> None:
        """Measured values of ``columns`` into ``out`` (SI): delayed truth + bias + noise, quantized."""
        for k, column in enumerate(columns):
            value = self.true_delayed(column) + self.bias[column]
            std = self.noise_std[column]
            if std > 0.0:
                value += std * self._gauss()
            if extra_noise_std > 0.0:
                value += extra_noise_std * self._gauss()
            step = self.quantization[column]
            if step > 0.0:
                value = step * round(value / step)
            out[k] = value
