"""The excitation of ``harness identify actuator``: its band, amplitude, limits and the controller that plays it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.measurements import Measurements
from harness.control.controllers import Controller
from harness.identification.excitation import (
    ExcitationController,
    check_within_limits,
    excitation_signal,
    peak_rate_N_per_s,
)
from harness.identification.excitation_settings import Excitation, ExcitationError
from harness.safety.config import ForceConfig

RATE_HZ = 500.0
FORCE = ForceConfig(max_force_N=10_000.0, max_force_rate_N_per_s=400_000.0)


def _share_in_band(samples: np.ndarray, low_hz: float, high_hz: float) -> float:
    power = np.abs(np.fft.rfft(samples)) ** 2
    freq = np.fft.rfftfreq(len(samples), 1.0 / RATE_HZ)
    return float(power[(freq >= low_hz) & (freq <= high_hz)].sum() / power.sum())


@pytest.mark.parametrize("kind", ["chirp", "random"])
def test_the_signal_has_its_amplitude_and_its_band_and_starts_and_ends_at_zero(kind):
    excitation = Excitation(kind, 1500.0, (2.0, 25.0), 30.0, seed=7)
    samples = excitation_signal(excitation, RATE_HZ)
    assert len(samples) == 30 * 500 + 1
    assert np.abs(samples).max() == pytest.approx(1500.0)
    assert samples[0] == pytest.approx(0.0, abs=1e-9) and samples[-1] == pytest.approx(0.0, abs=1e-9)
    assert _share_in_band(samples, 2.0, 25.0) > 0.97  # the tapers spread a little outside
    assert _share_in_band(samples, 1.5, 30.0) > 0.99
    assert _share_in_band(samples, 0.0, 1.0) < 0.005 and _share_in_band(samples, 40.0, 250.0) < 0.001


def test_the_chirp_sweeps_from_the_bottom_of_the_band_to_its_top_logarithmically():
    excitation = Excitation("chirp", 1000.0, (1.0, 30.0), 20.0)
    samples = excitation_signal(excitation, RATE_HZ)
    inner = samples[1:-1]  # the zero samples at both ends left out
    k = np.nonzero(np.diff(np.signbit(inner)))[0]
    crossings = (k + inner[k] / (inner[k] - inner[k + 1])) / RATE_HZ  # linear between the samples
    measured_hz = 1.0 / (2.0 * np.diff(crossings))
    midpoints_s = 0.5 * (crossings[1:] + crossings[:-1])
    expected_hz = 1.0 * 30.0 ** (midpoints_s / 20.0)  # f(t) = f_low (f_high / f_low)^(t / T): equal time per octave
    np.testing.assert_allclose(measured_hz, expected_hz, rtol=0.02)
    assert measured_hz[0] < 1.2 and measured_hz[-1] > 28.0


def test_the_random_signal_follows_its_seed():
    one = excitation_signal(Excitation("random", 1000.0, (1.0, 30.0), 10.0, seed=1), RATE_HZ)
    again = excitation_signal(Excitation("random", 1000.0, (1.0, 30.0), 10.0, seed=1), RATE_HZ)
    other = excitation_signal(Excitation("random", 1000.0, (1.0, 30.0), 10.0, seed=2), RATE_HZ)
    np.testing.assert_array_equal(one, again)
    assert np.abs(one - other).max() > 100.0


@pytest.mark.parametrize("kind", ["chirp", "random"])
def test_the_peak_rate_checked_bounds_the_signal_own_rate(kind):
    excitation = Excitation(kind, 2000.0, (1.0, 30.0), 20.0)
    samples = excitation_signal(excitation, RATE_HZ)
    steepest = np.abs(np.diff(samples)).max() * RATE_HZ
    assert steepest <= peak_rate_N_per_s(excitation, samples, RATE_HZ)
    assert peak_rate_N_per_s(excitation, samples, RATE_HZ) == pytest.approx(2 * math.pi * 30.0 * 2000.0)


def test_an_excitation_within_the_limits_passes():
    excitation = Excitation("chirp", 2000.0, (1.0, 30.0), 40.0)  # 2 pi 30 Hz 2000 N = 377 kN/s
    check_within_limits(excitation, excitation_signal(excitation, RATE_HZ), RATE_HZ, FORCE)


def test_an_amplitude_above_the_force_limit_is_refused_naming_the_option():
    excitation = Excitation("chirp", 10_001.0, (0.5, 5.0), 40.0)
    with pytest.raises(ExcitationError, match=r"^--amplitude-N: .*safety\.force\.max_force_N = 10000 N") as refused:
        check_within_limits(excitation, excitation_signal(excitation, RATE_HZ), RATE_HZ, FORCE)
    assert refused.value.option == "--amplitude-N"


def test_a_peak_rate_above_the_rate_limit_is_refused_naming_the_option_and_the_way_out():
    excitation = Excitation("chirp", 2200.0, (1.0, 30.0), 40.0)  # 415 kN/s
    with pytest.raises(ExcitationError, match=r"^--amplitude-N: .*max_force_rate_N_per_s = 400000 N/s") as refused:
        check_within_limits(excitation, excitation_signal(excitation, RATE_HZ), RATE_HZ, FORCE)
    message = str(refused.value)
    assert "--band-hz" in message
    assert f"{400_000 / (2 * math.pi * 30):.0f} N" in message  # the largest amplitude that passes


def test_a_band_above_the_nyquist_frequency_is_refused():
    excitation = Excitation("chirp", 100.0, (1.0, 250.0), 40.0)
    with pytest.raises(ExcitationError, match=r"^--band-hz: .*250 Hz"):
        check_within_limits(excitation, excitation_signal(excitation, RATE_HZ), RATE_HZ, FORCE)
    slower = Excitation("chirp", 100.0, (1.0, 130.0), 40.0)  # below 250 Hz, above half the status rate
    samples = excitation_signal(slower, RATE_HZ)
    check_within_limits(slower, samples, RATE_HZ, FORCE)
    with pytest.raises(ExcitationError, match=r"^--band-hz: .*status_rate_hz"):
        check_within_limits(slower, samples, RATE_HZ, FORCE, measured_rate_hz=250.0)


def test_an_excitation_too_short_for_its_resolution_is_refused():
    excitation = Excitation("chirp", 1000.0, (1.0, 30.0), 5.0, resolution_hz=0.25)  # needs 5 * 1024 samples
    with pytest.raises(ExcitationError, match=r"^--duration: found 5 s, expected at least 10\.2 s"):
        check_within_limits(excitation, excitation_signal(excitation, RATE_HZ), RATE_HZ, FORCE)


def test_the_controller_plays_the_signal_from_the_start_of_running_and_nothing_else():
    samples = np.array([0.0, 10.0, 20.0, 30.0, 0.0])
    controller = ExcitationController(samples, RATE_HZ)
    assert isinstance(controller, Controller) and not controller.needs_full_state
    meas = Measurements()
    period = 1.0 / RATE_HZ
    assert controller.update(1.0, period, meas, 500.0) == 0.0  # not started: silent
    controller.start(1.0)
    played = [controller.update(1.0 + k * period, period, meas, 500.0) for k in range(7)]
    assert played == [0.0, 10.0, 20.0, 30.0, 0.0, 0.0, 0.0]  # ignores friction and measurements; silent after the end
    assert controller.force_N == 0.0 and controller.sliding_variable == 0.0
    controller.reset()
    assert controller.update(1.0 + 2 * period, period, meas, 0.0) == 0.0


def test_a_band_holding_too_few_frequencies_of_the_estimate_is_refused_before_anything_moves():
    """Issue 30: --resolution-hz 10 --band-hz 1,5 excited the actuator, then raised IndexError (no bin in the band)."""
    from harness.identification.choices import MIN_BAND_BINS

    between = Excitation("chirp", 100.0, (1.0, 5.0), 2.0, resolution_hz=10.0)  # a bin every 500/64 = 7.8 Hz
    with pytest.raises(ExcitationError, match=r"^--resolution-hz: found 10 Hz: .*7\.81 Hz.* holds 0 of them; expected at "
                                              r"least 10 .*--resolution-hz 0\.4 or finer"):
        check_within_limits(between, excitation_signal(between, RATE_HZ), RATE_HZ, FORCE)
    suggested = Excitation("chirp", 100.0, (1.0, 5.0), 40.0, resolution_hz=(5.0 - 1.0) / MIN_BAND_BINS)
    check_within_limits(suggested, excitation_signal(suggested, RATE_HZ), RATE_HZ, FORCE)  # the way out it names works
