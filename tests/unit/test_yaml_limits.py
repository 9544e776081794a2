"""YAML too long, too deep or too large once its aliases expand is refused with the limit named; values are quoted bounded.

Every check here counts (values, levels, calls of ``__repr__``) instead of timing: the
alias bomb of the review took 66 s and 3.2 GB, and a regression shows as a count far above
the bound, not as a slow test.
"""

from __future__ import annotations

import pytest
import yaml

from harness.config.schema import DESCRIBE_CHARS, _describe
from harness.config.yamlload import (
    MAX_DEPTH,
    MAX_VALUES,
    MAX_YAML_CHARS,
    UniqueKeyLoader,
    YamlLimitError,
    check_expansion,
    load_unique,
)
from harness.errors import ProfileError
from harness.profile import load_profile, parse_overrides
from harness.sweep.study import load_study
from tests.conftest import PROFILES


def _bomb(levels: int = 9, width: int = 9) -> str:
    """The billion laughs: ``levels`` anchors, each a list of ``width`` aliases of the one before."""
    lines = [f"l0: &l0 [{', '.join(['lol'] * width)}]"]
    lines += [f"l{i}: &l{i} [{', '.join([f'*l{i - 1}'] * width)}]" for i in range(1, levels)]
    return "\n".join(lines) + "\n"


def _compose(text: str) -> yaml.Node:
    """The root node as PyYAML composes it, without this module's checks."""
    return yaml.compose(text, Loader=yaml.SafeLoader)


def _nested(depth: int) -> str:
    return "[" * depth + "1" + "]" * depth


def _nested_levels(levels: int) -> str:
    """A scalar inside lists: ``levels`` levels deep, the scalar included."""
    return _nested(levels - 1)


def test_nesting_up_to_the_limit_loads_and_one_level_more_is_refused():
    assert load_unique(_nested_levels(MAX_DEPTH)) is not None
    with pytest.raises(YamlLimitError) as info:
        load_unique(_nested_levels(MAX_DEPTH + 1))
    assert f"nested deeper than {MAX_DEPTH} levels" in info.value.problem and "MAX_DEPTH" in info.value.problem


def test_500_nested_brackets_are_refused_not_a_recursion_error():
    """The review's input: a 1 kB file of 500 '[' overflowed the stack while it was composed."""
    with pytest.raises(YamlLimitError) as info:
        load_unique(_nested(500))
    assert info.value.problem_mark.column == MAX_DEPTH  # where the first level too many opens (0-based)


def test_aliases_cannot_nest_deeper_than_the_text_does():
    """An anchor 21 levels tall used 22 levels down: 42 once expanded, though neither line nests more than 22."""
    text = f"a: &a {_nested(20)}\nb: &b {'[' * 20}*a{']' * 20}\n"
    with pytest.raises(YamlLimitError, match=r"nested 42 levels deep once the aliases are expanded; expected at most 32"):
        load_unique(text)


def test_expanded_values_are_counted_exactly_without_expanding():
    """A list of 3 strings named 4 times: each alias counts the whole list it names."""
    text = "base: &b [x, y, z]\nuses: [*b, *b, *b, *b]\n"
    values, depth = check_expansion(_compose(text))
    # root mapping 1, keys 2, the anchored list 1 + 3, the list of uses 1 + 4 * (1 + 3)
    assert (values, depth) == (1 + 2 + 4 + 1 + 16, 4)  # root, list of uses, aliased list, string
    assert load_unique(text)["uses"] == [["x", "y", "z"]] * 4


def test_the_billion_laughs_are_refused_before_anything_is_built(monkeypatch):
    text = _bomb()
    assert len(text) < 1000
    built = []
    monkeypatch.setattr(UniqueKeyLoader, "construct_document", lambda self, node: built.append(node))
    with pytest.raises(YamlLimitError) as info:
        load_unique(text)
    assert built == []  # refused on the node graph: no Python object of it was made
    assert f"more than {MAX_VALUES} values once its aliases" in info.value.problem and "MAX_VALUES" in info.value.problem


def test_a_smaller_alias_tree_within_the_limit_loads():
    text = _bomb(levels=4, width=9)
    sizes = [1 + 9]  # l0: a list of 9 strings
    for _ in range(3):
        sizes.append(1 + 9 * sizes[-1])  # l1..l3: a list of 9 copies of the one before
    values, depth = check_expansion(_compose(text))
    assert (values, depth) == (1 + 4 + sum(sizes), 2 + 4)  # the root and its 4 keys, then each anchored list once
    assert values < MAX_VALUES
    assert len(load_unique(text)["l3"]) == 9


def test_a_recursive_anchor_is_refused():
    with pytest.raises(YamlLimitError, match="recursive anchor"):
        load_unique("a: &a [1, *a]\n")


def test_a_text_longer_than_the_limit_is_refused():
    with pytest.raises(YamlLimitError, match=f"{MAX_YAML_CHARS + 1} characters long; expected at most {MAX_YAML_CHARS}"):
        load_unique("#" * (MAX_YAML_CHARS + 1))


@pytest.mark.parametrize("path", sorted(PROFILES.glob("*.yaml")) + sorted((PROFILES / "studies").glob("*.yaml")),
                         ids=lambda p: p.name)
def test_the_shipped_files_are_far_inside_the_limits(path):
    """The docstrings' claims: 5-7 levels and a few hundred values, a quarter of the depth and 1 % of the values;
    the largest shipped file (the rig profile, with its derivations) is at most 5 % of the size limit."""
    values, depth = check_expansion(_compose(path.read_text()))
    assert depth <= MAX_DEPTH // 4 and values <= MAX_VALUES // 100
    assert path.stat().st_size <= MAX_YAML_CHARS // 20


def test_a_profile_a_set_value_and_a_study_all_name_the_limit(tmp_path):
    """The three ways YAML comes in share one loader and report the limit with the file or --set."""
    profile = tmp_path / "deep.yaml"
    profile.write_text(f"name: {_nested(500)}\n")
    with pytest.raises(ProfileError, match=r"deep.yaml: invalid YAML at line 1, column \d+: .*MAX_DEPTH"):
        load_profile(profile)
    with pytest.raises(ProfileError, match=r"--set: .*not valid YAML \(.*MAX_DEPTH"):
        parse_overrides([f"name={_nested(500)}"])
    study = tmp_path / "bomb_study.yaml"
    study.write_text(_bomb() + f"name: *l8\nprofile: {PROFILES / 'nceer_4dof.yaml'}\n")
    with pytest.raises(ProfileError, match=r"bomb_study.yaml: invalid YAML at line \d+, column \d+: .*MAX_VALUES"):
        load_study(study)


class CountedRepr:
    """A leaf whose ``repr`` counts its calls."""

    calls = 0

    def __repr__(self) -> str:
        CountedRepr.calls += 1
        return "leaf"


def test_a_value_is_quoted_without_building_its_whole_repr():
    """The field report: the message built the repr of a billion strings to show 60 characters of it."""
    value: object = [CountedRepr()] * 9
    for _ in range(5):
        value = [value] * 9  # 9^6 leaves by reference, as YAML aliases build them (a full repr: half a million calls)
    CountedRepr.calls = 0
    text = _describe(value)
    assert len(text) <= DESCRIBE_CHARS and text.startswith("[[[")
    assert CountedRepr.calls == 0  # three levels are shown, and the leaves lie six deep
    shallow = [[CountedRepr()] * 300] * 300
    _describe(shallow)
    assert CountedRepr.calls <= 4 * 4  # at most 4 items of each of the lists shown


@pytest.mark.parametrize(
    ("value", "text"),
    [("abc", "'abc'"), (3.5, "3.5"), (None, "None"), (True, "True"), ([1, 2, 3], "[1, 2, 3]"), ({"a": 1}, "{'a': 1}")],
)
def test_short_values_are_quoted_as_repr_quotes_them(value, text):
    assert _describe(value) == text


def test_a_long_string_is_cut_to_the_quotation_length():
    text = _describe("x" * 10_000)
    assert len(text) <= DESCRIBE_CHARS and text.startswith("'xxx") and "..." in text
