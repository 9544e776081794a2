"""The excitation of an identification run: a force signal, its limits, and the controller that plays it.

The signal is a logarithmic chirp (equal time per octave, as a lab's swept-sine tool plays
it) or band-limited random noise (Gaussian, zero outside the band), scaled so that its peak
is the amplitude. Both start and end at zero force through raised-cosine tapers
(:attr:`Excitation.taper_s`), so the supervisor's rate limit never sees a step.

The signal is sent as the commanded actuator force through the run's normal path:
:class:`ExcitationController` is a controller like the sliding-mode ones (the
:class:`~harness.control.controllers.Controller` protocol), which ignores the measurements
and returns the signal at the loop's time; the supervisor clamps, rate-limits and fades it,
and trips on any interlock, exactly as it does a controller's force.

:func:`check_within_limits` refuses, before anything moves, an excitation the supervisor
would have to clip: a peak above ``safety.force.max_force_N``, or a peak force rate above
``safety.force.max_force_rate_N_per_s``. The peak rate of a band-limited signal of peak
``A`` and highest frequency ``f_high`` is at most ``2 pi f_high A`` (Bernstein's
inequality; a sine at ``f_high`` reaches it), so that is the figure checked, with the
sampled signal's own largest step rate if that is larger (the tapers add a little).

What to play (:class:`Excitation`, the command's options) is in
:mod:`harness.identification.excitation_settings`, which the command line's parser reads without numpy.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from drivers.measurements import Measurements
from harness.identification.choices import MIN_BAND_BINS
from harness.identification.excitation_settings import Excitation, ExcitationError
from harness.safety.config import ForceConfig

#: Welch segments an estimate needs at least (with 50 % overlap): fewer give a coherence of 1 by construction.
MIN_AVERAGES = 4


def _ramp(n: int) -> np.ndarray:
    """``n`` samples of a raised cosine from 0 to 1."""
    return 0.5 - 0.5 * np.cos(np.pi * np.arange(n) / max(n - 1, 1))


def _taper(n: int, start_n: int, end_n: int) -> np.ndarray:
    """A window of ``n`` samples rising from 0 to 1 over ``start_n`` samples and falling back over the last ``end_n``."""
    window = np.ones(n)
    if start_n > 1:
        window[:start_n] = _ramp(start_n)
    if end_n > 1:
        window[n - end_n:] *= _ramp(end_n)[::-1]
    return window


def _band_limited_noise(n: int, rate_hz: float, band_hz: tuple[float, float], seed: int) -> np.ndarray:
    """Gaussian noise with its spectrum zeroed outside ``band_hz`` (unit standard deviation)."""
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    freq = np.fft.rfftfreq(n, 1.0 / rate_hz)
    spectrum[(freq < band_hz[0]) | (freq > band_hz[1])] = 0.0
    noise = np.fft.irfft(spectrum, n)
    return noise / noise.std()


def excitation_signal(excitation: Excitation, rate_hz: float) -> np.ndarray:
    """The force (N) to command at each tick ``k / rate_hz`` from the start of the excitation.

    Parameters
    ----------
    excitation : Excitation
    rate_hz : float
        The loop's rate (Hz).

    Returns
    -------
    ndarray
        ``round(duration_s * rate_hz) + 1`` samples, zero at both ends, peak ``amplitude_N``.
    """
    n = int(round(excitation.duration_s * rate_hz)) + 1
    t = np.arange(n) / rate_hz
    if excitation.signal == "chirp":
        from scipy.signal import chirp  # here, not at the top: the command line's parser imports this module

        shape = chirp(t, excitation.low_hz, excitation.duration_s, excitation.high_hz, method="logarithmic", phi=-90.0)
    else:
        shape = _band_limited_noise(n, rate_hz, excitation.band_hz, excitation.seed)
    start_s, end_s = excitation.taper_s
    shape = shape * _taper(n, int(round(start_s * rate_hz)), int(round(end_s * rate_hz)))
    return excitation.amplitude_N * shape / np.abs(shape).max()


def peak_rate_N_per_s(excitation: Excitation, samples: np.ndarray, rate_hz: float) -> float:
    """The force rate to check (N/s): ``2 pi f_high A``, or the samples' largest step rate if larger."""
    stepped = float(np.abs(np.diff(samples)).max()) * rate_hz if len(samples) > 1 else 0.0
    return max(excitation.bound_rate_N_per_s, stepped)


def check_within_limits(
    excitation: Excitation, samples: np.ndarray, rate_hz: float, force: ForceConfig, measured_rate_hz: float | None = None,
) -> None:
    """Refuse an excitation the supervisor would clip, or one too short or too fast to estimate from.

    Parameters
    ----------
    excitation : Excitation
    samples : ndarray
        :func:`excitation_signal` at ``rate_hz``.
    rate_hz : float
        The loop's rate (Hz).
    force : ForceConfig
        The profile's ``safety.force``.
    measured_rate_hz : float, optional
        Rate of the measured force's frames (ACTUATOR_STATUS, Hz) when slower than the loop's:
        the band must stay below half of it too.

    Raises
    ------
    ExcitationError
        Naming the option to change and the limit it broke.
    """
    sampled_hz = min(rate_hz, measured_rate_hz or rate_hz)
    nyquist_hz = 0.5 * sampled_hz
    if excitation.low_hz >= excitation.high_hz:
        raise ExcitationError("--band-hz", f"found {excitation.low_hz:g},{excitation.high_hz:g} Hz, expected LOW < HIGH")
    if excitation.high_hz >= nyquist_hz:
        what = "the loop" if sampled_hz == rate_hz else "the measured force (can.status_rate_hz)"
        raise ExcitationError("--band-hz", f"found an upper frequency of {excitation.high_hz:g} Hz, expected one below "
                                           f"{nyquist_hz:g} Hz, the Nyquist frequency of {what} sampled at {sampled_hz:g} Hz")
    peak_N = float(np.abs(samples).max())
    if peak_N > force.max_force_N:
        raise ExcitationError(
            "--amplitude-N", f"found {peak_N:g} N, expected at most safety.force.max_force_N = {force.max_force_N:g} N: "
            "the supervisor would clamp the excitation",
        )
    rate = peak_rate_N_per_s(excitation, samples, rate_hz)
    limit = force.max_force_rate_N_per_s
    if rate > limit:
        largest_amplitude = limit / (2.0 * math.pi * excitation.high_hz)
        highest_hz = limit / (2.0 * math.pi * excitation.amplitude_N)
        raise ExcitationError(
            "--amplitude-N", f"with --band-hz up to {excitation.high_hz:g} Hz the peak force rate is 2 pi f_high A = "
            f"{rate:.4g} N/s, expected at most safety.force.max_force_rate_N_per_s = {limit:g} N/s: lower --amplitude-N "
            f"to {largest_amplitude:.0f} N or the upper frequency of --band-hz to {highest_hz:.3g} Hz",
        )
    segment = excitation.segment_samples(rate_hz)
    check_band_bins(excitation, segment, rate_hz)
    needed_s = (MIN_AVERAGES + 1) * segment / 2 / rate_hz  # MIN_AVERAGES segments at 50 % overlap
    if excitation.duration_s < needed_s:
        raise ExcitationError(
            "--duration", f"found {excitation.duration_s:g} s, expected at least {needed_s:.3g} s: {MIN_AVERAGES} Welch "
            f"averages of {segment} samples ({segment / rate_hz:.3g} s, --resolution-hz {excitation.resolution_hz:g})",
        )


def check_band_bins(excitation: Excitation, segment: int, rate_hz: float) -> None:
    """Refuse a band that holds fewer than :data:`~harness.identification.choices.MIN_BAND_BINS` frequencies of the estimate.

    The estimate has a frequency every ``rate_hz / segment`` Hz (the Welch segment's bins);
    a band between two of them would be excited and then give nothing to fit or plot.

    Raises
    ------
    ExcitationError
        Naming ``--resolution-hz``, the frequencies the band holds and the resolution that would do.
    """
    freq_hz = np.fft.rfftfreq(segment, 1.0 / rate_hz)
    inside = int(np.count_nonzero((freq_hz >= excitation.low_hz) & (freq_hz <= excitation.high_hz)))
    if inside < MIN_BAND_BINS:
        finest_hz = (excitation.high_hz - excitation.low_hz) / MIN_BAND_BINS
        raise ExcitationError(
            "--resolution-hz", f"found {excitation.resolution_hz:g} Hz: the estimate then has a frequency every "
            f"{rate_hz / segment:.3g} Hz ({segment} samples a segment at {rate_hz:g} Hz), and --band-hz "
            f"{excitation.low_hz:g},{excitation.high_hz:g} holds {inside} of them; expected at least {MIN_BAND_BINS} "
            f"(a response to fit and plot, not a point): --resolution-hz {finest_hz:.3g} or finer, or a wider band",
        )


class ExcitationController:
    """Plays a precomputed force signal as a controller's raw force, from the start of RUNNING.

    It ignores the measurements and the friction estimate. Before :meth:`start` and after
    the signal's end it returns zero. The loop's supervisor shapes its output like any
    controller's (clamp, rate limit, stroke fade, stopping ramp) and trips on any interlock.

    Parameters
    ----------
    samples : ndarray
        The force (N) at each tick from the start (:func:`excitation_signal`).
    rate_hz : float
        The loop's rate (Hz): sample ``k`` is played at ``start + k / rate_hz``.
    """

    needs_full_state: ClassVar[bool] = False

    def __init__(self, samples: np.ndarray, rate_hz: float):
        self.samples = np.ascontiguousarray(samples, dtype=float)
        self._values = self.samples.tolist()  # a float per tick without a numpy scalar
        self.rate_hz = float(rate_hz)
        self.start_t_s: float | None = None
        self.reset()

    def reset(self) -> None:
        """Back to silence, not started."""
        self.start_t_s = None
        self.sliding_variable = 0.0
        self.equivalent_force_N = 0.0
        self.force_N = 0.0

    def start(self, t: float) -> None:
        """The excitation's sample 0 is at loop time ``t`` (s): the loop's ``on_start``, when RUNNING begins."""
        self.start_t_s = t

    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None = None) -> float:
        """The excitation's force (N) at loop time ``t`` (s); zero before the start and after the end."""
        start = self.start_t_s
        force = 0.0
        if start is not None:
            k = int(round((t - start) * self.rate_hz))
            if 0 <= k < len(self._values):
                force = self._values[k]
        self.force_N = force
        return force
