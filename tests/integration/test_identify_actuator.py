"""``harness identify actuator`` end to end on the virtual rig, in lockstep (deterministic, no timing)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from harness import exit_codes
from harness.cli import main
from harness.identification.excitation import excitation_signal
from harness.identification.excitation_settings import Excitation
from harness.identification.frf import read_frf_csv
from harness.profile import load_profile
from harness.recording import load_run
from harness.runs.identify import IdentifyOptions, condition_profile, identify_actuator, run_condition
from harness.safety.checks import bit
from harness.safety.lifecycle import State

SHORT = ["--duration", "4", "--resolution-hz", "1", "--quiet"]


def _run_folders(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_dir() and (p / "metadata.json").is_file())


@pytest.mark.slow
def test_identify_actuator_measures_the_first_order_actuator_in_both_conditions(tmp_path, capsys):
    out = tmp_path / "frf"
    status = main(["identify", "actuator", "--out", str(out), "--both", "--variant", "force_source", *SHORT])
    printed = capsys.readouterr().out
    assert status == exit_codes.OK, printed
    assert printed.count("outcome: completed") == 2
    assert len(printed.strip().splitlines()) == 2  # --quiet: each condition's outcome line, nothing else
    for name in ("frf.csv", "frf_blocked.csv"):
        lines = (out / name).read_text().splitlines()
        assert lines[0] == "freq_hz,magnitude,phase_deg,coherence"
        response = read_frf_csv(out / name)
        assert response.freq_hz[0] >= 1.0 and response.freq_hz[-1] <= 30.0  # restricted to the band
        assert len(response.freq_hz) >= 25
        # The force-source variant: a 10 ms first-order lag (and the loop's delay) -> unit gain at low
        # frequency, about -3 dB near 16 Hz, a lag that grows with frequency.
        assert response.magnitude[0] == pytest.approx(1.0, abs=0.05)
        top = float(np.interp(30.0, response.freq_hz, response.magnitude))
        assert top == pytest.approx(1.0 / np.sqrt(1.0 + (2 * np.pi * 30.0 * 0.01) ** 2), rel=0.1)
        assert response.phase_deg[0] > -15.0 and response.phase_deg[-1] < -60.0
        assert np.all(np.diff(response.phase_deg) < 2.0)  # lag grows (to the estimate's noise)
        assert np.median(response.coherence) > 0.98
    assert (out / "frf.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    record = json.loads((out / "excitation.json").read_text())
    assert record["profile"] == "nceer_4dof" and record["harness_version"]
    assert record["excitation"]["signal"] == "chirp" and record["excitation"]["duration_s"] == 4.0
    assert set(record["conditions"]) == {"free", "blocked"}
    folders = _run_folders(out)
    assert len(folders) == 2
    for condition in ("free", "blocked"):
        folder = out / record["conditions"][condition]["run_folder"]
        metadata = json.loads((folder / "metadata.json").read_text())
        assert metadata["identification"]["condition"] == condition
        assert metadata["controller"] == "excitation (chirp)"
        pinned = (folder / "profile.yaml").read_text()
        assert f"base_pinned: {'true' if condition == 'blocked' else 'false'}" in pinned
        run = load_run(folder)
        running = run["state"].astype(int) == int(State.RUNNING)
        assert np.abs(run["force_command_N"][running]).max() == pytest.approx(2000.0, rel=0.01)
        assert np.abs(run["table_displacement_m"]).max() < 1e-3  # the table held still: no record played


def test_an_excitation_above_the_force_limit_is_refused_before_anything_runs(tmp_path, capsys):
    out = tmp_path / "frf"
    status = main(["identify", "actuator", "--out", str(out), "--amplitude-N", "12000", *SHORT])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert "--amplitude-N" in err and "max_force_N" in err
    assert not out.exists() or not _run_folders(out)
    status = main(["identify", "actuator", "--out", str(out), "--amplitude-N", "3000", "--band-hz", "1,30", *SHORT])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert "--amplitude-N" in err and "max_force_rate_N_per_s" in err
    assert not out.exists() or not _run_folders(out)


def test_the_excitation_goes_through_the_supervisor(tmp_path):
    """Past the command's own check (which refuses it), a force above the limit is still clamped by the supervisor."""
    # A plain force loop: its force stays below its command. With the servo controller's velocity feed-forward
    # the load cell can pass the clamped command by the feed-forward's lag (555 N measured here; reported in
    # issue 31's notes), which this test does not cover.
    profile = load_profile(None, overrides=["safety.force.max_force_N=500", "safety.force.tracking_tolerance_N=200",
                                            "rig.actuator.hydraulics.feedforward.gain=0",
                                            "safety.force.velocity_feedforward_gain=0"])
    excitation = Excitation("chirp", 1000.0, (1.0, 10.0), 3.0, resolution_hz=1.0)
    samples = excitation_signal(excitation, profile.control.rate_hz)
    options = IdentifyOptions(excitation, tmp_path, interface="virtual", channel=f"identify-{os.getpid()}", show_console=False)
    session = run_condition(profile, "free", options, samples, console=None, on_host_timing=None)
    assert session.outcome == "completed"
    run = load_run(session.run_path)
    assert np.abs(run["force_raw_N"]).max() == pytest.approx(1000.0, rel=0.01)  # the excitation as played
    assert np.abs(run["force_command_N"]).max() <= 500.0 + 1e-9  # as the supervisor let it through
    clamped = (run["interlock_flags"].astype(int) & bit("force_clamp")) != 0
    assert clamped.sum() > 100
    assert np.abs(run["force_measured_N"]).max() < 550.0  # the actuator got the clamped force (5 N load-cell noise)


def test_blocked_pins_the_base_mat_on_the_virtual_rig_only():
    profile = load_profile(None, overrides=["rig.base_pinned=true"])
    assert condition_profile(profile, "free", virtual_rig=True).rig.base_pinned is False
    assert condition_profile(profile, "blocked", virtual_rig=True).rig.base_pinned is True
    real = load_profile(None)
    assert condition_profile(real, "blocked", virtual_rig=False) is real  # the lab clamps it; the run records it


def test_on_a_real_rig_nothing_arms_without_the_operator(tmp_path):
    profile = load_profile(None)
    options = IdentifyOptions(Excitation(duration_s=4.0, resolution_hz=1.0), tmp_path, conditions=("free", "blocked"),
                              interface="socketcan", channel="can-not-opened", external_rig=True, show_console=False)
    asked = []
    result = identify_actuator(profile, options, confirm=lambda condition: asked.append(condition) or False)
    assert asked == ["free"] and result.declined == "free" and not result.conditions
    assert result.exit_code == exit_codes.INPUT_ERROR
    assert not _run_folders(tmp_path)


def test_both_conditions_on_a_real_rig_need_the_operator_between_them(tmp_path, capsys):
    status = main(["identify", "actuator", "--out", str(tmp_path), "--both", "--yes", "--interface", "socketcan",
                   "--channel", "can0", *SHORT])
    assert status == exit_codes.INPUT_ERROR
    assert "--both" in capsys.readouterr().err


@pytest.mark.parametrize("band", ["30,1", "1", "0,30", "a,b"])
def test_a_malformed_band_is_refused_naming_the_option(tmp_path, capsys, band):
    assert main(["identify", "actuator", "--out", str(tmp_path), "--band-hz", band]) == exit_codes.INPUT_ERROR
    assert "--band-hz" in capsys.readouterr().err


def test_identify_without_a_kind_shows_its_help(capsys):
    assert main(["identify"]) == exit_codes.INPUT_ERROR
    assert "actuator" in capsys.readouterr().out


def test_the_help_examples_parse():
    import shlex

    from harness.cli import build_parser
    from harness.commands.identify_actuator import EXAMPLES

    lines = [line.split("(")[0] for line in EXAMPLES.splitlines() if line.strip().startswith("harness identify")]
    assert len(lines) >= 3
    for line in lines:
        args = build_parser().parse_args(shlex.split(line)[1:])
        assert args.kind == "actuator" and args.out.startswith("frf")  # each its own DIR: a used one is refused


def test_rows_of_skipped_ticks_are_filled_in_on_the_tick_grid():
    from harness.runs.identify import on_tick_grid

    t = np.array([1.000, 1.002, 1.004, 1.010, 1.012])  # ticks at 1.006 and 1.008 missed (500 Hz)
    filled = on_tick_grid(t, 3.0 * t, 500.0)
    np.testing.assert_allclose(filled, 3.0 * np.arange(1.000, 1.0121, 0.002))
    every = np.arange(10) / 500.0
    np.testing.assert_array_equal(on_tick_grid(every, np.sin(every), 500.0), np.sin(every))


@pytest.mark.slow
def test_the_fit_recovers_an_actuator_whose_truth_is_hidden_from_the_harness(tmp_path, capsys):
    """The virtual rig's actuator has a bulk modulus 30 % above and a valve 30 % slower than the profile
    believes (rig.truth.actuator); the harness measures both conditions on the CAN path, in lockstep, with
    the rig's sensor noise and quantization, and fits SPEC 7a."""
    import yaml

    out = tmp_path / "frf"
    # A servo controller without velocity feed-forward: the whole velocity feedback k_h / w_f shows in the free
    # condition (with the shipped feed-forward it is near zero, and test_identify_reports_the_effective_velocity_
    # feedback_... covers it).
    hidden = ["--set", "rig.truth.actuator.bulk_modulus_Pa=1.3e9", "--set", "rig.truth.actuator.valve_bandwidth_hz=52.5",
              "--set", "rig.actuator.hydraulics.feedforward.gain=0", "--set", "safety.force.velocity_feedforward_gain=0"]
    status = main(["identify", "actuator", "--out", str(out), "--both", "--band-hz", "1,80", "--amplitude-N", "700",
                   "--duration", "20", "--quiet", "--allow-weaker-safety", *hidden])
    assert status == exit_codes.OK, capsys.readouterr().out
    overlay = yaml.safe_load((out / "identified.yaml").read_text())["rig"]["actuator"]
    assert overlay["hydraulics"]["cylinder"]["bulk_modulus_Pa"] == pytest.approx(1.3e9, rel=0.05)
    assert overlay["hydraulics"]["cylinder"]["valve_bandwidth_hz"] == pytest.approx(52.5, rel=0.05)
    assert overlay["hydraulics"]["force_loop_bandwidth_hz"] == pytest.approx(20.0, rel=0.05)  # the lab's tuning
    assert overlay["delay_s"] == pytest.approx(0.001, abs=2e-4)
    record = json.loads((out / "identification.json").read_text())
    assert {error["condition"] for error in record["fit_error"]} == {"blocked", "free"}
    assert len(record["runs"]) == 2 and (out / "actuator_fit.png").is_file()
    # The identified actuator against the true one over the excited band, within 5 % and 5 deg: its two
    # responses, command to force (blocked) and sliding velocity to force (the velocity feedback)
    from harness.identification.actuator_fit import (
        ActuatorParameters,
        blocked_response,
        velocity_feedback_response,
    )
    from harness.rig.truth import true_hydraulics

    profile = load_profile(overrides=hidden[1::2])
    truth = ActuatorParameters.from_config(true_hydraulics(profile.rig.actuator.hydraulics, profile.rig.truth.actuator),
                                           0.001 + 0.5 / profile.control.rate_hz, sample_s=profile.rig.physics_substep_s)
    fitted = record["parameters"]
    identified = ActuatorParameters(**{**truth.__dict__, **{k: v["value"] for k, v in fitted.items()}})
    freq = read_frf_csv(out / "frf_velocity.csv").freq_hz
    for model in (lambda p: blocked_response(p, freq), lambda p: velocity_feedback_response(p, freq)):
        ratio = model(identified) / model(truth)
        assert np.max(np.abs(np.abs(ratio) - 1)) <= 0.05
        assert np.max(np.abs(np.degrees(np.angle(ratio)))) <= 5.0


@pytest.mark.slow
def test_identify_reports_the_effective_velocity_feedback_of_a_rig_whose_feedforward_is_hidden(tmp_path, capsys):
    """The profile believes full feed-forward (alpha = 1, c_eff = 0); the rig's servo controller is set
    to half of it and its oil is 30 % stiffer (rig.truth.actuator): c_eff = 0.5 x 1.3 x 94 = 61 kN s/m.
    The free test recovers it within 15 %, with a standard error that covers the difference."""
    out = tmp_path / "frf"
    hidden = ["--set", "rig.truth.actuator.feedforward_gain=0.5", "--set", "rig.truth.actuator.bulk_modulus_Pa=1.3e9"]
    status = main(["identify", "actuator", "--out", str(out), "--both", "--band-hz", "1,80", "--amplitude-N", "700",
                   "--duration", "20", "--quiet", *hidden])
    assert status == exit_codes.OK, capsys.readouterr().out
    from harness.rig.truth import true_hydraulics

    profile = load_profile(overrides=hidden[1::2])
    true = true_hydraulics(profile.rig.actuator.hydraulics, profile.rig.truth.actuator)
    expected = true.velocity_feedback_Ns_per_m()
    assert expected == pytest.approx(0.5 * 1.3 * profile.rig.actuator.hydraulics.loop_damping_Ns_per_m(), rel=1e-6)
    found = json.loads((out / "identification.json").read_text())["velocity_feedback_Ns_per_m"]
    assert found["value"] == pytest.approx(expected, rel=0.15)
    assert 0.0 < found["standard_error"] < 0.15 * expected
    assert found["controller_damping_Ns_per_m"] == pytest.approx(profile.structure.base_mass_kg * 8.0)


@pytest.mark.slow
def test_the_shipped_actuators_default_chirp_states_intervals_that_hold_the_rigs_own_values(tmp_path, capsys):
    """Issue 33: the README's actuator step (1-30 Hz chirp at 2 kN, both conditions) on the shipped rig, whose
    values are the truth. Every fitted value's stated 95 % interval holds it: the force loop's bandwidth and the
    feed-forward gain were 3 % and 8 % off, 15 and 5 standard errors, before the fit took in the orifice's
    describing function and the servo controller's command rate limit (harness/identification/actuator_fit.py)."""
    from harness.identification.actuator import loop_delay_s
    from harness.identification.actuator_fit import ActuatorParameters
    from harness.identification.fit_statistics import interval_95
    from harness.rig.grid import half_up

    out = tmp_path / "frf"
    status = main(["identify", "actuator", "--out", str(out), "--both", "--duration", "20", "--quiet", "--yes",
                   "--set", "rig.seed=3"])
    assert status == exit_codes.OK, capsys.readouterr().out
    profile = load_profile()
    step_s = 1.0 / profile.control.rate_hz  # in lockstep the rig delays its sensors by whole steps
    truth = ActuatorParameters.from_config(
        profile.rig.actuator.hydraulics, profile.rig.actuator.delay_s + loop_delay_s(profile, lockstep=True),
        half_up(profile.rig.sensors.velocity.delay_s / step_s) * step_s, profile.rig.physics_substep_s,
    )
    fitted = {name: p for name, p in json.loads((out / "identification.json").read_text())["parameters"].items()
              if p["fitted"]}
    assert {"force_loop_bandwidth_hz", "valve_bandwidth_hz", "hydraulic_stiffness_N_per_m", "feedforward_gain"} <= set(fitted)
    for name, p in fitted.items():
        low, high = interval_95(p["value"], p["standard_error"])
        assert low <= getattr(truth, name) <= high, (name, p, getattr(truth, name))
