"""The sustained-oscillation check (``force_oscillation``): its high-pass, its window, its limit, its action.

The limit is a running RMS compared strictly (``>``): each test states where it fires to the tick,
at and around the bound, against the detector's own running RMS of a reference run.
"""

from __future__ import annotations

import dataclasses
import math
import random

import pytest

from harness.safety.config import ForceConfig, SafetyConfig, check_config
from harness.safety.detector_base import HighPass
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.oscillation_detectors import ForceOscillation
from harness.safety.supervisor import Supervisor

DT = 0.002  # the shipped profile's 500 Hz
FAST_DT = 0.0005  # a 2 kHz loop (the FD profile)
STATUS_EVERY = 8  # ACTUATOR_STATUS at the shipped can.status_rate_hz, 250 Hz: one load-cell sample every 8 ticks
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


def test_stalls_of_the_loop_move_the_filter_less_far_and_add_no_content() -> None:
    """The controller's band (full scale at 2 Hz, 4 kN at 12.2 Hz) in a 2 kHz loop that stalls 1-10 ms now and then.

    The RMS above the corner is the band's own, as without stalls: the filter's states mean the
    same at every step. The direct-form biquad it replaced read millions of newtons here.
    """
    both = lambda t: 10_000.0 * math.sin(2.0 * math.pi * 2.0 * t) + 4_000.0 * math.sin(2.0 * math.pi * 12.2 * t)  # noqa: E731
    peaks = []
    for stalls in (False, True):
        detector, health, rng, t = ForceOscillation(CONFIG), TickHealth(), random.Random(5), 0.0
        while t < 3.0:
            dt = FAST_DT * (rng.randint(2, 20) if stalls and rng.random() < 0.03 else 1)
            t += dt
            detector.command_N = both(t)
            detector.update(t, dt, health)
        peaks.append(detector.peak_rms_N)
    expected = math.hypot(10_000.0 * _gain(2.0, dt=FAST_DT), 4_000.0 * _gain(12.2, dt=FAST_DT)) / math.sqrt(2)
    assert peaks[0] == pytest.approx(expected, rel=0.03)
    assert peaks[1] == pytest.approx(peaks[0], rel=0.1)
    assert max(peaks) < CONFIG.oscillation_limit_N


def test_a_constant_through_steps_of_any_length_gives_nothing_nor_a_ramp_after_stalls() -> None:
    """At rest on any step; a ramp (a second-order high-pass passes none) back at 0 once the stalls are over."""
    high, rng = HighPass(30.0), random.Random(7)
    assert all(abs(high.update(2_500.0, FAST_DT * rng.randint(1, 40))) < 1e-9 for _ in range(200))  # rounding only
    ramp, t, out = HighPass(30.0), 0.0, 0.0
    for k in range(4000):  # stalls through the first 1.5 s of loop time, then 0.5 s on the period
        dt = FAST_DT * (rng.randint(2, 20) if k < 3000 and rng.random() < 0.05 else 1)
        t += dt
        out = ramp.update(1.0e5 * t, dt)
    assert abs(out) < 1e-3  # N, of a ramp at 100 kN/s


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


# ------------------------------------------------------------------ the load cell's own samples


def _held_load_cell(detector: ForceOscillation, seconds: float, force, fresh_says: bool = True) -> None:
    """A 2 kHz loop over a load cell sampled at 250 Hz and held between samples, as the tick hands it over.

    ``fresh_says=False`` marks every tick fresh: the held value taken for a new sample each tick.
    """
    health, held = TickHealth(), 0.0
    for k in range(int(seconds / FAST_DT)):
        fresh = k % STATUS_EVERY == 0
        if fresh:
            held = force(k * FAST_DT)
        health.measured_force_N, health.actuator_status_fresh = held, fresh or not fresh_says
        detector.update(k * FAST_DT, FAST_DT, health)


def test_at_2_khz_the_load_cell_is_filtered_per_sample_and_the_controllers_band_stays_quiet() -> None:
    """Full scale at 2 Hz and 4 kN at 12.2 Hz, the load cell at 250 Hz, the loop at 2 kHz: quiet.

    Filtered every tick, the held samples are a staircase whose 4 ms steps are content above the
    corner that the force never had: a healthy run at 2 kHz was stopped at 482 N on its stairs
    (a CI run, 29 Nov 2026), where its samples alone gave 162 N. Per sample, the RMS is the band's
    own, at the gain of the filter stepped at the sample interval.
    """
    both = lambda t: 10_000.0 * math.sin(2.0 * math.pi * 2.0 * t) + 4_000.0 * math.sin(2.0 * math.pi * 12.2 * t)  # noqa: E731
    per_sample = ForceOscillation(CONFIG)
    _held_load_cell(per_sample, 3.0, both)
    sample_dt = STATUS_EVERY * FAST_DT
    expected = math.hypot(10_000.0 * _gain(2.0, dt=sample_dt), 4_000.0 * _gain(12.2, dt=sample_dt)) / math.sqrt(2)
    assert per_sample.peak_rms_N == pytest.approx(expected, rel=0.02)
    assert per_sample.peak_rms_N < CONFIG.oscillation_limit_N
    stairs = ForceOscillation(CONFIG)
    _held_load_cell(stairs, 3.0, both, fresh_says=False)
    assert stairs.peak_rms_N > CONFIG.oscillation_limit_N, "the staircase this test guards against is above the limit"


def test_a_load_cell_sampled_at_250_hz_that_limit_cycles_still_fires_when_its_window_says() -> None:
    sample_dt = STATUS_EVERY * FAST_DT
    ratio = 2.0
    amplitude = ratio * CONFIG.oscillation_limit_N * math.sqrt(2) / _gain(LIMIT_CYCLE_HZ, dt=sample_dt)
    detector, health, held, fired = ForceOscillation(CONFIG), TickHealth(), 0.0, []
    for k in range(int(1.0 / FAST_DT)):
        health.actuator_status_fresh = k % STATUS_EVERY == 0
        if health.actuator_status_fresh:
            held = amplitude * math.sin(2.0 * math.pi * LIMIT_CYCLE_HZ * k * FAST_DT)
        health.measured_force_N = held
        fired.append(detector.update(k * FAST_DT, FAST_DT, health))
    first = fired.index(True)
    expected_s = CONFIG.oscillation_window_s * math.log(ratio**2 / (ratio**2 - 1))
    assert first * FAST_DT == pytest.approx(expected_s, abs=0.02)  # a cycle of ripple and the filter's start
    assert first % STATUS_EVERY == 0, "the load cell's RMS moves only with a sample"
    assert all(fired[first:]), "and the check stays active on the ticks between samples"


def test_between_load_cell_samples_an_rms_equal_to_the_limit_is_still_within_it() -> None:
    """The ticks between samples judge the RMS of the last sample by the same rule: acts only above the limit."""
    sample_dt = STATUS_EVERY * FAST_DT
    amplitude = 2.0 * CONFIG.oscillation_limit_N * math.sqrt(2) / _gain(LIMIT_CYCLE_HZ, dt=sample_dt)
    cycle = lambda t: amplitude * math.sin(2.0 * math.pi * LIMIT_CYCLE_HZ * t)  # noqa: E731
    reference = ForceOscillation(dataclasses.replace(CONFIG, oscillation_limit_N=1e9))
    _held_load_cell(reference, 0.3, cycle)
    at_peak = ForceOscillation(dataclasses.replace(CONFIG, oscillation_limit_N=reference.peak_rms_N))
    health, held, fired = TickHealth(), 0.0, []
    for k in range(int(0.3 / FAST_DT)):
        health.actuator_status_fresh = k % STATUS_EVERY == 0
        if health.actuator_status_fresh:
            held = cycle(k * FAST_DT)
        health.measured_force_N = held
        fired.append(at_peak.update(k * FAST_DT, FAST_DT, health))
    assert at_peak.peak_rms_N == reference.peak_rms_N and not any(fired)


def test_a_load_cell_not_finite_fires_on_a_tick_without_a_new_sample_too() -> None:
    detector, health = ForceOscillation(CONFIG), TickHealth()
    assert not detector.update(0.0, FAST_DT, health)
    health.actuator_status_fresh, health.measured_force_N = False, math.inf
    assert detector.update(FAST_DT, FAST_DT, health)


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

