"""Duplicate YAML keys are refused, in profile files and in --set values, with both lines named."""

from __future__ import annotations

import pytest
import yaml

from harness.config.yamlload import DuplicateKeyError, load_unique
from harness.errors import ProfileError
from harness.profile import load_profile, parse_overrides
from tests.conftest import PROFILES


def test_unique_keys_load_like_safe_load():
    text = "a: 1\nb: {c: [1, 2], d: x}\nbase: &b {x: 1, y: 2}\nmerged:\n  <<: *b\n  x: 3\n"
    assert load_unique(text) == yaml.safe_load(text)
    assert load_unique(text)["merged"] == {"x": 3, "y": 2}  # a merge key may be overridden: YAML intends it


@pytest.mark.parametrize(
    ("text", "key", "second", "first"),
    [
        ("a: 1\nb: 2\na: 3\n", "a", "line 3, column 1", "line 1, column 1"),
        ("top:\n  k: 1\n  j: 2\n  k: 3\n", "k", "line 4, column 3", "line 2, column 3"),
        ("items:\n  - {k: 1, k: 2}\n", "k", "line 2, column 12", "line 2, column 6"),
        ("{1: a, 1.0: b}\n", 1.0, "line 1, column 8", "line 1, column 2"),
    ],
)
def test_a_duplicate_key_names_both_lines(text, key, second, first):
    with pytest.raises(DuplicateKeyError) as info:
        load_unique(text)
    message = info.value.describe()
    assert f"duplicate key {key!r} at {second} (first at {first})" in message
    assert isinstance(info.value, yaml.YAMLError)


def test_a_second_safety_section_is_refused_not_merged(tmp_path):
    """The field report: the second section replaced the first and the stroke limits fell back to defaults."""
    text = (PROFILES / "nceer_4dof.yaml").read_text()
    first_line = text.splitlines().index("safety:") + 1
    path = tmp_path / "two_safety_sections.yaml"
    path.write_text(text + "\nsafety:\n  force:\n    max_force_N: 5000\n")
    second_line = len(text.splitlines()) + 2
    with pytest.raises(ProfileError) as info:
        load_profile(path)
    message = str(info.value)
    assert str(path) in message
    assert f"duplicate key 'safety' at line {second_line}, column 1 (first at line {first_line}, column 1)" in message


def test_a_duplicate_in_an_extended_profile_is_refused(tmp_path):
    child = tmp_path / "child.yaml"
    child.write_text(f"extends: {PROFILES / 'nceer_4dof.yaml'}\nname: a\nname: b\n")
    with pytest.raises(ProfileError, match=r"child.yaml: duplicate key 'name' at line 3"):
        load_profile(child)


def test_overriding_a_key_of_the_extended_profile_is_not_a_duplicate(tmp_path):
    child = tmp_path / "child.yaml"
    child.write_text(f"extends: {PROFILES / 'nceer_4dof.yaml'}\nname: mine\n")
    assert load_profile(child).name == "mine"


def test_a_duplicate_key_inside_a_set_value_is_refused():
    with pytest.raises(ProfileError, match=r"--set: .*in the value, duplicate key 'hard_limit_m' at line 1"):
        parse_overrides(["safety.stroke={hard_limit_m: 0.05, hard_limit_m: 0.02}"])


@pytest.mark.parametrize(
    "items",
    [
        ["safety.stroke.hard_limit_m=0.05", "safety.stroke.hard_limit_m=0.06"],
        ["safety.stroke.hard_limit_m=0.05", "safety.stroke={soft_limit_m: 0.03}"],
        ["safety.stroke={soft_limit_m: 0.03}", "safety.stroke.hard_limit_m=0.05"],
        ["safety.stroke.hard_limit_m=0.05", " safety.stroke.hard_limit_m =0.06"],
    ],
)
def test_the_same_key_set_twice_is_refused(items):
    with pytest.raises(ProfileError, match=r"--set: override .* sets safety.stroke.* again after"):
        parse_overrides(items)


def test_distinct_set_keys_still_combine():
    assert parse_overrides(["safety.stroke.hard_limit_m=0.05", "safety.stroke.soft_limit_m=0.03", "name=x"]) == {
        "safety": {"stroke": {"hard_limit_m": 0.05, "soft_limit_m": 0.03}},
        "name": "x",
    }
