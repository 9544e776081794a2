"""The control actuator's model (SPEC 7a) fitted to its measured frequency responses.

The servo-valve driven cylinder under its force loop (:mod:`harness.hydraulics.cylinder`) gives,
with the loop's gain on a blocked piston ``w_f = K_p (4 beta_e / V_t) A q_nl`` and the valve
``G_v(s) = w_v^2 / (s^2 + 2 zeta_v w_v s + w_v^2)``::

    F = [N w_f G_v(s) u_c - k_h xdot_b] / D(s),     D(s) = s + c + N w_f G_v(s)        (F1)

``N`` is the orifice's describing function (:func:`orifice_describing_function`): the valve
passes ``q_nl x_v sqrt(1 - sign(x_v) p_L / p_s)``, less flow while the force grows away from
zero and more while it returns, so a sinusoid of force amplitude ``F_0`` sees the loop's gain
times ``N = 1 - O(x^2) + j 2 x / (3 pi)`` (``x = F_0 / (A p_s)``, the spool in quadrature
with the force): a loss of magnitude ``(w / w_f) 2 x / (3 pi)``, 1-3 % over a 1-30 Hz chirp at
2 kN on the shipped 15 kN actuator, which the small-signal model (``N = 1``) would read as a
3 % lower ``w_f``. With a chirp (:attr:`Measured.command`) each bin is the
quasi-steady sinusoid at its frequency, and ``N`` is found with the force and spool phasors
it gives (a fixed point, :data:`DESCRIBING_ITERATIONS`); a random excitation is fitted with
``N = 1`` (its amplitude is no sinusoid's).

The command reaches the force loop through the servo controller's command rate limit
(``rig.actuator.force_rate_limit_N_per_s``, applied once per controller sample): the loop's
staircase jumps by up to ``2 pi f A T`` per tick, 700 N at 28 Hz and 2 kN in a 2 ms tick,
which a 500 kN/s limit spreads over three 0.5 ms samples. That is a lag growing with frequency
and amplitude (3.9 deg at 28.6 Hz here) that no linear term holds; with a chirp it is taken
per bin from the staircase itself (:class:`CommandPath`), before the fit, since it depends on
no fitted value.

``k_h = 4 beta_e A^2 / V_t`` the hydraulic stiffness, ``c = k_h C_l / A^2`` the leakage's
pole. What the loop records adds a delay ``tau`` between the command and the load cell (the
command's transport, the status frame's period, the hold of the command over a tick).

- **Blocked** (``xdot_b = 0``): ``H_b = e^{-s tau} R N w_f G_v / D``, ``R`` the command's hold and rate limit.
- **Free**: the base mat moves, ``xdot_b`` answers the force through the structure, its
  bearings' friction and the table. Taking the cross-spectrum of (F1) with the command gives,
  whatever moves the base mat (friction included),
  ``H_free = (e^{-s tau} R N w_f G_v - k_h (1 - alpha N G_v H) T) / D`` with ``T`` the measured response from the
  command to the sliding velocity (:data:`VELOCITY_FILE`). No model of the structure is
  needed: the free condition adds ``k_h`` alone.

The fit: least squares on the complex response (real and imaginary parts of the relative
error ``(H_model - H) / |H|``), both conditions together, each bin weighted by
``sqrt(2 n_d gamma^2 / (1 - gamma^2))``, the inverse of the H1 estimate's relative standard
deviation (Bendat & Piersol) with ``n_d`` the Welch segments, ``gamma^2`` capped at
:data:`COHERENCE_CAP`. Standard errors are the larger of the Jacobian's (the residuals'
correlation across neighbouring bins in) and the data's own: the sandwich over
:data:`~.fit_statistics.BLOCKS` consecutive stretches of the band, both conditions' bins of a
stretch together (the chirp sweeps the band in time, so a stretch of the band is a stretch of
the run); :func:`.fit_statistics.honest_standard_errors`, as the structure and bearing fits do.

Which groups the data determine (:data:`FITTED`, :data:`HELD`): the force loop's gain
``w_f`` (the blocked response's bandwidth), the valve's natural frequency ``w_v`` (inside
the loop it shapes the closed loop's magnitude near ``w_f``, which a pure delay cannot), the
delay ``tau`` (phase the loop's magnitude does not explain), and with a free condition ``k_h``.
Held at the profile's values: ``zeta_v`` (below ``w_v`` the valve's phase is
``2 zeta_v w / w_v``, so ``zeta_v`` and ``w_v`` trade one for the other; :func:`fit_actuator`
reports their correlation when both are freed) and ``C_l`` (its pole ``c`` is below 1 rad/s,
a gain change of 0.01 dB within the band). ``A``, ``V_t``, ``q_nl`` and ``K_p`` enter only
through ``w_f`` and ``k_h``; with the cylinder's geometry (``A``, ``V_t``) known from its
drawings, ``k_h`` gives the bulk modulus ``beta_e = k_h V_t / (4 A^2)``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from scipy import optimize

from harness.hydraulics import linear
from harness.hydraulics.config import HydraulicActuatorConfig
from harness.identification.fit_statistics import (
    correlation_time,
    covariance,
    honest_standard_errors,
    relative_error,
    time_blocks,
)
from harness.identification.frf import FrequencyResponse

#: The measured response from the command to the sliding velocity, free condition (m/s per N).
VELOCITY_FILE = "frf_velocity.csv"
#: Coherence is capped here in the weights: beyond it the estimate's bias (the orifice's
#: nonlinearity, leakage, the hold between ticks) exceeds its variance.
COHERENCE_CAP = 0.999
#: The fitted parameters, in the order of the fit's vector.
FITTED = ("force_loop_bandwidth_hz", "valve_bandwidth_hz", "delay_s", "hydraulic_stiffness_N_per_m", "velocity_lag_s",
          "feedforward_gain")
#: Fitted only with a free condition.
FREE_ONLY = ("hydraulic_stiffness_N_per_m", "velocity_lag_s", "feedforward_gain")
#: Held at the profile's values, and why.
HELD = {
    "valve_damping_ratio": "below the valve's natural frequency its phase is 2 zeta_v w / w_v: zeta_v and w_v trade one "
                           "for the other (their correlation when both are freed is reported)",
    "leakage_m3_per_s_Pa": "its pole c = k_h C_l / A^2 is below 1 rad/s: a gain change of about 0.01 dB within the band",
}
#: Relative standard error above which a fitted value counts as not determined by the data.
DETERMINED_REL_ERROR = 0.1
#: Points over a period at which :func:`orifice_describing_function` takes the first harmonic.
DESCRIBING_POINTS = 128
#: Fixed-point iterations for the describing function (it moves the phasors by about ``x / 5``:
#: each iteration multiplies the change by about that, 0.03 at the shipped 2 kN).
DESCRIBING_ITERATIONS = 4
_PHASE = np.exp(2j * np.pi * np.arange(DESCRIBING_POINTS) / DESCRIBING_POINTS)
#: Ticks of the staircase over which :meth:`CommandPath.factor` takes the first harmonics (4 s at
#: 500 Hz: five periods of the lowest 1.2 Hz bin).
RATE_LIMIT_TICKS = 2000


@dataclass(frozen=True)
class ActuatorParameters:
    """The linearised actuator of (F1).

    Attributes
    ----------
    force_loop_bandwidth_hz : float
        ``w_f / 2 pi`` (Hz).
    valve_bandwidth_hz, valve_damping_ratio : float
        ``w_v / 2 pi`` (Hz) and ``zeta_v``.
    delay_s : float
        ``tau`` (s), command to recorded load cell.
    hydraulic_stiffness_N_per_m : float
        ``k_h`` (N/m).
    leakage_pole_per_s : float
        ``c`` (1/s).
    velocity_lag_s : float
        How much later the sliding velocity is measured than the load cell's force (s): the
        velocity sensors' conditioning delay (``rig.sensors.velocity.delay_s``).
    feedforward_gain : float
        ``alpha``, the share of ``k_h`` the servo controller's velocity feed-forward cancels (SPEC 7a');
        fitted with a free condition when the profile's is not 0.
    feedforward_filter_hz, feedforward_delay_s : float
        The feed-forward's LVDT filter corner (Hz) and delay (s, the LVDT's and half a sample of
        the backward difference): the servo controller's settings, held.
    force_capacity_N : float
        ``A p_s`` (N), the cylinder's force with the whole supply across the piston: the scale of
        the orifice's describing function (held: the supply pressure and the piston are the
        equipment's, known; ``inf``: the small-signal model).
    """

    force_loop_bandwidth_hz: float
    valve_bandwidth_hz: float
    valve_damping_ratio: float
    delay_s: float
    hydraulic_stiffness_N_per_m: float
    leakage_pole_per_s: float = 0.0
    velocity_lag_s: float = 0.0
    feedforward_gain: float = 0.0
    feedforward_filter_hz: float = math.inf
    feedforward_delay_s: float = 0.0
    force_capacity_N: float = math.inf

    @classmethod
    def from_config(cls, hydraulics: HydraulicActuatorConfig, delay_s: float, velocity_lag_s: float = 0.0,
                    sample_s: float = 0.0) -> ActuatorParameters:
        """The profile's actuator (``rig.actuator.hydraulics``) with a delay ``delay_s`` (s).

        ``sample_s`` is the servo controller's sample period (the rig's physics sub-step), whose half
        the feed-forward's backward difference adds to its LVDT's delay.
        """
        c, feedforward = hydraulics.cylinder, hydraulics.feedforward
        return cls(
            hydraulics.force_loop_bandwidth_hz, c.valve_bandwidth_hz, c.valve_damping_ratio, delay_s,
            c.hydraulic_stiffness_N_per_m,
            linear.leakage_pole_per_s(c.hydraulic_stiffness_N_per_m, c.leakage_m3_per_s_Pa, c.piston_area_m2),
            velocity_lag_s, feedforward.gain, feedforward.velocity_filter_hz, feedforward.lvdt.delay_s + 0.5 * sample_s,
            c.force_capacity_N,
        )

    def velocity_feedback_Ns_per_m(self) -> float:
        """``c_eff = (1 - alpha) k_h / w_f`` (N s/m): the force lost per m/s of stroke at low frequency and no load."""
        return linear.velocity_feedback_Ns_per_m(
            self.hydraulic_stiffness_N_per_m, self.bandwidth_rad_s(), self.feedforward_gain,
        )

    def bandwidth_rad_s(self) -> float:
        """``w_f`` (rad/s): the force loop's bandwidth on a blocked piston."""
        return linear.angular_frequency_rad_s(self.force_loop_bandwidth_hz)

    def vector(self) -> np.ndarray:
        """The :data:`FITTED` values."""
        return np.array([getattr(self, name) for name in FITTED])

    def with_vector(self, values: np.ndarray) -> ActuatorParameters:
        """These parameters with the :data:`FITTED` ones replaced."""
        return dataclasses.replace(self, **dict(zip(FITTED, (float(v) for v in values), strict=True)))


def _valve(p: ActuatorParameters, s: np.ndarray) -> np.ndarray:
    """``G_v(s)``."""
    w_v = linear.angular_frequency_rad_s(p.valve_bandwidth_hz)
    return w_v**2 / (s**2 + 2.0 * p.valve_damping_ratio * w_v * s + w_v**2)


def _feedforward_stiffness(p: ActuatorParameters, s: np.ndarray) -> np.ndarray:
    """``alpha k_h G_v H``: the flow demand the servo controller's feed-forward adds per m of stroke (N/m, complex).

    ``H`` is the feed-forward's LVDT delay and first-order filter (SPEC 7a'); 0 for a plain loop.
    """
    if p.feedforward_gain == 0.0:
        return np.zeros(np.shape(s), dtype=complex)
    sensed = np.exp(-s * p.feedforward_delay_s) / (1.0 + s / (2.0 * np.pi * p.feedforward_filter_hz))
    return p.feedforward_gain * p.hydraulic_stiffness_N_per_m * _valve(p, s) * sensed


def orifice_describing_function(demand: np.ndarray, force_N: np.ndarray, capacity_N: float) -> np.ndarray:
    """The valve's flow per spool opening at its first harmonic, relative to no load (complex, per bin).

    The spool ``x_v = Re(X e^{j theta})`` (any scale: ``demand`` is proportional to it) passes
    ``q_nl x_v sqrt(1 - sign(x_v) p_L / p_s)`` with ``A p_L = Re(F e^{j theta})``;
    ``N = Q_1 / X``, ``Q_1`` the flow's first harmonic over :data:`DESCRIBING_POINTS` points.
    Past the supply (``sign(x_v) p_L > p_s``) the valve passes nothing.

    Parameters
    ----------
    demand : numpy.ndarray
        Phasors proportional to the spool's (complex).
    force_N : numpy.ndarray
        Phasors of the cylinder's force ``A p_L`` (N, complex), same shape.
    capacity_N : float
        ``A p_s`` (N).
    """
    spool = np.real(np.multiply.outer(demand, _PHASE))
    load = np.real(np.multiply.outer(force_N, _PHASE)) / capacity_N
    flow = spool * np.sqrt(np.clip(1.0 - np.sign(spool) * load, 0.0, None))
    first = 2.0 * np.mean(flow * np.conj(_PHASE), axis=-1)
    safe = np.where(demand == 0, 1.0, demand)
    return np.where(demand == 0, 1.0, first / safe)


def _recorded_force(p: ActuatorParameters, freq_hz: np.ndarray, stroke: np.ndarray | None,
                    command: CommandPath | None) -> np.ndarray:
    """The recorded load cell per N of command (complex): (F1) with ``stroke`` the sliding velocity per N of command.

    ``stroke`` None is the blocked piston. Without ``command`` (small signal) ``N`` and the rate
    limit's ``R`` are 1. With it, ``R`` is :meth:`CommandPath.factor`, and ``N`` is iterated with
    the force and the spool's phasors the loop gives at its amplitude
    (:func:`orifice_describing_function`; 1 for an infinite ``p.force_capacity_N``).
    """
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    gain = p.bandwidth_rad_s() * _valve(p, s)
    reaching = np.exp(-s * p.delay_s) * (1.0 if command is None else command.factor(freq_hz))  # per N of command
    amplitude_N = 0.0 if command is None else command.amplitude_N
    velocity = np.zeros_like(s) if stroke is None else stroke
    feedforward = _feedforward_stiffness(p, s) * velocity

    def force(describing: np.ndarray | float) -> np.ndarray:
        return (describing * (gain * reaching + feedforward) - p.hydraulic_stiffness_N_per_m * velocity) / (
            s + p.leakage_pole_per_s + describing * gain)

    describing: np.ndarray | float = 1.0
    for _ in range(DESCRIBING_ITERATIONS if amplitude_N > 0.0 and math.isfinite(p.force_capacity_N) else 0):
        now = force(describing)
        demand = gain * (reaching - now) + feedforward
        describing = orifice_describing_function(demand * amplitude_N, now * amplitude_N, p.force_capacity_N)
    return force(describing)


def blocked_response(p: ActuatorParameters, freq_hz: np.ndarray, command: CommandPath | None = None) -> np.ndarray:
    """``H_b(j w)``: command to recorded load cell with the piston held (N/N, complex).

    ``command``: a chirp's, for the orifice's describing function and the rate limit; None: small signal.
    """
    return _recorded_force(p, freq_hz, None, command)


def velocity_feedback_response(p: ActuatorParameters, freq_hz: np.ndarray) -> np.ndarray:
    """``k_h (1 - alpha G_v H) / D(j w)``: the force the sliding velocity bleeds, per m/s (N s/m, complex; small signal).

    ``k_h / w_f`` at low frequency for a plain loop, ``(1 - alpha) k_h / w_f`` with the servo
    controller's velocity feed-forward. With :func:`blocked_response` it is the whole actuator of
    (F1), whatever it pushes.
    """
    s = 2j * np.pi * np.asarray(freq_hz, dtype=float)
    denominator = s + p.leakage_pole_per_s + p.bandwidth_rad_s() * _valve(p, s)
    return (p.hydraulic_stiffness_N_per_m - _feedforward_stiffness(p, s)) / denominator


def free_response(p: ActuatorParameters, freq_hz: np.ndarray, velocity_response: np.ndarray,
                  command: CommandPath | None = None) -> np.ndarray:
    """``H_free(j w)`` given the measured command-to-sliding-velocity response ``T`` (m/s per N, complex).

    The delay ``tau`` is the command's: the velocity bleeds the force where it is, so ``T`` enters
    as measured, advanced by the velocity sensors' delay relative to the load cell
    (:attr:`ActuatorParameters.velocity_lag_s`). ``command`` as in :func:`blocked_response`.
    """
    lead = np.exp(2j * np.pi * np.asarray(freq_hz, dtype=float) * p.velocity_lag_s)
    return _recorded_force(p, freq_hz, velocity_response * lead, command)


def complex_response(response: FrequencyResponse) -> np.ndarray:
    """A measured response as complex numbers."""
    return response.magnitude * np.exp(1j * np.radians(response.phase_deg))


def bin_weights(response: FrequencyResponse, segments: float) -> np.ndarray:
    """``sqrt(2 n_d gamma^2 / (1 - gamma^2))`` per bin, ``gamma^2`` capped at :data:`COHERENCE_CAP`."""
    coherence = np.clip(response.coherence, 0.0, COHERENCE_CAP)
    return np.sqrt(2.0 * segments * coherence / (1.0 - coherence))


@dataclass(frozen=True)
class CommandPath:
    """How the loop's command reaches the force loop: a staircase of the loop's period, rate limited.

    Attributes
    ----------
    amplitude_N : float
        The chirp's amplitude (N); 0 for an excitation that is no sinusoid (random): the
        staircase's hold alone, no describing function, no rate limit.
    tick_s : float
        The loop's period (s): the command is a staircase of this step.
    sample_s : float
        The servo controller's sample period (s), at which its rate limit acts.
    rate_limit_N_per_s : float
        The servo controller's command rate limit (N/s); ``inf``: none.
    """

    amplitude_N: float
    tick_s: float
    sample_s: float
    rate_limit_N_per_s: float = math.inf
    _factors: dict[bytes, np.ndarray] = field(default_factory=dict, compare=False, repr=False)

    def factor(self, freq_hz: np.ndarray) -> np.ndarray:
        """Per bin, the command reaching the loop over the sinusoid commanded, less the hold's half tick (complex).

        The hold of a staircase of period ``T`` is ``sinc(f T) e^{-j pi f T}`` at its first
        harmonic; the half tick is in the fit's delay, so the hold alone gives ``sinc(f T)``
        (0.6 % at 30 Hz and 500 Hz). With a chirp's amplitude and a finite limit, the staircase
        ``A sin(2 pi f k T)`` over :data:`RATE_LIMIT_TICKS` ticks is held over the controller's
        samples and moved at most ``rate_limit_N_per_s * sample_s`` per sample, as the virtual
        rig's servo controller does (:func:`harness.rig.actuator.slew_and_clamp`), and its first
        harmonic is taken against the sinusoid's.
        """
        freq_hz = np.asarray(freq_hz, dtype=float)
        key = freq_hz.tobytes()
        if key not in self._factors:
            self._factors[key] = self._compute(freq_hz)
        return self._factors[key]

    def _compute(self, freq_hz: np.ndarray) -> np.ndarray:
        if self.amplitude_N <= 0.0 or not math.isfinite(self.rate_limit_N_per_s):
            return np.sinc(freq_hz * self.tick_s).astype(complex)
        per_tick = max(1, int(round(self.tick_s / self.sample_s)))
        samples = RATE_LIMIT_TICKS * per_tick
        time_s = np.arange(samples) * self.sample_s
        staircase = self.amplitude_N * np.sin(2.0 * np.pi * np.outer(freq_hz, (np.arange(samples) // per_tick) * self.tick_s))
        limited = np.empty_like(staircase)
        step = self.rate_limit_N_per_s * self.sample_s
        held = np.zeros(freq_hz.shape)
        for j in range(samples):
            held = np.clip(staircase[:, j], held - step, held + step)
            limited[:, j] = held
        phasor = np.exp(-2j * np.pi * np.outer(freq_hz, time_s))
        sinusoid = self.amplitude_N * np.sin(2.0 * np.pi * np.outer(freq_hz, time_s))
        sample_hold = np.sinc(freq_hz * self.sample_s) * np.exp(-1j * np.pi * freq_hz * self.sample_s)  # each sample held
        half_tick = np.exp(-1j * np.pi * freq_hz * self.tick_s)
        return (limited * phasor).sum(axis=1) / (sinusoid * phasor).sum(axis=1) * sample_hold / half_tick


@dataclass(frozen=True)
class Measured:
    """What the fit is given: the blocked response, and optionally the free one with its ``T``.

    Attributes
    ----------
    blocked : FrequencyResponse or None
    free, velocity : FrequencyResponse or None
        Both or neither: the free response and the command-to-sliding-velocity one, same bins.
    segments : float
        Welch segments averaged per estimate (``n_d``), for the weights.
    command : CommandPath or None
        The command's hold and, with a chirp, its amplitude and the servo controller's rate
        limit, for the orifice's describing function and the rate limit's lag. None: the
        small-signal model of a continuous command.
    """

    blocked: FrequencyResponse | None = None
    free: FrequencyResponse | None = None
    velocity: FrequencyResponse | None = None
    segments: float = 8.0
    command: CommandPath | None = None

    def __post_init__(self) -> None:
        if (self.free is None) != (self.velocity is None):
            raise ValueError("expected the free response together with its command-to-sliding-velocity response")
        if self.blocked is None and self.free is None:
            raise ValueError("expected a blocked or a free response to fit")
        if self.free is not None and self.velocity is not None and not np.allclose(self.free.freq_hz, self.velocity.freq_hz):
            raise ValueError("expected the free and the sliding-velocity responses on the same frequencies")


@dataclass(frozen=True)
class ConditionError:
    """The fit's error over the band in one condition: ``|H_fit| / |H| - 1`` (%) and the phase difference (deg)."""

    condition: str
    magnitude_rms_pct: float
    magnitude_max_pct: float
    phase_rms_deg: float
    phase_max_deg: float

    def as_dict(self) -> dict[str, float | str]:
        """For ``identification.json``."""
        return dict(self.__dict__)


@dataclass(frozen=True)
class ActuatorFit:
    """The fitted actuator and how well the data determine it.

    Attributes
    ----------
    parameters : ActuatorParameters
    standard_errors : dict of str to float
        Per :data:`fitted` name, in its unit.
    fitted : tuple of str
        The names fitted (``hydraulic_stiffness_N_per_m`` only with a free condition).
    errors : tuple of ConditionError
    valve_correlation : float
        Correlation of ``w_v`` and ``zeta_v`` when both are freed at the solution (why ``zeta_v`` is held).
    """

    parameters: ActuatorParameters
    standard_errors: dict[str, float]
    fitted: tuple[str, ...]
    errors: tuple[ConditionError, ...]
    valve_correlation: float = math.nan
    notes: tuple[str, ...] = field(default=())
    covariance: np.ndarray | None = field(default=None, compare=False)

    def velocity_feedback(self) -> tuple[float, float] | None:
        """``(c_eff, standard error)`` (N s/m) from the free condition, or None without one.

        ``c_eff = (1 - alpha) k_h / w_f``, its error from the fit's covariance of ``k_h``, ``w_f``
        and ``alpha`` (the delta method: their errors are correlated).
        """
        if "hydraulic_stiffness_N_per_m" not in self.fitted or self.covariance is None:
            return None
        p = self.parameters
        value = p.velocity_feedback_Ns_per_m()
        omega = p.bandwidth_rad_s()
        partials = {
            "hydraulic_stiffness_N_per_m": (1.0 - p.feedforward_gain) / omega,
            "force_loop_bandwidth_hz": -value / p.force_loop_bandwidth_hz,
            "feedforward_gain": -linear.loop_damping_Ns_per_m(p.hydraulic_stiffness_N_per_m, omega),
        }
        gradient = np.array([partials.get(name, 0.0) for name in self.fitted])
        return value, float(math.sqrt(max(float(gradient @ self.covariance @ gradient), 0.0)))

    def determined(self, name: str) -> bool:
        """True when ``name``'s relative standard error is at most :data:`DETERMINED_REL_ERROR`."""
        return name in self.fitted and relative_error(getattr(self.parameters, name), self.standard_errors[name]) \
            <= DETERMINED_REL_ERROR


def _residuals(p: ActuatorParameters, measured: Measured) -> np.ndarray:
    """Weighted relative complex errors of both conditions, real and imaginary parts stacked."""
    parts = []
    if measured.blocked is not None:
        h = complex_response(measured.blocked)
        error = (blocked_response(p, measured.blocked.freq_hz, measured.command) - h) / np.abs(h)
        parts.append(error * bin_weights(measured.blocked, measured.segments))
    if measured.free is not None and measured.velocity is not None:
        h = complex_response(measured.free)
        model = free_response(p, measured.free.freq_hz, complex_response(measured.velocity), measured.command)
        parts.append((model - h) / np.abs(h) * bin_weights(measured.free, measured.segments))
    stacked = np.concatenate(parts)
    return np.concatenate([stacked.real, stacked.imag])


def condition_error(condition: str, model: np.ndarray, response: FrequencyResponse) -> ConditionError:
    """The fit's magnitude error (%) and phase error (deg) over ``response``'s band."""
    ratio = np.abs(model) / response.magnitude - 1.0
    phase = np.degrees(np.angle(model * np.exp(-1j * np.radians(response.phase_deg))))
    return ConditionError(
        condition, float(100 * np.sqrt(np.mean(ratio**2))), float(100 * np.max(np.abs(ratio))),
        float(np.sqrt(np.mean(phase**2))), float(np.max(np.abs(phase))),
    )


def fit_actuator(measured: Measured, start: ActuatorParameters, hold: tuple[str, ...] = ()) -> ActuatorFit:
    """Fit (F1) to the measured responses, from ``start`` (the profile's actuator).

    Parameters
    ----------
    measured : Measured
    start : ActuatorParameters
        First guess and the held values (``zeta_v``, ``c``).
    hold : tuple of str
        :data:`FITTED` names to hold at ``start``'s values as well.

    Returns
    -------
    ActuatorFit
    """
    if start.feedforward_gain == 0.0:  # a plain loop: nothing to fit
        hold = (*hold, "feedforward_gain")
    names = tuple(n for n in FITTED if n not in hold and (measured.free is not None or n not in FREE_ONLY))
    index = [FITTED.index(n) for n in names]
    scale = start.vector()[index]
    scale = np.where(scale > 0, scale, 1e-3)

    def params(x: np.ndarray) -> ActuatorParameters:
        full = start.vector()
        full[index] = x * scale
        return start.with_vector(full)

    solution = optimize.least_squares(
        lambda x: _residuals(params(x), measured), np.ones(len(names)), bounds=(1e-3, 1e3), x_scale="jac", method="trf",
    )
    best = params(solution.x)
    cov = _honest_covariance(solution.jac, solution.fun, _band_blocks(measured)) * np.outer(scale, scale)
    errors = {name: float(math.sqrt(max(cov[i, i], 0.0))) for i, name in enumerate(names)}
    conditions = []
    if measured.blocked is not None:
        model = blocked_response(best, measured.blocked.freq_hz, measured.command)
        conditions.append(condition_error("blocked", model, measured.blocked))
    if measured.free is not None and measured.velocity is not None:
        model = free_response(best, measured.free.freq_hz, complex_response(measured.velocity), measured.command)
        conditions.append(condition_error("free", model, measured.free))
    return ActuatorFit(best, errors, tuple(names), tuple(conditions), _valve_correlation(best, measured), covariance=cov)


def _band_blocks(measured: Measured) -> np.ndarray:
    """The stretch of the band (0 .. BLOCKS - 1) of each residual of :func:`_residuals`, in its layout."""
    conditions = [r for r in (measured.blocked, measured.free if measured.velocity is not None else None) if r is not None]
    blocks = np.concatenate([time_blocks(len(response.freq_hz)) for response in conditions])
    return np.concatenate([blocks, blocks])  # real parts, then imaginary parts


def _honest_covariance(jacobian: np.ndarray, residuals: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """The fit's covariance, each variance the larger of the Jacobian's and the blocks' (correlations the Jacobian's)."""
    model = covariance(jacobian, residuals, correlation_time(residuals))
    errors = honest_standard_errors(jacobian, residuals, blocks)
    model_errors = np.sqrt(np.maximum(np.diag(model), 0.0))
    ratio = np.divide(errors, model_errors, out=np.ones_like(errors), where=model_errors > 0)
    return model * np.outer(ratio, ratio)


def _valve_correlation(p: ActuatorParameters, measured: Measured) -> float:
    """Correlation of ``w_v`` and ``zeta_v`` from the Jacobian at ``p`` with both free."""
    base = np.array([p.valve_bandwidth_hz, p.valve_damping_ratio])

    def residual(x: np.ndarray) -> np.ndarray:
        changed = dataclasses.replace(p, valve_bandwidth_hz=x[0] * base[0], valve_damping_ratio=x[1] * base[1])
        return _residuals(changed, measured)

    r0 = residual(np.ones(2))
    step = 1e-5
    jac = np.column_stack([(residual(np.ones(2) + step * np.eye(2)[k]) - r0) / step for k in range(2)])
    cov = np.linalg.pinv(jac.T @ jac)
    denominator = math.sqrt(cov[0, 0] * cov[1, 1])
    return float(cov[0, 1] / denominator) if denominator > 0 else math.nan


def bulk_modulus_Pa(hydraulic_stiffness_N_per_m: float, hydraulics: HydraulicActuatorConfig) -> float:
    """``beta_e = k_h V_t / (4 A^2)`` (Pa) with the cylinder's geometry from the profile.

    :func:`harness.hydraulics.linear.bulk_modulus_Pa` on ``rig.actuator.hydraulics.cylinder``'s ``A`` and ``V_t``.
    """
    c = hydraulics.cylinder
    return linear.bulk_modulus_Pa(hydraulic_stiffness_N_per_m, c.piston_area_m2, c.oil_volume_m3)
