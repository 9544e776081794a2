"""Friction bearings: velocity-dependent friction with a Bouc-Wen hysteretic variable (SPEC 2, Eq. 3-5).

    f     = mu * mbar * g * nu                                           (Eq. 3)
    mu    = mu_m - mu_f * exp(-a_mu * |xdot_b|)                          (Eq. 4)
    nudot = (alpha xdot_b - beta |xdot_b| |nu|^(eta-1) nu - gamma xdot_b |nu|^eta) / D_y   (Eq. 5)

The coefficient depends on the sliding VELOCITY (a text copy of Eq. 4 shows |x_b|, a typo).
The numerical functions are compiled with numba and take the parameters packed in
one float array (see :meth:`BearingConfig.packed`), so the integration kernel and the
online friction estimator share one implementation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np

from harness.config.schema import quantity

# Indices into the packed parameter array.
MU_MAX, MU_DELTA, A_MU, WEIGHT, ALPHA, BETA, GAMMA, ETA, YIELD = range(9)

#: Beyond this many yield displacements of travel in one direction, nu has reached its bound.
_SATURATION_TRAVEL = 40.0
#: Largest travel per RK4 sub-step of the local nu update, in yield displacements.
_SUBSTEP_TRAVEL = 0.1


@dataclass(frozen=True)
class BearingConfig:
    """Friction-bearing parameters of Eq. 3-5 (SI)."""

    mu_max: float = quantity(unit="1", ge=0, le=1, doc="mu_m, friction coefficient at high sliding velocity")
    mu_delta: float = quantity(unit="1", ge=0, le=1, doc="mu_f, drop of the coefficient at zero velocity")
    a_mu_s_per_m: float = quantity(unit="s/m", ge=0, doc="a_mu, velocity constant of Eq. 4")
    yield_displacement_m: float = quantity(unit="m", gt=0, doc="D_y, Bouc-Wen yield displacement")
    alpha: float = quantity(1.0, gt=0, doc="Bouc-Wen alpha")
    beta: float = quantity(0.5, ge=0, doc="Bouc-Wen beta")
    gamma: float = quantity(0.5, doc="Bouc-Wen gamma")
    eta: float = quantity(2.0, ge=1, doc="Bouc-Wen exponent eta")

    def __post_init__(self) -> None:
        if self.mu_delta > self.mu_max:
            raise ValueError(f"mu_delta = {self.mu_delta} exceeds mu_max = {self.mu_max}: friction would turn negative at rest")
        if self.beta + self.gamma <= 0:
            raise ValueError(f"beta + gamma = {self.beta + self.gamma:g}, expected > 0 for a bounded hysteretic variable")

    @property
    def nu_bound(self) -> float:
        """The bound of |nu|: (alpha / (beta + gamma))^(1/eta); 1 for the usual parameters."""
        return (self.alpha / (self.beta + self.gamma)) ** (1.0 / self.eta)

    def packed(self, total_weight_N: float) -> np.ndarray:
        """Parameters packed for the compiled functions, with the carried weight ``mbar g`` (N)."""
        return np.array(
            [
                self.mu_max,
                self.mu_delta,
                self.a_mu_s_per_m,
                total_weight_N,
                self.alpha,
                self.beta,
                self.gamma,
                self.eta,
                self.yield_displacement_m,
            ]
        )


@numba.njit(cache=True, nogil=True)
def friction_coefficient(sliding_velocity: float, params: np.ndarray) -> float:
    """mu of Eq. 4 for a sliding velocity (m/s)."""
    return params[MU_MAX] - params[MU_DELTA] * math.exp(-params[A_MU] * abs(sliding_velocity))


@numba.njit(cache=True, nogil=True)
def friction_force(sliding_velocity: float, nu: float, params: np.ndarray) -> float:
    """f of Eq. 3 (N)."""
    return friction_coefficient(sliding_velocity, params) * params[WEIGHT] * nu


@numba.njit(cache=True, nogil=True)
def _power(magnitude: float, exponent: float) -> float:
    """``magnitude ** exponent`` by multiplication for the usual whole exponents (eta - 1 = 1, 2)."""
    if exponent == 1.0:
        return magnitude
    if exponent == 2.0:
        return magnitude * magnitude
    if exponent == 0.0:
        return 1.0
    return magnitude**exponent


@numba.njit(cache=True, nogil=True)
def hysteretic_rate(sliding_velocity: float, nu: float, params: np.ndarray) -> float:
    """nudot of Eq. 5 (1/s)."""
    magnitude = abs(nu)
    power = _power(magnitude, params[ETA] - 1.0)
    return (
        params[ALPHA] * sliding_velocity
        - params[BETA] * abs(sliding_velocity) * power * nu
        - params[GAMMA] * sliding_velocity * power * magnitude
    ) / params[YIELD]


@numba.njit(cache=True, nogil=True)
def _travel_slope(nu: float, direction: float, params: np.ndarray) -> float:
    """d nu / d x_b for travel in ``direction`` (+1 or -1), from Eq. 5 divided by xdot_b."""
    return hysteretic_rate(direction, nu, params)


@numba.njit(cache=True, nogil=True)
def advance_hysteretic(nu: float, sliding_velocity: float, dt: float, params: np.ndarray) -> float:
    """Advance nu over ``dt`` with the sliding velocity held constant (exact to RK4 accuracy).

    With constant velocity Eq. 5 is an autonomous equation in the travel
    ``x = xdot_b t``, so it is integrated in travel with sub-steps of at most a tenth
    of the yield displacement; beyond 40 yield displacements of travel nu
    has reached its bound. This stays accurate however stiff Eq. 5 is at the
    sample rate of a controller (D_y of tens of micrometres).

    Parameters
    ----------
    nu : float
        Hysteretic variable at the start.
    sliding_velocity : float
        Measured sliding velocity held over the step (m/s).
    dt : float
        Step (s).
    params : ndarray
        Packed bearing parameters.
    """
    travel = sliding_velocity * dt
    if travel == 0.0:
        return nu
    direction = 1.0 if travel > 0.0 else -1.0
    distance = abs(travel) / params[YIELD]
    bound = (params[ALPHA] / (params[BETA] + params[GAMMA])) ** (1.0 / params[ETA])
    if distance > _SATURATION_TRAVEL or direction * nu >= bound:
        return direction * bound
    n_sub = int(math.ceil(distance / _SUBSTEP_TRAVEL))
    h = travel / n_sub
    for _ in range(n_sub):
        if direction * nu >= bound * (1.0 - 1e-12):  # at the bound while loading: a fixed point
            return direction * bound
        k1 = _travel_slope(nu, direction, params) * direction
        k2 = _travel_slope(nu + 0.5 * h * k1, direction, params) * direction
        k3 = _travel_slope(nu + 0.5 * h * k2, direction, params) * direction
        k4 = _travel_slope(nu + h * k3, direction, params) * direction
        nu += h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
    return nu


@numba.njit(cache=True, nogil=True)
def estimator_step(nu: float, mean_velocity: float, velocity: float, dt: float, params: np.ndarray):
    """One online-estimator step: nu advanced with the mean velocity, then mu and f at ``velocity``.

    Returns
    -------
    nu, mu, force : float
        Hysteretic variable, friction coefficient (Eq. 4) and friction force (Eq. 3, N).
    """
    nu = advance_hysteretic(nu, mean_velocity, dt, params)
    mu = friction_coefficient(velocity, params)
    return nu, mu, mu * params[WEIGHT] * nu
