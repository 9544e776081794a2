"""Fit the bearings' friction law (Eq. 3-5) to the friction force measured through the base mat's balance.

The model is the one the plant and the friction estimator use (:mod:`harness.model.bearing`):

    f = mu(xdot_b) * mbar g * nu,    mu = mu_max - mu_delta exp(-a_mu |xdot_b|)      (Eq. 3, 4)

with ``nu`` the Bouc-Wen variable of Eq. 5. Eq. 5 is rate-independent (divided by ``xdot_b`` it
is an equation in the travel), so ``nu`` is simulated along the measured sliding displacement
with the plant's own exact local update (:func:`harness.model.bearing.advance_hysteretic`),
sample by sample. Fitted: ``mu_max``, ``mu_delta``, ``a_mu`` and the yield displacement ``D_y``;
``alpha``, ``beta``, ``gamma`` and ``eta`` keep the profile's values (the shape of the loop's
corners, which the rig's sensors cannot resolve at a ``D_y`` of tens of micrometres).

Two things make the fit work at the rig's noise:

- **the sliding displacement** is fused from the displacement and velocity sensors
  (:func:`fused_displacement`): the displacement sensors' noise (micrometres) is of the order
  of ``D_y``, and ``nu`` simulated along it would jitter on every sample and drift where the
  bearing sticks. The velocity, integrated, is smooth at short times and the displacement is
  right at long ones; a complementary filter takes each where it is good;
- **measured and fitted force are low-passed alike** (zero-phase Butterworth at
  :data:`LOWPASS_HZ`): the force balance sums accelerations whose noise, times the masses,
  is tens of newtons per sample, and whose sensors are read at different rates. Filtering
  both the same way keeps the comparison fair at the sharp friction reversals.

- **the load cell's timing** is fitted too: the load cell and the motion sensors reach the
  loop with different delays (on the virtual rig in lockstep the motion sensors' 1 ms is a
  whole 2 ms tick, the load cell's none), and a tick's misalignment between the actuator's
  force and the inertia forces it balances put ``a_mu`` 10 % off in a dry run. The force
  balance takes the actuator's force ``delay`` earlier (linear between samples).

The fit is :func:`scipy.optimize.least_squares` (trust-region reflective, bounded), started
from the profile's values, in parameters that keep the law valid: ``mu_max``,
``mu_delta / mu_max`` in [0, 1], the logarithms of ``a_mu`` and ``D_y``, and the delay. Standard errors
come from the data as the structure's do: the larger of the Jacobian's (the residuals' correlation
time in) and a block sandwich over stretches of each record
(:func:`~harness.identification.fit_statistics.honest_standard_errors`), both carried to the
reported values through the derivatives of the change of parameters. Whether the data
determine a parameter is judged twice: the motion must hold what the parameter shapes
(:func:`coverage`), and its relative standard error must be below
:data:`DETERMINED_RELATIVE_ERROR`.

**The sensors' noise in the fit's input** is corrected by simulation-extrapolation (SIMEX:
Cook & Stefanski, "Simulation-extrapolation estimation in parametric measurement error
models", JASA 89(428), 1994; Carroll, Ruppert, Stefanski & Crainiceanu, "Measurement Error in
Nonlinear Models", 2nd ed., 2006, ch. 5; :func:`simex_correction`). The noise left in the fused
displacement moves ``nu`` back and forth along a path the bearing did not travel, an error in
the fit's input that least squares does not average out: on the virtual rig the plain fit read
``D_y`` +3.6 % high on average over 20 seeds, every seed above the truth, and -0.4 % with the
sensors' noise cut to a trace (benchmarks/README.md). SIMEX adds more noise of the sensors' own
kind (their standard deviations estimated from the record's samples,
:func:`harness.identification.simex.noise_std`, not taken from any configuration), refits,
and extrapolates the values' trend in the added variance back to none. It corrects ``D_y``
only (:data:`SIMEX_CORRECTED`): the friction law proper was covered in 20 of 20 seeds before,
and corrected too (measured on the same 20 run folders) ``mu_delta`` read further from the truth
(mean error +1.5 % against +1.1 %, covered in 19 of 20): its small bias is not the input's
noise. The extrapolations of all four are in the record (:class:`SimexCorrection`); the
others' values, and the load cell's delay, are the plain fit's. ``D_y``'s standard error is the
plain fit's and the extrapolation's Monte Carlo error combined (:func:`_corrected`). The
correction needs the displacement sensor's samples (``SlidingRecord.measured_displacement_m``);
without them the plain fit is returned. It costs 16 refits (:data:`SIMEX_LAMBDAS` times
:data:`SIMEX_REPLICATES`), each started from the plain fit.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numba
import numpy as np
from scipy import optimize, signal

from harness.identification.choices import LOWPASS_HZ
from harness.identification.fit_statistics import correlation_time, honest_standard_errors, relative_error, time_blocks
from harness.identification.simex import extrapolate, noise_std
from harness.model.bearing import A_MU, MU_DELTA, MU_MAX, YIELD, BearingConfig, advance_hysteretic

#: The fitted parameters, as the profile's ``bearing`` section names them.
PARAMETERS = ("mu_max", "mu_delta", "a_mu_s_per_m", "yield_displacement_m")
#: Crossover of the complementary filter: below it the displacement sensors, above it the velocity ones (Hz).
CROSSOVER_HZ = 2.0
#: A run slid when its sliding speed exceeded this (m/s): 25 times the rig's velocity noise.
SLIDING_SPEED_M_S = 0.005
#: Time the motion must spend where a parameter shapes the friction for it to be determined (s).
MIN_COVERAGE_S = 0.2
#: Largest relative standard error of a determined parameter.
DETERMINED_RELATIVE_ERROR = 0.1
#: Largest load-cell delay searched, either way (s).
MAX_DELAY_S = 0.01
#: SIMEX: the noise variances added to the sensors', in units of their own (:func:`simex_correction`).
SIMEX_LAMBDAS = (0.5, 1.0, 1.5, 2.0)
#: SIMEX: replicates of the added noise per lambda.
SIMEX_REPLICATES = 4
#: SIMEX: the values it corrects (the other values are the plain fit's; see the module docstring).
SIMEX_CORRECTED = ("yield_displacement_m",)
#: SIMEX: seed of the added noise (the correction is deterministic: the same records give the same values).
SIMEX_SEED = 332


@dataclass(frozen=True)
class SlidingRecord:
    """One run's sliding motion and friction force, on a uniform grid.

    Attributes
    ----------
    label : str
        The run's name, for plots and messages.
    rate_hz : float
        Sample rate (Hz).
    displacement_m : ndarray
        Sliding displacement ``x_b`` (m), fused (:func:`fused_displacement`).
    velocity_m_s : ndarray
        Sliding velocity ``xdot_b`` (m/s), as measured.
    actuator_force_N : ndarray
        The load cell's force ``u`` (N).
    other_forces_N : ndarray
        The rest of the force balance, ``-k_b x_b - m_b a_b - sum_j m_j a_j`` (N): the friction is their sum.
    measured_displacement_m : ndarray or None
        The displacement sensor's samples before the fusion (m): what the SIMEX correction adds
        noise to (:func:`simex_correction`); None when not known (no correction then).
    """

    label: str
    rate_hz: float
    displacement_m: np.ndarray
    velocity_m_s: np.ndarray
    actuator_force_N: np.ndarray
    other_forces_N: np.ndarray
    measured_displacement_m: np.ndarray | None = None

    @property
    def duration_s(self) -> float:
        return (len(self.velocity_m_s) - 1) / self.rate_hz

    def friction_N(self, delay_s: float = 0.0) -> np.ndarray:
        """The friction force of the force balance (N), with the load cell's force taken ``delay_s`` earlier."""
        force = self.actuator_force_N
        if delay_s != 0.0:
            t = np.arange(len(force)) / self.rate_hz
            force = np.interp(t - delay_s, t, force)
        return force + self.other_forces_N


@dataclass(frozen=True)
class ParameterEstimate:
    """One identified value and what the data say of it.

    Attributes
    ----------
    name : str
        Its key in the profile's section.
    value, standard_error : float
        In the key's unit.
    design : float
        The profile's value the fit started from.
    determined : bool
        Whether the data determine it (:func:`coverage` and the relative standard error).
    reason : str
        Why, in one sentence.
    """

    name: str
    value: float
    standard_error: float
    design: float
    determined: bool
    reason: str

    @property
    def relative_error(self) -> float:
        return relative_error(self.value, self.standard_error)

    def as_dict(self) -> dict:
        return {"value": self.value, "standard_error": self.standard_error,
                "relative_standard_error": self.relative_error, "design_value": self.design,
                "determined": self.determined, "reason": self.reason}


@dataclass(frozen=True)
class SimexCorrection:
    """What the SIMEX correction did (:func:`simex_correction`).

    Attributes
    ----------
    displacement_noise_m, velocity_noise_m_s : tuple of float
        Per record the sensors' noise standard deviations estimated from the samples
        (:func:`harness.identification.simex.noise_std`), in m and m/s.
    lambdas : tuple of float
        The added noise variances over the measured ones, 0 (the plain fit) first.
    replicates : int
        Fits per ``lambda`` > 0.
    plain : dict of str to (float, float)
        By :data:`PARAMETERS` name, the plain fit's value and standard error.
    means : dict of str to tuple of float
        By name, the estimate averaged over the replicates at each ``lambda``.
    extrapolated : dict of str to float
        By name, the extrapolation to ``lambda = -1`` (before :func:`_corrected` keeps it valid).
    extrapolation_se : dict of str to float
        By name, the extrapolation's Monte Carlo standard error.
    evaluations : int
        Model evaluations the refits took.
    """

    displacement_noise_m: tuple[float, ...]
    velocity_noise_m_s: tuple[float, ...]
    lambdas: tuple[float, ...]
    replicates: int
    plain: dict[str, tuple[float, float]]
    means: dict[str, tuple[float, ...]]
    extrapolated: dict[str, float]
    extrapolation_se: dict[str, float]
    evaluations: int

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class FrictionFit:
    """The fitted friction law and its quality.

    Attributes
    ----------
    estimates : dict of str to ParameterEstimate
        By :data:`PARAMETERS` name.
    bearing : BearingConfig
        The design with every fitted value put in (determined or not).
    rms_error_N : float
        RMS of measured minus fitted force, both low-passed (N).
    peak_friction_N : float
        Largest |measured force|, low-passed (N).
    delay_s, delay_se_s : float
        The load cell's delay against the motion sensors (s), and its standard error.
    correlation_samples : float
        The residuals' integrated autocorrelation time (samples).
    evaluations : int
        Model evaluations the fit took.
    measured_N, fitted_N : tuple of ndarray
        Per record, the low-passed measured and fitted force (N).
    fitted_nu : tuple of ndarray
        Per record, the fitted hysteretic variable.
    slid : tuple of bool
        Per record, whether the base mat slid (faster than :data:`SLIDING_SPEED_M_S`).
    note : str
        Why nothing was fitted, when nothing was.
    simex : SimexCorrection or None
        The errors-in-variables correction the estimates carry; None when not made.
    """

    estimates: dict[str, ParameterEstimate]
    bearing: BearingConfig
    rms_error_N: float
    peak_friction_N: float
    delay_s: float
    delay_se_s: float
    correlation_samples: float
    evaluations: int
    measured_N: tuple[np.ndarray, ...]
    fitted_N: tuple[np.ndarray, ...]
    fitted_nu: tuple[np.ndarray, ...]
    slid: tuple[bool, ...]
    note: str = ""
    simex: SimexCorrection | None = None

    @property
    def determined(self) -> tuple[str, ...]:
        """Names of the determined parameters, in :data:`PARAMETERS` order."""
        return tuple(name for name in PARAMETERS if self.estimates[name].determined)

    @property
    def relative_rms_error(self) -> float:
        """:attr:`rms_error_N` over :attr:`peak_friction_N`."""
        return self.rms_error_N / self.peak_friction_N if self.peak_friction_N > 0 else math.inf


def fused_displacement(displacement_m: np.ndarray, velocity_m_s: np.ndarray, rate_hz: float,
                       crossover_hz: float = CROSSOVER_HZ) -> np.ndarray:
    """The sliding displacement from both sensors: a complementary filter, run forward and backward and averaged.

    ``x' = v + w_c (x_measured - x)``: below ``crossover_hz`` the estimate follows the
    displacement sensor, above it the integrated velocity. Both paths pass the true motion
    unchanged when the two sensors agree (the velocity is the displacement's derivative), so the
    filter removes noise, not signal; averaging the forward and the backward pass cancels
    the lag that a one-way pass gives the noise.
    """
    x = np.asarray(displacement_m, dtype=float)
    v = np.asarray(velocity_m_s, dtype=float)
    dt = 1.0 / rate_hz
    keep = math.exp(-2.0 * math.pi * crossover_hz * dt)
    forward = _complementary(x, v, dt, keep)
    backward = _complementary(x[::-1].copy(), -v[::-1].copy(), dt, keep)[::-1]
    return 0.5 * (forward + backward)


@numba.njit(cache=True, nogil=True)
def _complementary(x: np.ndarray, v: np.ndarray, dt: float, keep: float) -> np.ndarray:
    """One pass of the complementary filter: integrate ``v`` (trapezoid), pull towards ``x`` by ``1 - keep`` per step."""
    out = np.empty_like(x)
    estimate = x[0]
    out[0] = estimate
    for k in range(1, x.shape[0]):
        estimate = keep * (estimate + 0.5 * (v[k - 1] + v[k]) * dt) + (1.0 - keep) * x[k]
        out[k] = estimate
    return out


@numba.njit(cache=True, nogil=True)
def nu_along(displacement_m: np.ndarray, nu0: float, params: np.ndarray) -> np.ndarray:
    """Eq. 5's ``nu`` along a sampled sliding displacement, from ``nu0`` (exact local update per sample)."""
    out = np.empty_like(displacement_m)
    nu = nu0
    out[0] = nu
    for k in range(1, displacement_m.shape[0]):
        nu = advance_hysteretic(nu, displacement_m[k] - displacement_m[k - 1], 1.0, params)
        out[k] = nu
    return out


class _Model:
    """The friction law over the records, in the fit's parameters ``(mu_max, mu_delta/mu_max, ln a_mu, ln D_y, delay in ms)``."""

    def __init__(self, records: Sequence[SlidingRecord], design: BearingConfig, weight_N: float, lowpass_hz: float):
        self.records = tuple(records)
        self.weight_N = weight_N
        self.params = design.packed(weight_N)
        self.bound = design.nu_bound
        self.filters = [_lowpass(record.rate_hz, lowpass_hz) for record in self.records]
        self.measured = self.balance(0.0)
        self.evaluations = 0

    def balance(self, delay_s: float) -> tuple[np.ndarray, ...]:
        """Per record the low-passed friction force of the force balance with the load cell ``delay_s`` earlier."""
        return tuple(_filtered(sos, record.friction_N(delay_s)) for sos, record in zip(self.filters, self.records, strict=True))

    @staticmethod
    def physical(theta: np.ndarray) -> np.ndarray:
        """``(mu_max, mu_delta, a_mu, D_y)`` of ``theta``."""
        return np.array([theta[0], theta[0] * theta[1], math.exp(theta[2]), math.exp(theta[3])])

    def packed(self, theta: np.ndarray) -> np.ndarray:
        params = self.params.copy()
        params[MU_MAX], params[MU_DELTA], params[A_MU], params[YIELD] = self.physical(theta)
        return params

    def response(self, theta: np.ndarray) -> tuple[list[np.ndarray], list[np.ndarray]]:
        """Per record the low-passed fitted force (N) and the fitted ``nu``."""
        self.evaluations += 1
        params = self.packed(theta)
        forces, nus = [], []
        static_N = max((params[MU_MAX] - params[MU_DELTA]) * self.weight_N, 1e-9)
        for sos, record, measured in zip(self.filters, self.records, self.measured, strict=True):
            nu0 = float(np.clip(measured[0] / static_N, -self.bound, self.bound))
            nu = nu_along(record.displacement_m, nu0, params)
            mu = params[MU_MAX] - params[MU_DELTA] * np.exp(-params[A_MU] * np.abs(record.velocity_m_s))
            forces.append(_filtered(sos, mu * self.weight_N * nu))
            nus.append(nu)
        return forces, nus

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        forces, _ = self.response(theta)
        measured = self.balance(theta[4] * 1e-3)
        return np.concatenate([f - m for f, m in zip(forces, measured, strict=True)])


def _lowpass(rate_hz: float, corner_hz: float) -> np.ndarray | None:
    """Second-order sections of a 4th-order Butterworth low-pass; None when the corner is near Nyquist."""
    if corner_hz >= 0.45 * rate_hz:
        return None
    return signal.butter(4, corner_hz, fs=rate_hz, output="sos")


def _filtered(sos: np.ndarray | None, values: np.ndarray) -> np.ndarray:
    return values.copy() if sos is None else signal.sosfiltfilt(sos, values)


def _bounds() -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of ``theta``."""
    return (np.array([1e-4, 0.0, math.log(0.01), math.log(1e-7), -1e3 * MAX_DELAY_S]),
            np.array([1.0, 1.0, math.log(1e5), math.log(1e-2), 1e3 * MAX_DELAY_S]))


def _start(design: BearingConfig) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start, lower and upper bounds of ``theta`` (the design's values, nudged inside the bounds)."""
    lower, upper = _bounds()
    ratio = design.mu_delta / design.mu_max if design.mu_max > 0 else 0.5
    start = np.array([design.mu_max, ratio, math.log(max(design.a_mu_s_per_m, 0.02)), math.log(design.yield_displacement_m),
                      0.0])
    margin = 1e-6 * (upper - lower)
    return np.clip(start, lower + margin, upper - margin), lower, upper


def coverage(records: Sequence[SlidingRecord], a_mu_s_per_m: float) -> dict[str, tuple[bool, str]]:
    """Whether the motion holds what each parameter shapes, and why: parameter -> (enough, sentence).

    - ``mu_max`` is the friction at high speed: sliding faster than ``3 / a_mu`` (where
      ``mu`` is within 5 % of it) for :data:`MIN_COVERAGE_S`;
    - ``mu_delta`` and ``a_mu`` shape how friction falls towards rest: sliding between
      ``0.3 / a_mu`` and ``3 / a_mu`` for as long;
    - ``D_y`` is the stiffness before sliding: the sliding direction reversing (each
      reversal swings ``nu`` through the yield) at least ten times.
    """
    speeds = np.concatenate([np.abs(r.velocity_m_s) for r in records])
    dt = np.concatenate([np.full(len(r.velocity_m_s), 1.0 / r.rate_hz) for r in records])
    fast_m_s = 3.0 / a_mu_s_per_m
    slow_m_s = 0.3 / a_mu_s_per_m
    fast_s = float(dt[speeds > fast_m_s].sum())
    transition_s = float(dt[(speeds > slow_m_s) & (speeds <= fast_m_s)].sum())
    reversals = sum(_reversals(r.velocity_m_s) for r in records)
    fast = (fast_s >= MIN_COVERAGE_S, f"{fast_s:.2g} s of sliding faster than 3/a_mu = {1e3 * fast_m_s:.3g} mm/s")
    transition = (transition_s >= MIN_COVERAGE_S,
                  f"{transition_s:.2g} s of sliding at {1e3 * slow_m_s:.3g}-{1e3 * fast_m_s:.3g} mm/s (0.3/a_mu to 3/a_mu)")
    return {
        "mu_max": fast,
        "mu_delta": transition,
        "a_mu_s_per_m": transition,
        "yield_displacement_m": (reversals >= 10, f"{reversals} reversals of the sliding direction"),
    }


def _reversals(velocity_m_s: np.ndarray) -> int:
    """Times the sliding direction reverses between two spells faster than :data:`SLIDING_SPEED_M_S`."""
    moving = velocity_m_s[np.abs(velocity_m_s) > SLIDING_SPEED_M_S]
    return int(np.count_nonzero(np.diff(np.sign(moving)) != 0))


def fit_friction(
    records: Sequence[SlidingRecord], design: BearingConfig, weight_N: float, lowpass_hz: float = LOWPASS_HZ,
    simex: bool = True,
) -> FrictionFit:
    """Fit ``mu_max``, ``mu_delta``, ``a_mu`` and ``D_y`` to the records; see the module docstring.

    Parameters
    ----------
    records : sequence of SlidingRecord
        At least one.
    design : BearingConfig
        The profile's bearing: the start of the fit, and the Bouc-Wen shape it keeps.
    weight_N : float
        ``mbar g``, the weight the bearings carry (N).
    lowpass_hz : float
        Corner of the low-pass applied to measured and fitted force alike (Hz).
    simex : bool
        Correct :data:`SIMEX_CORRECTED` (``D_y``) for the sensors' noise in the fit's input
        (:func:`simex_correction`); made only when every record holds its displacement sensor's samples.

    Returns
    -------
    FrictionFit
        When no record slid, nothing is fitted: every estimate is the design's, not determined.
    """
    model = _Model(records, design, weight_N, lowpass_hz)
    peak_N = max(float(np.abs(m).max()) for m in model.measured)
    slid = tuple(bool(np.abs(r.velocity_m_s).max() > SLIDING_SPEED_M_S) for r in records)
    if not any(slid):
        peak_speed = max(float(np.abs(r.velocity_m_s).max()) for r in records)
        note = (f"no run slid: the peak sliding speed was {1e3 * peak_speed:.3g} mm/s, expected above "
                f"{1e3 * SLIDING_SPEED_M_S:g} mm/s; friction that never broke away gives none of the friction law "
                f"(only a lower bound of (mu_max - mu_delta) mbar g: {peak_N:.4g} N)")
        return _unfitted(model, design, peak_N, slid, note)
    start, _, _ = _start(design)
    solution = _solve(model, start)
    theta = solution.x
    tau = correlation_time(solution.fun)
    gradient = np.zeros((5, 5))  # physical (mu_max, mu_delta, a_mu, D_y) and the delay (ms), from theta
    gradient[np.diag_indices(5)] = (1.0, 0.0, math.exp(theta[2]), math.exp(theta[3]), 1.0)
    gradient[1, 0], gradient[1, 1] = theta[1], theta[0]  # mu_delta = mu_max * ratio
    blocks = np.concatenate([time_blocks(len(record.displacement_m)) for record in records])
    standard_errors = honest_standard_errors(solution.jac, solution.fun, blocks, gradient)
    values = model.physical(theta)
    errors = standard_errors[:4]
    correction = None
    if simex and all(record.measured_displacement_m is not None for record in records):
        correction = simex_correction(records, design, weight_N, lowpass_hz, theta, errors)
        values, errors = _corrected(correction)
        theta = np.array([values[0], values[1] / values[0], math.log(values[2]), math.log(values[3]), theta[4]])
    enough = coverage(records, float(values[2]))
    designs = (design.mu_max, design.mu_delta, design.a_mu_s_per_m, design.yield_displacement_m)
    estimates = {}
    for i, name in enumerate(PARAMETERS):
        relative = relative_error(float(values[i]), float(errors[i]))
        covered, why = enough[name]
        precise = relative < DETERMINED_RELATIVE_ERROR
        verdict = "determined" if covered and precise else "not determined"
        reason = f"{verdict}: {why}; standard error {100 * relative:.2g} % (at most {100 * DETERMINED_RELATIVE_ERROR:g} %)"
        estimates[name] = ParameterEstimate(name, float(values[i]), float(errors[i]), float(designs[i]), covered and precise,
                                            reason)
    fitted_forces, fitted_nu = model.response(theta)
    delay_s, delay_se_s = float(theta[4] * 1e-3), float(standard_errors[4] * 1e-3)
    bearing = dataclasses.replace(design, mu_max=float(values[0]), mu_delta=float(values[1]), a_mu_s_per_m=float(values[2]),
                                  yield_displacement_m=float(values[3]))
    measured = model.balance(delay_s)
    rms = float(np.sqrt(np.mean(np.concatenate([f - m for f, m in zip(fitted_forces, measured, strict=True)])**2)))
    evaluations = model.evaluations + (correction.evaluations if correction else 0)
    return FrictionFit(estimates, bearing, rms, peak_N, delay_s, delay_se_s, tau, evaluations, measured,
                       tuple(fitted_forces), tuple(fitted_nu), slid, simex=correction)


def _solve(model: _Model, start: np.ndarray) -> optimize.OptimizeResult:
    """The bounded least-squares fit of ``theta`` from ``start``."""
    lower, upper = _bounds()
    margin = 1e-9 * (upper - lower)
    return optimize.least_squares(model.residuals, np.clip(start, lower + margin, upper - margin), bounds=(lower, upper),
                                  x_scale=np.array([0.01, 0.1, 0.3, 0.3, 0.5]))


def _measured_displacement(record: SlidingRecord) -> np.ndarray:
    """The record's displacement sensor samples (m); :func:`simex_correction` is given only records that have them."""
    assert record.measured_displacement_m is not None, "the SIMEX correction needs the displacement sensor's samples"
    return record.measured_displacement_m


def simex_correction(records: Sequence[SlidingRecord], design: BearingConfig, weight_N: float, lowpass_hz: float,
                     theta: np.ndarray, plain_se: np.ndarray, lambdas: Sequence[float] = SIMEX_LAMBDAS,
                     replicates: int = SIMEX_REPLICATES, seed: int = SIMEX_SEED) -> SimexCorrection:
    """SIMEX for the sensors' noise in the fit's input (Cook & Stefanski 1994; Carroll et al. 2006, ch. 5).

    The displacement and velocity sensors' noise reaches the fit through its input (``nu`` is
    simulated along the fused displacement; ``mu`` is evaluated at the measured velocity), and
    biases it. For each ``lambda`` in ``lambdas``, ``replicates`` times: Gaussian noise of
    standard deviation ``sqrt(lambda)`` times each sensor's own (estimated from its samples,
    :func:`harness.identification.simex.noise_std`), independent from sample to sample, is added
    to the displacement sensor's samples and to the velocity, the displacement fused again
    (:func:`fused_displacement`) and the same fit made, started from the plain fit's ``theta``.
    Replicate ``b`` draws its noise once and scales it by ``sqrt(lambda)`` (common random
    numbers). Each replicate's four values at the ``lambda`` and the plain fit's are extrapolated
    to ``lambda = -1`` with a quadratic, and the extrapolations averaged
    (:func:`harness.identification.simex.extrapolate`); :func:`_corrected` chooses what is used.

    Parameters
    ----------
    records : sequence of SlidingRecord
        Each with its ``measured_displacement_m``.
    design, weight_N, lowpass_hz
        As :func:`fit_friction`'s.
    theta : ndarray
        The plain fit's parameters (the refits start there).
    plain_se : ndarray
        The plain fit's standard errors of ``mu_max``, ``mu_delta``, ``a_mu``, ``D_y``.
    lambdas : sequence of float
        The added noise variances, in units of the sensors' own (each > 0).
    replicates : int
        Refits per ``lambda``.
    seed : int
        Of the added noise: the same records give the same correction.
    """
    sigma_x = tuple(noise_std(_measured_displacement(r)) for r in records)
    sigma_v = tuple(noise_std(r.velocity_m_s) for r in records)
    plain = _Model.physical(theta)
    estimates, evaluations = np.empty((replicates, len(lambdas), len(PARAMETERS))), 0
    for b in range(replicates):
        rng = np.random.default_rng([seed, b])
        draws = [(rng.standard_normal(len(r.velocity_m_s)), rng.standard_normal(len(r.velocity_m_s))) for r in records]
        for i, lam in enumerate(lambdas):
            scale = math.sqrt(lam)
            noisy = [_with_noise(r, scale * sx * zx, scale * sv * zv)
                     for r, sx, sv, (zx, zv) in zip(records, sigma_x, sigma_v, draws, strict=True)]
            model = _Model(noisy, design, weight_N, lowpass_hz)
            estimates[b, i] = model.physical(_solve(model, theta).x)
            evaluations += model.evaluations
    result = extrapolate(plain, lambdas, estimates)
    return SimexCorrection(
        sigma_x, sigma_v, tuple(float(x) for x in result.lambdas), replicates,
        {name: (float(plain[i]), float(plain_se[i])) for i, name in enumerate(PARAMETERS)},
        {name: tuple(float(m) for m in result.means[:, i]) for i, name in enumerate(PARAMETERS)},
        {name: float(result.value[i]) for i, name in enumerate(PARAMETERS)},
        {name: float(result.standard_error[i]) for i, name in enumerate(PARAMETERS)}, evaluations)


def _with_noise(record: SlidingRecord, noise_x: np.ndarray, noise_v: np.ndarray) -> SlidingRecord:
    """The record with ``noise_x`` (m) added to its displacement sensor's samples and ``noise_v`` (m/s) to its velocity."""
    x = record.measured_displacement_m + noise_x
    v = record.velocity_m_s + noise_v
    return dataclasses.replace(record, displacement_m=fused_displacement(x, v, record.rate_hz), velocity_m_s=v,
                               measured_displacement_m=x)


def _corrected(correction: SimexCorrection) -> tuple[np.ndarray, np.ndarray]:
    """The values of ``mu_max``, ``mu_delta``, ``a_mu``, ``D_y`` and their standard errors, SIMEX-corrected where chosen.

    For the values in :data:`SIMEX_CORRECTED` the extrapolant's at ``lambda = -1``, kept inside
    the law's validity (``0 <= mu_delta <= mu_max``, ``a_mu`` and ``D_y`` inside the fit's
    bounds), with a standard error that combines, as independent, the plain fit's (the data's
    sampling error, which SIMEX does not remove) and the extrapolation's Monte Carlo error (the
    finite replicates): ``se^2 = se_plain^2 + se_extrapolation^2``. It does not hold the
    extrapolant's own model error (a quadratic in ``lambda`` is an approximation; Carroll et al.
    section 5.3.2). The other values are the plain fit's, with its standard errors.
    """
    values = np.array([correction.extrapolated[name] if name in SIMEX_CORRECTED else correction.plain[name][0]
                       for name in PARAMETERS])
    values[0] = float(np.clip(values[0], 1e-4, 1.0))
    values[1] = float(np.clip(values[1], 0.0, values[0]))
    values[2] = float(np.clip(values[2], 0.01, 1e5))
    values[3] = float(np.clip(values[3], 1e-7, 1e-2))
    errors = np.array([math.hypot(correction.plain[name][1], correction.extrapolation_se[name]) if name in SIMEX_CORRECTED
                       else correction.plain[name][1] for name in PARAMETERS])
    return values, errors


def _unfitted(model: _Model, design: BearingConfig, peak_N: float, slid: tuple[bool, ...], note: str) -> FrictionFit:
    """The result when nothing can be fitted: the design's values, none determined, the design's force for the plots."""
    start, _, _ = _start(design)
    forces, nus = model.response(start)
    designs = (design.mu_max, design.mu_delta, design.a_mu_s_per_m, design.yield_displacement_m)
    estimates = {name: ParameterEstimate(name, float(value), math.inf, float(value), False, f"not determined: {note}")
                 for name, value in zip(PARAMETERS, designs, strict=True)}
    residual = np.concatenate([f - m for f, m in zip(forces, model.measured, strict=True)])
    return FrictionFit(estimates, design, float(np.sqrt(np.mean(residual**2))), peak_N, 0.0, math.inf, 1.0,
                       model.evaluations, model.measured, tuple(forces), tuple(nus), slid, note)
