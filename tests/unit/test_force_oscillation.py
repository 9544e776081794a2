"""The sustained-oscillation check (``force_oscillation``): its high-pass, its window, its limit, its action.

The limit is a running RMS compared strictly (``>``): each test states where it fires to the tick,
at and around the bound, against the detector's own running RMS of a reference run.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from harness.safety.config import ForceConfig, SafetyConfig, check_config
from harness.safety.detector_base import HighPass
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.oscillation_detectors import ForceOscillation
from harness.safety.supervisor import Supervisor

DT = 0.002  # the shipped profile's 500 Hz
CONFIG = ForceConfig()
LIMIT_CYCLE_HZ = 48.3  # the coupled peak of the shipped actuator's free response (issue 30)


def _gain(frequency_hz: float, corner_hz: float = CONFIG.oscillation_corner_hz, dt: float = DT) -> float:
    """The discrete Butterworth high-pass's gain at ``frequency_hz`` (the bilinear transform, pre-warped at the corner)."""
    r = math.tan(math.pi * frequency_hz * dt) / math.tan(math.pi * corner_hz * dt)
    return r * r / math.sqrt(1.0 + r**4)


def _sine(amplitude_N: float, frequency_hz: float, k: int) -> float:
    return amplitude_N * math.sin(2.0 * math.pi * frequency_hz * k * DT)


def _run(detector: ForceOscillation, n: int, commanded, measured) -> list[bool]:
    """Feed ``n`` ticks of ``commanded(k)`` and ``measured(k)``; return what the detector said each tick."""
    health = TickHealth()
    fired = []
    for k in range(n):
        detector.command_N = commanded(k)
        health.measured_force_N = measured(k)
        fired.append(detector.update(k * DT, DT, health))
    return fired


def _reference_rms(n: int, commanded, measured) -> list[float]:
    """The running RMS (the larger of the two forces) each tick, from a detector that never fires."""
    detector = ForceOscillation(dataclasses.replace(CONFIG, oscillation_limit_N=1e6))
    health = TickHealth()
    out = []
    for k in range(n):
        detector.command_N = commanded(k)
        health.measured_force_N = measured(k)
        detector.update(k * DT, DT, health)
        out.append(max(detector.rms_N))
    return out


# ------------------------------------------------------------------ the high-pass
@pytest.mark.parametrize("frequency_hz", [5.0, 12.2, 30.0, LIMIT_CYCLE_HZ, 100.0])
def test_the_high_pass_is_a_butterworth_at_its_corner_and_around_it(frequency_hz: float) -> None:
    high = HighPass(CONFIG.oscillation_corner_hz)
    n = int(4.0 / DT)
    out = [high.update(_sine(1.0, frequency_hz, k), DT) for k in range(n)]
    last = out[n - int(2.0 / DT):]  # the last two seconds, transient gone
    amplitude = math.sqrt(2.0 * sum(y * y for y in last) / len(last))
    assert amplitude == pytest.approx(_gain(frequency_hz), rel=2e-3, abs=1e-4)
    if frequency_hz == 30.0:
        assert amplitude == pytest.approx(1 / math.sqrt(2), rel=2e-3)  # -3 dB at the corner exactly


def test_the_high_pass_starts_at_rest_passes_no_constant_and_starts_again_after_reset() -> None:
    high = HighPass(30.0)
    assert [high.update(5_000.0, DT) for _ in range(10)] == [0.0] * 10
    high.update(6_000.0, DT)
    assert high.update(6_000.0, DT) != 0.0  # a step passes, then decays
    high.reset()
    assert high.update(-3_000.0, DT) == 0.0


def test_a_step_longer_than_a_quarter_period_at_the_corner_is_taken_as_one() -> None:
    long, capped = HighPass(30.0), HighPass(30.0)
    assert long.max_step_s == pytest.approx(0.25 / 30.0)
    for value in (0.0, 100.0, -50.0, 400.0):
        assert long.update(value, 0.05) == capped.update(value, capped.max_step_s)
    within, at_cap = HighPass(30.0), HighPass(30.0)
    outputs = [(within.update(v, 0.008), at_cap.update(v, at_cap.max_step_s)) for v in (0.0, 100.0, -50.0)]
    assert outputs[-1][0] != outputs[-1][1]  # a step just within the cap is taken as it is


# ------------------------------------------------------------------ the limit, to the tick
def test_fires_just_above_its_limit_and_not_at_it() -> None:
    n = int(1.0 / DT)
    measured = lambda k: _sine(1_000.0, LIMIT_CYCLE_HZ, k)  # noqa: E731
    quiet = lambda k: 0.0  # noqa: E731
    rms = _reference_rms(n, quiet, measured)
    peak = max(rms)
    at_peak = ForceOscillation(dataclasses.replace(CONFIG, oscillation_limit_N=peak))
    assert not any(_run(at_peak, n, quiet, measured)), "an RMS equal to the limit is within it"
    below = dataclasses.replace(CONFIG, oscillation_limit_N=peak * (1 - 1e-9))
    fired = _run(ForceOscillation(below), n, quiet, measured)
    assert fired == [value > peak * (1 - 1e-9) for value in rms]
    assert sum(fired) >= 1


@pytest.mark.parametrize("which", ["commanded", "measured"])
def test_either_force_alone_fires_and_the_detail_names_it(which: str) -> None:
    oscillating = lambda k: _sine(1_500.0, LIMIT_CYCLE_HZ, k)  # noqa: E731
    quiet = lambda k: 0.0  # noqa: E731
    commanded, measured = (oscillating, quiet) if which == "commanded" else (quiet, oscillating)
    detector = ForceOscillation(CONFIG)
    fired = _run(detector, int(1.0 / DT), commanded, measured)
    first = fired.index(True)
    rms = _reference_rms(int(1.0 / DT), commanded, measured)
    assert first == next(k for k, value in enumerate(rms) if value > CONFIG.oscillation_limit_N)
    detail = detector.detail(TickHealth())
    assert detail.startswith(f"{which} force RMS above 30 Hz over a 0.5 s window")
    assert "expected at most 475 N" in detail and "limit cycle" in detail
    assert detector.rms_N[1 if which == "commanded" else 0] == 0.0  # the other force saw nothing


@pytest.mark.parametrize("ratio", [1.5, 2.0, 3.0])
def test_a_sustained_sinusoid_fires_when_its_window_says(ratio: float) -> None:
    """RMS ``r`` times the limit: fires ``window * ln(r^2 / (r^2 - 1))`` after it begins (docs/SAFETY.md)."""
    amplitude = ratio * CONFIG.oscillation_limit_N * math.sqrt(2) / _gain(LIMIT_CYCLE_HZ)
    fired = _run(ForceOscillation(CONFIG), int(2.0 / DT), lambda k: 0.0, lambda k: _sine(amplitude, LIMIT_CYCLE_HZ, k))
    expected_s = CONFIG.oscillation_window_s * math.log(ratio**2 / (ratio**2 - 1))
    assert fired.index(True) * DT == pytest.approx(expected_s, abs=0.012)  # a cycle of ripple and the filter's start
    assert all(fired[fired.index(True):])  # and stays while the oscillation lasts


def test_the_controllers_band_stays_quiet() -> None:
    """Full-scale force at 2 Hz, 4 kN at the top structural mode (12.2 Hz): below the limit."""
    both = lambda k: _sine(10_000.0, 2.0, k) + _sine(4_000.0, 12.2, k)  # noqa: E731
    detector = ForceOscillation(CONFIG)
    assert not any(_run(detector, int(3.0 / DT), both, both))
    expected = math.hypot(10_000.0 * _gain(2.0), 4_000.0 * _gain(12.2)) / math.sqrt(2)
    assert detector.peak_rms_N == pytest.approx(expected, rel=0.05)
    assert detector.peak_rms_N < CONFIG.oscillation_limit_N


def test_a_load_cell_not_finite_fires_and_a_reset_clears_everything() -> None:
    detector = ForceOscillation(CONFIG)
    health = TickHealth()
    assert not detector.update(0.0, DT, health)
    health.measured_force_N = math.nan
    assert detector.update(DT, DT, health)
    assert detector.present(health) == ""  # not knowable from one sample: a reset is never refused
    detector.reset()
    assert detector.rms_N == [0.0, 0.0] and detector.peak_rms_N == 0.0 and detector.command_N == 0.0
    health.measured_force_N = 2_000.0
    assert not detector.update(2 * DT, DT, health)  # started again at rest on the new value
    assert detector.rms_N == [0.0, 0.0]


def test_the_window_must_hold_three_cycles_at_the_corner() -> None:
    def problems(window_s: float) -> list[str]:
        config = SafetyConfig(force=dataclasses.replace(CONFIG, oscillation_corner_hz=30.0, oscillation_window_s=window_s))
        return [p for p in check_config(config) if "oscillation_window_s" in p]

    assert problems(0.1) == []  # 3 cycles
    assert problems(0.0999) and "expected at least 3" in problems(0.0999)[0]
    exact = SafetyConfig(force=dataclasses.replace(CONFIG, oscillation_corner_hz=12.0, oscillation_window_s=0.25))
    assert not [p for p in check_config(exact) if "oscillation" in p]  # exactly 3.0 cycles: accepted


# ------------------------------------------------------------------ in the supervisor
def _supervised(action: str) -> tuple[Supervisor, TickHealth]:
    config = SafetyConfig(force=dataclasses.replace(CONFIG, oscillation_action=action))
    supervisor, health = Supervisor(config, period_s=DT), TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    health.table_fresh = health.base_fresh = False  # no new sensor samples: the sensors' checks have nothing to judge
    return supervisor, health


def test_a_load_cell_that_limit_cycles_stops_the_run_safely_by_default() -> None:
    supervisor, health = _supervised("safe_stop")
    amplitude = 2.0 * CONFIG.oscillation_limit_N * math.sqrt(2) / _gain(LIMIT_CYCLE_HZ)
    for k in range(1, int(1.0 / DT)):
        health.measured_force_N = _sine(amplitude, LIMIT_CYCLE_HZ, k)
        supervisor.update(k * DT, DT, health, 0.0)
        if supervisor.state is not State.RUNNING:
            break
    assert supervisor.state is State.STOPPING and supervisor.stop_reason == "force_oscillation"
    assert k * DT == pytest.approx(CONFIG.oscillation_window_s * math.log(4 / 3), abs=0.012)
    assert "measured force RMS above 30 Hz" in supervisor.stop_detail


def test_a_trip_when_the_profile_says_so_and_the_command_is_watched_too() -> None:
    supervisor, health = _supervised("trip")
    amplitude = 2.0 * CONFIG.oscillation_limit_N * math.sqrt(2) / _gain(LIMIT_CYCLE_HZ)
    for k in range(1, int(1.0 / DT)):  # the load cell stays at zero: only the command the supervisor sent oscillates
        supervisor.update(k * DT, DT, health, _sine(amplitude, LIMIT_CYCLE_HZ, k))
        if supervisor.state is not State.RUNNING:
            break
    assert supervisor.state is State.TRIPPED and supervisor.command.trip_reason == "force_oscillation"
    assert supervisor.trip_detail.startswith("commanded force RMS above 30 Hz")
    assert supervisor.oscillation.command_N == 0.0  # the trip's zero command is what it sees next


def test_the_detail_gives_each_forces_own_rms() -> None:
    """Both forces oscillate, at different amplitudes: the detail names each with its own figure."""
    detector = ForceOscillation(CONFIG)
    commanded = lambda k: _sine(2_000.0, LIMIT_CYCLE_HZ, k)  # noqa: E731
    measured = lambda k: _sine(1_000.0, LIMIT_CYCLE_HZ, k)  # noqa: E731
    assert any(_run(detector, int(1.0 / DT), commanded, measured))
    commanded_rms, measured_rms = detector.rms_N
    assert commanded_rms > 1.5 * measured_rms > 0.0
    detail = detector.detail(TickHealth())
    assert f"(commanded {commanded_rms:.6g} N, measured {measured_rms:.6g} N)" in detail

