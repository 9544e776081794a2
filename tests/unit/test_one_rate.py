"""Issue 35, item 4: the loop rate has one source, ``control.rate_hz``, and every other rate derives from it.

Before, ``--rate`` wrote ``control.rate_hz``, ``loop.rate_hz``, ``can.command_rate_hz`` and
``can.sensor_rate_hz``, and the profile refused copies that disagreed.
"""

from __future__ import annotations

import dataclasses

import pytest

from harness.canbus.config import CanConfig
from harness.errors import ProfileError
from harness.loop.config import LoopConfig
from harness.paths import PROFILE_DIR
from harness.profile import Profile, load_profile
from harness.runs.options import StudyOptions, resolve_profile

RIG = PROFILE_DIR / "nceer_4dof.yaml"
EIGHT = PROFILE_DIR / "eight_story.yaml"


@pytest.mark.parametrize("path", [RIG, EIGHT])
def test_the_command_and_sensor_rates_are_the_loops_rate(path):
    profile = load_profile(path)
    assert profile.can.loop_rate_hz == profile.control.rate_hz
    assert profile.can.command_rate_hz == profile.control.rate_hz
    assert profile.can.sensor_rate_hz is None, "the shipped profiles send their sensors once per tick"
    assert profile.can.sensor_frame_rate_hz == profile.control.rate_hz
    rates = profile.can.rates_hz()
    assert rates["ACTUATOR_CMD"] == profile.control.rate_hz
    assert rates["TABLE_SENSORS"] == rates["BASE_SENSORS"] == profile.control.rate_hz


def test_rate_moves_every_rate_that_follows_it():
    profile = resolve_profile(load_profile(RIG), StudyOptions(rate_hz=1000.0))
    assert profile.control.rate_hz == 1000.0
    assert profile.can.command_rate_hz == 1000.0
    assert profile.can.sensor_frame_rate_hz == 1000.0
    assert profile.can_settings("socketcan", "vcan0").command_rate_hz == 1000.0


def test_a_replace_of_the_control_section_reaches_the_can_section():
    profile = load_profile(RIG)
    faster = dataclasses.replace(profile, control=dataclasses.replace(profile.control, rate_hz=2000.0))
    assert faster.can.command_rate_hz == 2000.0
    assert faster.can.sensor_frame_rate_hz == 2000.0


def test_a_sensor_rate_of_its_own_stays_when_the_loop_rate_changes():
    profile = resolve_profile(load_profile(RIG, overrides=["can.sensor_rate_hz=250"]), StudyOptions(rate_hz=1000.0))
    assert profile.can.command_rate_hz == 1000.0
    assert profile.can.sensor_frame_rate_hz == 250.0


@pytest.mark.parametrize("key", ["loop.rate_hz", "can.command_rate_hz"])
def test_a_former_copy_of_the_rate_is_refused_saying_where_the_rate_is(key):
    with pytest.raises(ProfileError, match=rf"{key}: {key} is no longer a key: the profile has one rate, control.rate_hz"):
        load_profile(RIG, overrides=[f"{key}=500"])


def test_the_loop_and_can_sections_have_no_rate_of_the_loop_to_set():
    assert "rate_hz" not in {field.name for field in dataclasses.fields(LoopConfig)}
    settable = {field.name for field in dataclasses.fields(CanConfig) if not field.metadata.get("internal")}
    assert "command_rate_hz" not in settable and "loop_rate_hz" not in settable
    with pytest.raises(ProfileError, match=r"unknown key 'loop_rate_hz'"):
        load_profile(RIG, overrides=["can.loop_rate_hz=1000"])


def _recorded_before_one_rate(rate_hz: float = 500.0, sensor_rate_hz: float = 500.0) -> dict:
    """A run folder's resolved profile as the harness wrote it when the rate had copies."""
    data = load_profile(RIG).resolved_data()
    data["loop"]["rate_hz"] = rate_hz
    data["can"]["command_rate_hz"] = rate_hz
    data["can"]["sensor_rate_hz"] = sensor_rate_hz
    return data


def test_a_run_recorded_with_the_copies_still_loads_for_replay():
    profile = Profile.from_resolved(_recorded_before_one_rate())
    assert profile.control.rate_hz == 500.0
    assert profile.can.sensor_rate_hz is None
    assert profile.can.command_rate_hz == 500.0


def test_a_recorded_sensor_rate_of_its_own_is_kept():
    profile = Profile.from_resolved(_recorded_before_one_rate(sensor_rate_hz=250.0))
    assert profile.can.sensor_rate_hz == 250.0


def test_a_recorded_copy_that_disagrees_is_refused():
    with pytest.raises(ProfileError, match=r"loop.rate_hz: found 1000.0 Hz, expected control.rate_hz \(500.0 Hz\)"):
        Profile.from_resolved(_recorded_before_one_rate(rate_hz=1000.0))


def test_the_resolved_profile_round_trips_without_the_copies():
    profile = resolve_profile(load_profile(RIG), StudyOptions(rate_hz=1000.0))
    data = profile.resolved_data()
    assert "rate_hz" not in data["loop"]
    assert "command_rate_hz" not in data["can"] and "loop_rate_hz" not in data["can"]
    again = Profile.from_resolved(data)
    assert again.can == profile.can
    assert again.control.rate_hz == 1000.0
