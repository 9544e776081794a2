"""The loop rate and the run length are checked against what arming, the stall budget and the record need.

Each bound is tested on both sides of its boundary and names the option (``--rate``,
``--duration``) or the profile key that set the value; --help states the same bounds.
"""

from __future__ import annotations

import argparse
import dataclasses

import pytest

from harness.cli import build_parser
from harness.commands.options import check_run_length
from harness.config.input_limits import MIN_RUN_SAMPLES
from harness.errors import ProfileError, RecordError
from harness.motions.config import SYNTHETIC_DT_S
from harness.motions.loading import load_motion
from harness.profile import load_profile
from harness.runs.loop_rate import check_loop_rate
from harness.runs.options import StudyOptions, resolve_profile
from tests.conftest import PROFILES

RIG = PROFILES / "nceer_4dof.yaml"
#: A rig whose stall budget and sensor age are long enough that the drive watchdog (50 ms) alone binds: 40 Hz.
WATCHDOG_BINDS = ["safety.run.max_stall_s=0.06", "safety.sensors.max_sensor_age_s=0.03", "safety.stroke.stop_time_s=0.1"]


def _at(rate_hz: float, overrides: tuple[str, ...] = (), profile_path=RIG):
    return resolve_profile(load_profile(profile_path, overrides=list(overrides)), StudyOptions(rate_hz=rate_hz))


@pytest.mark.parametrize("path", sorted(PROFILES.glob("*.yaml")), ids=lambda p: p.stem)
def test_the_shipped_profiles_arm_from_100_hz_as_help_says(path):
    """--help says 100 Hz for the shipped profiles: 2 periods in their 20 ms stall budget."""
    check_loop_rate(_at(100.0, profile_path=path), True, virtual_rig=False)
    with pytest.raises(ProfileError, match=r"--rate: found 99.9 Hz .* expected at least 100 Hz: 2 periods must fit in "
                                           r"safety.run.max_stall_s \(20 ms"):
        check_loop_rate(_at(99.9, profile_path=path), True, virtual_rig=False)


@pytest.mark.parametrize("rate_hz", [10.0, 0.001])
def test_the_review_rates_are_refused_naming_both_bounds(rate_hz):
    """--rate 10 (real time) and 0.001 (lockstep) ended in 'could not arm ... drive fault=True' with a run folder."""
    with pytest.raises(ProfileError) as info:
        check_loop_rate(_at(rate_hz), True, virtual_rig=True)
    message = str(info.value)
    assert message.startswith(f"--rate: found {rate_hz:g} Hz")
    assert "safety.run.max_stall_s" in message and "rig.drive.watchdog_timeout_s (50 ms" in message
    assert "lockstep too" in message


def test_the_drive_watchdog_binds_when_the_stall_budget_allows_slower():
    check_loop_rate(_at(40.0, WATCHDOG_BINDS), True, virtual_rig=False)  # 2 x 25 ms = the 50 ms watchdog
    with pytest.raises(ProfileError) as info:
        check_loop_rate(_at(38.0, WATCHDOG_BINDS), True, virtual_rig=False)
    message = str(info.value)
    assert "expected at least 40 Hz" in message and "rig.drive.watchdog_timeout_s" in message
    assert "safety.run.max_stall_s" not in message  # 2 x 26.3 ms fits its 60 ms


def test_sensor_frames_slower_than_the_sensor_age_are_refused_at_their_key():
    profile = load_profile(RIG, overrides=["can.sensor_rate_hz=40"])  # 25 ms apart, against a 20 ms age limit
    with pytest.raises(ProfileError, match=r"nceer_4dof.yaml: can.sensor_rate_hz: found sensor frames every 25 ms .*"
                                           r"expected at least 50 Hz"):
        check_loop_rate(profile, False, virtual_rig=False)


def test_the_profile_key_is_named_when_the_rate_came_from_the_profile():
    profile = load_profile(RIG, overrides=["control.rate_hz=50"])
    with pytest.raises(ProfileError, match=r"nceer_4dof.yaml: control.rate_hz: found 50 Hz"):
        check_loop_rate(profile, False, virtual_rig=False)


def test_a_dry_run_needs_whole_physics_substeps_per_period():
    check_loop_rate(_at(300.0), True, virtual_rig=False)  # a real rig has no sub-steps
    with pytest.raises(ProfileError, match=r"--rate: found 300 Hz: its period of 3.33333 ms is not a whole number of the "
                                           r"virtual rig's physics sub-steps .*such as 333.333 Hz or 285.714 Hz"):
        check_loop_rate(_at(300.0), True, virtual_rig=True)
    check_loop_rate(_at(250.0), True, virtual_rig=True)


def test_a_run_shorter_than_ten_periods_is_refused_naming_where_the_length_came_from():
    profile = load_profile(RIG)
    shortest_s = MIN_RUN_SAMPLES / profile.control.rate_hz
    check_run_length(profile, argparse.Namespace(duration=shortest_s, rate=None))
    with pytest.raises(ProfileError, match=r"^--duration: found 1e-09 s, expected at least 0.02 s: 10 periods"):
        check_run_length(profile, argparse.Namespace(duration=1e-9, rate=None))
    with pytest.raises(ProfileError, match=r"--duration: found 5 s, expected at least 10 s: 10 periods of the 1 Hz"):
        check_run_length(profile, argparse.Namespace(duration=5.0, rate=1.0))
    short = dataclasses.replace(profile, record=dataclasses.replace(profile.record, duration_s=0.01))
    with pytest.raises(ProfileError, match=r"nceer_4dof.yaml: record.duration_s: found 0.01 s"):
        check_run_length(short, argparse.Namespace())


def test_a_run_shorter_than_ten_samples_of_the_record_is_refused_naming_the_option():
    """--duration 1e-9 reported 'synthetic record: expected duration_s >= 0.1 s', a length nobody typed."""
    record = load_profile(RIG).record  # the synthetic record at time scale 2: 5 ms samples
    shortest_s = MIN_RUN_SAMPLES * SYNTHETIC_DT_S / record.time_scale
    assert load_motion(dataclasses.replace(record, duration_s=shortest_s), base_dir=PROFILES).duration_s == \
        pytest.approx(shortest_s)
    with pytest.raises(RecordError) as info:
        load_motion(dataclasses.replace(record, duration_s=shortest_s * 0.9), base_dir=PROFILES)
    assert str(info.value) == (
        "record 'synthetic': found a run length (--duration or record.duration_s) of 0.045 s, expected at least "
        "0.05 s: 10 samples of the record, 0.005 s each after the time scale of 2"
    )


def _help(command: str) -> str:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices[command]
    return " ".join(sub.format_help().split())


@pytest.mark.parametrize("command", ["dry-run", "run"])
def test_help_states_the_rate_and_duration_bounds(command):
    text = _help(command)
    assert "in (0, 5000]; and at least 2 / safety.run.max_stall_s, 2 / rig.drive.watchdog_timeout_s and " \
           "1 / safety.sensors.max_sensor_age_s (100 Hz for the shipped profiles), in lockstep too" in text
    assert "in (0, 600]; and at least 10 samples of the record and 10 periods of the control rate" in text
    assert ("a whole number of rig.physics_substep_s per period" in text) == (command == "dry-run")


def _nothing_may_start(*args, **kwargs):
    raise AssertionError("the loop-rate check must refuse before anything starts")


def test_a_dry_run_called_directly_is_refused_a_bad_rate_before_anything_starts(tmp_path, monkeypatch):
    """Issue 35: the check lived in the command line only; harness/runs/dry_run.py called directly skipped it."""
    import harness.runs.dry_run as dry_run_module
    from harness.runs.dry_run import DryRunOptions

    monkeypatch.setattr(dry_run_module, "serving_virtual_rig", _nothing_may_start)
    monkeypatch.setattr(dry_run_module, "run_session", _nothing_may_start)
    options = DryRunOptions(study=StudyOptions(rate_hz=10.0, duration_s=1.0), lockstep=True, show_console=False,
                            compare=False, log_dir=str(tmp_path))
    with pytest.raises(ProfileError, match=r"--rate: found 10 Hz .* expected at least 100 Hz"):
        dry_run_module.dry_run(load_profile(RIG), options)
    assert not any(tmp_path.iterdir())  # no run folder


def test_an_identification_called_directly_is_refused_a_bad_rate_before_anything_starts(tmp_path, monkeypatch):
    """harness/runs/identify.py goes through the session and the virtual rig, which check the rate whoever calls."""
    import harness.runs.dry_run as dry_run_module
    from harness.identification.excitation_settings import Excitation
    from harness.runs.identify import IdentifyOptions, identify_actuator

    monkeypatch.setattr(dry_run_module, "_rig_process", _nothing_may_start)
    profile = load_profile(RIG, overrides=["control.rate_hz=50"])
    options = IdentifyOptions(Excitation("chirp", 1000.0, (1.0, 10.0), 4.0, resolution_hz=1.0), tmp_path / "id", lockstep=True,
                              show_console=False)
    with pytest.raises(ProfileError, match=r"control.rate_hz.*found 50 Hz .* expected at least 100 Hz"):
        identify_actuator(profile, options)


def test_the_virtual_rig_refuses_a_period_of_part_sub_steps_whoever_starts_it():
    from harness.runs.dry_run import serving_virtual_rig

    profile = _at(300.0)  # 3.33 ms: not whole 0.5 ms sub-steps (the shipped rig's)
    with pytest.raises(ProfileError, match=r"not a whole number of the virtual rig's physics sub-steps"):
        with serving_virtual_rig(profile, profile.can_settings(None, None), True, None):  # type: ignore[arg-type]
            pass
