"""The actuator fit's large-signal terms: the orifice's describing function and the command's hold and rate limit.

Each is checked against the virtual rig's own physics (the orifice law of
:mod:`harness.hydraulics.cylinder`, the servo controller's rate limit of
:func:`harness.rig.actuator.slew_and_clamp`) run in time, not against the formula it implements.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harness.hydraulics import cylinder as hy
from harness.identification.actuator_fit import (
    ActuatorParameters,
    CommandPath,
    Measured,
    blocked_response,
    fit_actuator,
    orifice_describing_function,
)
from harness.identification.frf import FrequencyResponse
from harness.profile import load_profile
from harness.rig.actuator import slew_and_clamp

PROFILE = load_profile()
HYDRAULICS = PROFILE.rig.actuator.hydraulics
CAPACITY_N = HYDRAULICS.cylinder.force_capacity_N


def _first_harmonic(signal: np.ndarray, time_s: np.ndarray, freq_hz: float) -> complex:
    """The complex amplitude of ``signal`` at ``freq_hz`` over whole periods (``Re(X e^{j w t})``)."""
    return complex(2.0 * np.mean(signal * np.exp(-2j * np.pi * freq_hz * time_s)))


@pytest.mark.parametrize("ratio", [0.02, 0.05])
def test_the_describing_function_of_a_spool_in_quadrature_is_its_small_amplitude_expansion(ratio: float) -> None:
    # Spool cos(theta), force x A p_s sin(theta): N = 1 - x^2 / 32 + j 2 x / (3 pi) + O(x^3).
    n = orifice_describing_function(np.array([1.0 + 0j]), np.array([-1j * ratio * CAPACITY_N]), CAPACITY_N)[0]
    assert n.real == pytest.approx(1.0 - ratio**2 / 32.0, abs=ratio**3)
    assert n.imag == pytest.approx(2.0 * ratio / (3.0 * math.pi), abs=ratio**3)


def test_without_load_or_with_a_scaled_spool_the_describing_function_is_unchanged() -> None:
    spool = np.array([0.3 + 0.1j, 2.0 - 1.0j])
    force = np.array([2000.0 - 500j, -800j])
    assert orifice_describing_function(spool, np.zeros(2, dtype=complex), CAPACITY_N) == pytest.approx(np.ones(2))
    np.testing.assert_allclose(orifice_describing_function(7.0 * spool, force, CAPACITY_N),
                               orifice_describing_function(spool, force, CAPACITY_N), rtol=1e-12)


def test_the_describing_function_is_the_first_harmonic_of_the_rigs_own_orifice_flow() -> None:
    rig = hy.pack_rig(HYDRAULICS, PROFILE.rig.table, 1000.0, True, 0.05)
    block = hy.ACTUATOR_CYLINDER
    area, q_nl = rig[block + hy.AREA], rig[block + hy.VALVE_FLOW]
    spool, force = 0.05 * np.exp(0.4j), 3000.0 * np.exp(-1.2j)
    theta = np.linspace(0.0, 2.0 * np.pi, 4096, endpoint=False)
    flow = np.array([hy.valve_flow(float(np.real(spool * np.exp(1j * t))), float(np.real(force * np.exp(1j * t))) / area,
                                   rig, block) for t in theta])
    measured = complex(2.0 * np.mean(flow * np.exp(-1j * theta))) / (q_nl * spool)
    expected = orifice_describing_function(np.array([spool]), np.array([force]), CAPACITY_N)[0]
    assert measured == pytest.approx(expected, abs=2e-4)
    assert abs(expected.imag) > 0.02  # far from the small-signal 1 at this load: the comparison can fail


@pytest.mark.slow
@pytest.mark.parametrize("freq_hz", [5.0, 15.0, 28.0])
def test_the_blocked_loop_at_2_kn_matches_the_rigs_cylinder_integrated_in_time(freq_hz: float) -> None:
    """The rig's blocked cylinder (its orifice, valve and leakage) under its force loop, integrated in time:
    the force's first harmonic is the large-signal model's, and not the small-signal one's."""
    rig = hy.pack_rig(HYDRAULICS, PROFILE.rig.table, 1000.0, True, 0.05)
    block, area = hy.ACTUATOR_CYLINDER, rig[hy.ACTUATOR_CYLINDER + hy.AREA]
    amplitude = 2000.0
    omega = 2.0 * np.pi * freq_hz

    def rates(t: float, y: np.ndarray) -> np.ndarray:
        out = np.zeros(3)
        current = hy.force_loop_current(rig[hy.ACTUATOR_GAIN], amplitude * math.cos(omega * t), area * y[0], 0.0)
        hy.cylinder_rates(y, out, 0, current, 0.0, 0.0, rig, block)
        return out

    period = 1.0 / freq_hz
    settle, periods = 0.5 + 4 * period, 4
    time_s = settle + np.arange(periods * 400) * period / 400
    solution = solve_ivp(rates, (0.0, time_s[-1]), np.zeros(3), t_eval=time_s, method="LSODA", rtol=1e-9, atol=1e-9,
                         max_step=period / 100)
    measured = _first_harmonic(area * solution.y[0], time_s, freq_hz) / amplitude
    p = ActuatorParameters.from_config(HYDRAULICS, 0.0)
    continuous = CommandPath(amplitude, 1e-7, 1e-7)  # a command neither held nor limited
    large = blocked_response(p, np.array([freq_hz]), continuous)[0]
    small = blocked_response(p, np.array([freq_hz]))[0]
    assert abs(measured / large - 1) < 1e-3
    assert abs(small / large - 1) > 3e-3  # what the small-signal model misses here: the test can tell


@pytest.mark.parametrize("freq_hz", [3.0, 12.5, 28.0])
def test_a_rate_limit_that_never_acts_leaves_the_holds_sinc(freq_hz: float) -> None:
    never = CommandPath(2000.0, 0.002, 0.0005, 1e12).factor(np.array([freq_hz]))[0]
    assert never == pytest.approx(np.sinc(freq_hz * 0.002), abs=2e-4)
    assert CommandPath(0.0, 0.002, 0.0005, 5e5).factor(np.array([freq_hz]))[0] == np.sinc(freq_hz * 0.002)


def test_the_rate_limits_lag_is_the_rig_servo_controllers_run_in_time() -> None:
    """25 Hz, 2 kN, 500 Hz ticks, 2 kHz samples, 500 kN/s: the rig's slew_and_clamp sample by sample, against the sinusoid."""
    freq_hz, amplitude, tick, sample, limit = 25.0, 2000.0, 0.002, 0.0005, 5e5
    per_tick, ticks = 4, 400  # 20 whole periods
    command = amplitude * np.sin(2 * np.pi * freq_hz * tick * (np.arange(ticks * per_tick) // per_tick))
    held, limited = 0.0, np.empty(command.size)
    for j, target in enumerate(command):
        held = limited[j] = slew_and_clamp(held, float(target), limit * sample, math.inf)
    time_s = np.arange(command.size) * sample
    tail = time_s >= 0.2  # past the first five periods
    ratio = _first_harmonic(limited[tail], time_s[tail], freq_hz) / _first_harmonic(
        amplitude * np.sin(2 * np.pi * freq_hz * time_s[tail]), time_s[tail], freq_hz)
    # Each sample held over its period, less the half tick the fit's delay holds.
    expected = ratio * np.sinc(freq_hz * sample) * np.exp(-1j * np.pi * freq_hz * sample) / np.exp(-1j * np.pi * freq_hz * tick)
    found = CommandPath(amplitude, tick, sample, limit).factor(np.array([freq_hz]))[0]
    assert found == pytest.approx(expected, abs=2e-3)
    assert np.degrees(np.angle(found)) < -2.0  # a lag the limit makes, beyond the hold's


def test_a_chirp_fitted_as_small_signal_reads_the_force_loop_low_and_with_its_command_path_finds_it() -> None:
    """The shipped actuator's default chirp (1-30 Hz, 2 kN) as the large-signal model has it, without noise."""
    truth = ActuatorParameters.from_config(HYDRAULICS, 0.003)
    chirp = CommandPath(2000.0, 1.0 / PROFILE.control.rate_hz, PROFILE.rig.physics_substep_s,
                        PROFILE.rig.actuator.force_rate_limit_N_per_s)
    freq = np.arange(1.0, 30.0, 0.25)
    h = blocked_response(truth, freq, chirp)
    blocked = FrequencyResponse(freq, np.abs(h), np.degrees(np.unwrap(np.angle(h))), np.full(freq.size, 0.999))
    start = dataclasses.replace(truth, force_loop_bandwidth_hz=17.0, valve_bandwidth_hz=60.0)
    small = fit_actuator(Measured(blocked, segments=20), start, hold=("delay_s",))
    large = fit_actuator(Measured(blocked, segments=20, command=chirp), start, hold=("delay_s",))
    assert large.parameters.force_loop_bandwidth_hz == pytest.approx(20.0, rel=1e-4)
    assert small.parameters.force_loop_bandwidth_hz < 0.99 * 20.0
