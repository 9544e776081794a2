"""Online friction estimate from the measured sliding velocity (SPEC 3, Eq. 3-5).

A rig cannot measure the bearing friction, so the controller uses
``f_hat = mu(xdot_b) * mbar * g * nu_hat``, with ``nu_hat`` from integrating Eq. 5
with the measured sliding velocity ``xdot_b = ydot_b - xdot_0``. Eq. 5 is stiff at
controller sample rates (D_y of tens of micrometres); the update integrates it in
sliding travel (see :func:`harness.model.bearing.advance_hysteretic`), which stays
accurate at any rate.
"""

from __future__ import annotations

import numpy as np

from harness.model.bearing import BearingConfig, estimator_step, friction_coefficient


class FrictionEstimator:
    """Integrates Eq. 5 online; exposes ``nu``, ``mu`` and ``force_N`` for logging.

    Parameters
    ----------
    bearing : BearingConfig
        Design values of the bearing.
    total_weight_N : float
        ``mbar g`` carried by the bearings (N).
    """

    __slots__ = ("_params", "nu", "mu", "force_N", "_last_velocity", "_started")

    def __init__(self, bearing: BearingConfig, total_weight_N: float):
        self._params: np.ndarray = bearing.packed(total_weight_N)
        self.reset()

    def reset(self, nu: float = 0.0) -> None:
        """Start again from ``nu`` with the bearing at rest."""
        self.nu = float(nu)
        self.mu = float(friction_coefficient(0.0, self._params))
        self.force_N = 0.0
        self._last_velocity = 0.0
        self._started = False

    def update(self, t: float, dt: float, sliding_velocity_m_s: float) -> float:
        """Advance the estimate to time ``t`` over the step ``dt`` (s); return the friction force (N).

        The travel over the step is taken with the mean of the previous and the
        current measured velocity (trapezoidal), and mu with the current one. The
        first update after :meth:`reset` has no previous sample and only records
        the velocity.
        """
        mean_velocity = 0.5 * (self._last_velocity + sliding_velocity_m_s) if self._started else 0.0
        self._started = True
        self._last_velocity = sliding_velocity_m_s
        self.nu, self.mu, self.force_N = estimator_step(self.nu, mean_velocity, sliding_velocity_m_s, dt, self._params)
        return self.force_N
