"""The SPEC 7a actuator fitted to frequency responses with known answers, noise included."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest
import yaml

from harness.identification.actuator import command_path, identify_actuator_fit, read_measured
from harness.identification.actuator_fit import (
    VELOCITY_FILE,
    ActuatorParameters,
    CommandPath,
    Measured,
    blocked_response,
    bulk_modulus_Pa,
    fit_actuator,
    free_response,
)
from harness.identification.frf import FrequencyResponse, write_frf_csv
from harness.identification.run_signals import IdentificationError
from harness.profile import load_profile

#: A servo controller without velocity feed-forward: the whole k_h shows in the free condition.
PROFILE = load_profile(overrides=["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0"])
HYDRAULICS = PROFILE.rig.actuator.hydraulics
#: The rig as the data have it: force loop, valve and bulk modulus away from the profile's.
TRUE = dataclasses.replace(
    ActuatorParameters.from_config(HYDRAULICS, 0.002, 0.0015),
    force_loop_bandwidth_hz=23.0, valve_bandwidth_hz=55.0,
    hydraulic_stiffness_N_per_m=1.3 * HYDRAULICS.cylinder.hydraulic_stiffness_N_per_m,
)


def _mobility(freq_hz: np.ndarray) -> np.ndarray:
    """A command-to-sliding-velocity response: the base mat and stories as one mass on a spring and damper (m/s per N)."""
    s = 2j * np.pi * freq_hz
    mass, stiffness, damping = 3000.0, 2.0e5, 4.0e3
    return 0.3 * s / (mass * s**2 + damping * s + stiffness)


def _response(h: np.ndarray, freq_hz: np.ndarray, coherence: float, rng: np.random.Generator) -> FrequencyResponse:
    """``h`` with the H1 estimate's scatter at ``coherence`` over 20 segments (relative std sqrt((1-g)/(2 n g)))."""
    std = np.sqrt((1 - coherence) / (2 * 20 * coherence))
    noisy = h * (1 + std * (rng.standard_normal(len(h)) + 1j * rng.standard_normal(len(h))) / np.sqrt(2))
    return FrequencyResponse(freq_hz, np.abs(noisy), np.degrees(np.unwrap(np.angle(noisy))), np.full(len(h), coherence))


def _measured(truth: ActuatorParameters, high_hz: float, seed: int = 0, command: CommandPath | None = None) -> Measured:
    """Both conditions' responses of ``truth``, with ``command``'s hold, orifice and rate limit (None: small signal)."""
    rng = np.random.default_rng(seed)
    freq = np.arange(1.0, high_hz, 0.25)
    mobility = _mobility(freq)
    velocity = _response(mobility, freq, 0.995, rng)
    blocked = _response(blocked_response(truth, freq, command), freq, 0.995, rng)
    free = _response(free_response(truth, freq, mobility, command), freq, 0.99, rng)
    return Measured(blocked, free, velocity, segments=20, command=command)


def _start() -> ActuatorParameters:
    return ActuatorParameters.from_config(HYDRAULICS, 0.002, 0.001)


@pytest.mark.parametrize("seed", [0, 1])
def test_a_band_past_the_force_loop_recovers_every_fitted_value(seed: int) -> None:
    fit = fit_actuator(_measured(TRUE, 80.0, seed), _start())
    for name in fit.fitted:
        assert getattr(fit.parameters, name) == pytest.approx(getattr(TRUE, name), rel=0.02), name
        assert fit.determined(name), name
    for error in fit.errors:  # the fit's error over the band is the noise's
        assert error.magnitude_rms_pct < 2.0 and error.phase_rms_deg < 1.0, error


def test_the_free_condition_alone_determines_the_velocity_feedback() -> None:
    measured = _measured(TRUE, 80.0)
    blocked_only = fit_actuator(dataclasses.replace(measured, free=None, velocity=None), _start())
    assert "hydraulic_stiffness_N_per_m" not in blocked_only.fitted  # nothing in the blocked data moves it
    both = fit_actuator(measured, _start())
    assert both.parameters.hydraulic_stiffness_N_per_m == pytest.approx(TRUE.hydraulic_stiffness_N_per_m, rel=0.02)
    beta = bulk_modulus_Pa(both.parameters.hydraulic_stiffness_N_per_m, HYDRAULICS)
    assert beta == pytest.approx(1.3 * HYDRAULICS.cylinder.bulk_modulus_Pa, rel=0.02)


def test_a_fit_that_ignored_the_velocity_feedback_would_miss_the_free_response() -> None:
    measured = _measured(TRUE, 80.0)
    wrong = dataclasses.replace(TRUE, hydraulic_stiffness_N_per_m=0.0)
    h = measured.free.magnitude * np.exp(1j * np.radians(measured.free.phase_deg))
    model = free_response(wrong, measured.free.freq_hz, _mobility(measured.free.freq_hz))
    assert np.max(np.abs(model / h - 1)) > 0.1  # the term the free condition identifies is not small


def test_with_the_delay_held_the_loop_and_valve_are_still_recovered() -> None:
    fit = fit_actuator(_measured(TRUE, 30.0), _start(), hold=("delay_s",))
    assert "delay_s" not in fit.fitted
    assert fit.parameters.force_loop_bandwidth_hz == pytest.approx(TRUE.force_loop_bandwidth_hz, rel=0.03)
    assert fit.parameters.valve_bandwidth_hz == pytest.approx(TRUE.valve_bandwidth_hz, rel=0.05)


def test_the_valve_frequency_and_damping_trade_one_for_the_other() -> None:
    fit = fit_actuator(_measured(TRUE, 30.0), _start(), hold=("delay_s",))
    assert abs(fit.valve_correlation) > 0.8  # why zeta_v is held


#: The excitation :func:`_write` records: a 700 N chirp at the loop's 500 Hz.
EXCITATION = {"signal": "chirp", "amplitude_N": 700.0, "duration_s": 40.0, "seed": 0, "resolution_hz": 0.25}
#: How that chirp reaches the shipped rig's force loop, as the identification reads it from excitation.json.
CHIRP = command_path(EXCITATION, 500.0, PROFILE)


def _write(out_dir, measured: Measured, band_hz: tuple[float, float]) -> None:
    write_frf_csv(out_dir / "frf_blocked.csv", measured.blocked)
    write_frf_csv(out_dir / "frf.csv", measured.free)
    write_frf_csv(out_dir / VELOCITY_FILE, measured.velocity)
    excitation = {**EXCITATION, "band_hz": list(band_hz)}
    (out_dir / "excitation.json").write_text(json.dumps({"excitation": excitation, "rate_hz": 500.0, "conditions": {}}))


def test_the_overlay_holds_what_was_determined_and_loads_over_the_profile(tmp_path) -> None:
    _write(tmp_path, _measured(TRUE, 80.0, command=CHIRP), (1.0, 80.0))
    result = identify_actuator_fit(tmp_path, PROFILE, lockstep=True)
    overlay = yaml.safe_load(result.overlay_path.read_text())
    hydraulics = overlay["rig"]["actuator"]["hydraulics"]
    assert hydraulics["force_loop_bandwidth_hz"] == pytest.approx(23.0, rel=0.02)
    assert hydraulics["cylinder"]["valve_bandwidth_hz"] == pytest.approx(55.0, rel=0.02)
    assert hydraulics["cylinder"]["bulk_modulus_Pa"] == pytest.approx(1.3e9, rel=0.02)
    # tau = the actuator's transport delay + half the loop's 2 ms period
    assert overlay["rig"]["actuator"]["delay_s"] == pytest.approx(TRUE.delay_s - 0.001, abs=1e-4)
    identified = load_profile(overlay=result.overlay_path)
    assert identified.rig.actuator.hydraulics.force_loop_bandwidth_hz == pytest.approx(23.0, rel=0.02)
    record = json.loads(result.record_path.read_text())
    assert record["parameters"]["valve_bandwidth_hz"]["determined"] is True
    assert {e["condition"] for e in record["fit_error"]} == {"blocked", "free"}
    assert "valve_damping_ratio" in record["held"] and result.plot_path.is_file()


def test_a_band_below_half_the_valve_holds_the_delay_and_says_why(tmp_path) -> None:
    _write(tmp_path, _measured(TRUE, 30.0, command=CHIRP), (1.0, 30.0))
    result = identify_actuator_fit(tmp_path, PROFILE, lockstep=True)
    assert "delay_s" in result.held and "--band-hz" in result.held["delay_s"]
    overlay = yaml.safe_load(result.overlay_path.read_text())
    assert "delay_s" not in overlay["rig"]["actuator"]


def test_a_free_response_without_its_velocity_response_is_refused(tmp_path) -> None:
    measured = _measured(TRUE, 30.0)
    write_frf_csv(tmp_path / "frf.csv", measured.free)
    with pytest.raises(IdentificationError, match=VELOCITY_FILE):
        read_measured(tmp_path, 20.0)
    with pytest.raises(IdentificationError, match="no frf_blocked.csv or frf.csv"):
        read_measured(tmp_path / "nothing", 20.0)


def test_with_the_feedforward_the_free_condition_gives_the_velocity_feedback_left() -> None:
    # The profile believes full feed-forward; the rig's servo controller is set to 0.6 of it.
    shipped = load_profile().rig.actuator.hydraulics
    start = ActuatorParameters.from_config(shipped, 0.002, 0.001, sample_s=0.0005)
    true = dataclasses.replace(TRUE, feedforward_gain=0.6, feedforward_filter_hz=start.feedforward_filter_hz,
                               feedforward_delay_s=start.feedforward_delay_s)
    fit = fit_actuator(_measured(true, 80.0), start)
    assert "feedforward_gain" in fit.fitted
    found = fit.velocity_feedback()
    assert found is not None
    expected = true.velocity_feedback_Ns_per_m()  # 0.4 x 1.3 k_h / (2 pi 23 Hz)
    assert found[0] == pytest.approx(expected, rel=0.03)
    assert 0.0 < found[1] < 0.05 * expected
    # A fit that took the rig's feed-forward for the profile's would miss it by the whole difference.
    assert start.velocity_feedback_Ns_per_m() == 0.0


def test_an_empty_section_above_determined_values_does_not_say_nothing_was_determined() -> None:
    """Issue 30: identified.yaml said "rig.actuator: nothing determined" above the values determined in its sub-sections."""
    from harness.identification.outputs import OverlayValue, overlay_text

    text = overlay_text(["header"], {
        "rig.actuator": [], "rig.actuator.hydraulics": [OverlayValue("force_loop_bandwidth_hz", 23.0, "1 SE")],
        "rig.actuator.hydraulics.cylinder": [],
    })
    lines = text.splitlines()
    assert "nothing determined" not in lines[1]
    assert lines[1].startswith("# rig.actuator: none of its own keys determined") and "rig.actuator.hydraulics" in lines[1]
    assert lines[-1].startswith("# rig.actuator.hydraulics.cylinder: nothing determined")  # and nothing below it is
    assert yaml.safe_load(text) == {"rig": {"actuator": {"hydraulics": {"force_loop_bandwidth_hz": 23.0}}}}
