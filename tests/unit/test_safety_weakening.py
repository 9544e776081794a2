"""Weakening a profile's safety settings from the command line, and limits the protocol cannot carry."""

from __future__ import annotations

import dataclasses
import re
import types
import typing

import pytest
from rich.console import Console

from harness.console.live import LiveConsole, view_command
from harness.errors import ProfileError
from harness.loop.status import LoopStatus
from harness.profile import command_force_limit_N, load_profile
from harness.safety.config import SafetyConfig
from harness.safety.weakening import (
    DIRECTIONS,
    FLAG,
    Weakening,
    is_weaker,
    require_acknowledged,
    safety_fields,
    summary,
    weakenings,
)
from tests.conftest import PROFILES, REPO

RIG = PROFILES / "nceer_4dof.yaml"
#: nceer_4dof sits at the edge of its stall budget (20 + 20 ms <= 50 - 10 ms): a shorter look-ahead
#: stays consistent only with a smaller stall budget and sensor age, both stricter.
CONSISTENT_SHORT_LOOK_AHEAD = [
    "safety.stroke.stop_time_s=0.02", "safety.run.max_stall_s=0.004", "safety.sensors.max_sensor_age_s=0.006",
]


def test_every_safety_field_has_a_direction():
    fields = safety_fields()
    assert set(DIRECTIONS) == set(fields), "give each new safety field a direction in harness/safety/weakening.py"
    hints = {name: typing.get_type_hints(kind) for name, kind in typing.get_type_hints(SafetyConfig).items()}
    for name, direction in DIRECTIONS.items():
        section, field = name.split(".")
        kind = hints[section][field]
        if typing.get_origin(kind) in (typing.Union, types.UnionType):  # optional: X | None
            kind = next(arg for arg in typing.get_args(kind) if arg is not type(None))
        if typing.get_origin(kind) is typing.Literal:
            assert direction == "milder", name
        elif typing.get_origin(kind) is tuple:
            assert direction == "fewer", name
        elif kind is bool:
            assert direction == "off", name
        else:
            assert direction in ("larger", "smaller"), name


def test_the_doc_gives_every_field_its_direction():
    text = (REPO / "docs" / "SAFETY.md").read_text()
    documented: dict[str, str] = {}
    for line in text.splitlines():
        found = re.match(r"\| `(larger|smaller|milder|fewer|off)` \| ([^|]+) \|", line)
        if found:
            for name in re.findall(r"`([a-z_]+\.[A-Za-z0-9_]+)`", found.group(2)):
                documented[name] = found.group(1)
    assert documented == DIRECTIONS


@pytest.mark.parametrize(("direction", "old", "new", "weaker"), [
    ("larger", 0.1, 0.2, True), ("larger", 0.2, 0.1, False), ("larger", 0.1, 0.1, False),
    ("larger", 1000.0, None, True), ("larger", None, 1000.0, False),
    ("smaller", 0.05, 0.02, True), ("smaller", 0.05, 0.06, False),
    ("milder", "trip", "safe_stop", True), ("milder", "safe_stop", "indicate", True), ("milder", "indicate", "trip", False),
    ("fewer", ("disable", "estop"), ("disable",), True), ("fewer", ("disable",), ("estop", "disable"), False),
    ("fewer", ("disable", "estop"), ("estop", "disable"), False),
    ("off", True, False, True), ("off", False, True, False),
])
def test_each_direction(direction, old, new, weaker):
    assert is_weaker(direction, old, new) is weaker


def test_weaker_and_stricter_changes_are_told_apart():
    own = SafetyConfig()
    used = dataclasses.replace(
        own, stroke=dataclasses.replace(own.stroke, hard_limit_m=0.05, stop_time_s=0.2),
        comms=dataclasses.replace(own.comms, error_frame_action="indicate", e2e_window_s=0.5),
    )
    found = {item.key: (item.profile_value, item.value) for item in weakenings(own, used)}
    assert found == {"safety.comms.error_frame_action": ("safe_stop", "indicate"), "safety.comms.e2e_window_s": (1.0, 0.5)}


def test_a_shorter_look_ahead_is_listed_and_refused_without_the_flag():
    profile = load_profile(RIG, overrides=CONSISTENT_SHORT_LOOK_AHEAD)
    assert [item.describe() for item in profile.safety_weakened] == ["safety.stroke.stop_time_s 0.05 -> 0.02"]
    with pytest.raises(ProfileError, match=r"safety.stroke.stop_time_s 0.05 -> 0.02.*--allow-weaker-safety"):
        require_acknowledged(profile.safety_weakened, False, profile.source_path)
    require_acknowledged(profile.safety_weakened, True, profile.source_path)


def test_stricter_settings_need_no_flag():
    profile = load_profile(RIG, overrides=["safety.stroke.hard_limit_m=0.09", "safety.stroke.fade_band_m=0.01"])
    assert profile.safety.stroke.hard_limit_m == 0.09 and profile.safety_weakened == ()


def test_a_variant_or_an_extending_file_is_the_profiles_own_choice(tmp_path):
    child = tmp_path / "loose.yaml"
    child.write_text(
        f"extends: {RIG}\nsafety:\n  stroke: {{arm_tolerance_m: 0.007}}\n"
        "variants:\n  looser: {safety: {stroke: {arm_tolerance_m: 0.008}, comms: {error_frame_action: indicate}}}\n"
    )
    assert load_profile(child).safety_weakened == ()
    assert load_profile(child, variant="looser").safety_weakened == ()
    assert load_profile(child, variant="looser", overrides=["safety.stroke.arm_tolerance_m=0.008"]).safety_weakened == ()
    (item,) = load_profile(child, variant="looser", overrides=["safety.stroke.arm_tolerance_m=0.009"]).safety_weakened
    assert (item.key, item.profile_value, item.value) == ("safety.stroke.arm_tolerance_m", 0.008, 0.009)
    (item,) = load_profile(child, overrides=["safety.stroke.arm_tolerance_m=0.008"]).safety_weakened
    assert item.profile_value == 0.007


#: A load-cell limit and a supply force above a raised max_force_N, so that the check under test speaks first.
ROOMY_FORCE = ("safety.force.load_cell_limit_N=60000", "safety.force.supply_force_N=60000")


def test_max_force_beyond_the_dbc_is_refused_at_load():
    assert command_force_limit_N("") == 30_000.0
    with pytest.raises(ProfileError, match=r"safety.force.max_force_N: found 40000 N, expected at most 30000 N.*ACTUATOR_CMD"):
        load_profile(RIG, overrides=["safety.force.max_force_N=40000", *ROOMY_FORCE])


def test_the_protocol_limit_is_read_from_the_dbc(tmp_path):
    dbc = tmp_path / "narrow.dbc"
    text = (REPO / "drivers" / "protocol" / "rig.dbc").read_text()
    dbc.write_text(text.replace('SG_ force : 16|16@1- (1,0) [-30000|30000] "N"', 'SG_ force : 16|16@1- (1,0) [-20000|20000] "N"'))
    overrides = [f"can.dbc_path={dbc}", "rig.actuator.force_limit_N=30000", "safety.force.max_force_N=25000", *ROOMY_FORCE]
    expected = r"expected at most 20000 N \(the range of the ACTUATOR_CMD force signal of .*narrow.dbc"
    with pytest.raises(ProfileError, match=expected):
        load_profile(RIG, overrides=overrides)


def test_max_force_beyond_an_actuator_rating_is_refused():
    with pytest.raises(ProfileError, match=r"found 15000 N, expected at most 12000 N \(rig.actuator.force_limit_N"):
        load_profile(RIG, overrides=["safety.force.max_force_N=15000", *ROOMY_FORCE])
    with pytest.raises(ProfileError, match=r"found 10000 N, expected at most 8000 N \(safety.force.actuator_rating_N"):
        load_profile(RIG, overrides=["safety.force.actuator_rating_N=8000"])
    assert load_profile(RIG, overrides=["safety.force.actuator_rating_N=11000"]).safety_weakened == ()


def test_the_panel_and_the_childs_command_carry_the_warning():
    line = "safety weakened (--allow-weaker-safety): safety.stroke.stop_time_s 0.05 -> 0.02"
    with LoopStatus(state="RUNNING", duration_s=1.0) as status:
        console = Console(record=True, width=160)
        console.print(LiveConsole(status, 0.08, 0.1, 10_000.0, "title", enabled=False, alerts=(line,)))
        assert line in console.export_text()
        command = view_command(status.path, 0.08, 0.1, 10_000.0, "title", parent_pid=1, alerts=(line,))
    assert f"--alert={line}" in command
    assert FLAG in line


def test_each_kind_of_value_is_described_and_recorded_as_plain_data():
    items = (
        Weakening("safety.stroke.stop_time_s", 0.05, 0.02, "smaller"),
        Weakening("safety.trip_actions.stroke", ("disable", "estop"), ("disable",), "fewer"),
        Weakening("safety.force.actuator_rating_N", 12_000.0, None, "larger"),
        Weakening("safety.estop.panel_required", True, False, "off"),
        Weakening("safety.sensors.stuck_samples", 50, 80, "larger"),
    )
    assert [item.describe() for item in items] == [
        "safety.stroke.stop_time_s 0.05 -> 0.02",
        "safety.trip_actions.stroke [disable, estop] -> [disable]",
        "safety.force.actuator_rating_N 12000 -> null",
        "safety.estop.panel_required True -> False",
        "safety.sensors.stuck_samples 50 -> 80",
    ]
    assert items[1].as_dict() == {"key": "safety.trip_actions.stroke", "profile_value": ["disable", "estop"],
                                  "value": ["disable"], "direction": "fewer"}
    assert items[2].as_dict()["value"] is None
    assert summary(items[:2]) == (
        "safety weakened (--allow-weaker-safety): safety.stroke.stop_time_s 0.05 -> 0.02; "
        "safety.trip_actions.stroke [disable, estop] -> [disable]"
    )
