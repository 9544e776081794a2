"""The refusal of an unacknowledged weakening, and what metadata keeps of each (mutation survivors)."""

from __future__ import annotations

import dataclasses

import pytest

from harness.errors import ProfileError
from harness.safety.config import SafetyConfig
from harness.safety.weakening import FLAG, require_acknowledged, weakenings


def _weakened():
    own = SafetyConfig()
    used = dataclasses.replace(
        own,
        force=dataclasses.replace(own.force, max_force_N=own.force.max_force_N * 1.1),
        run=dataclasses.replace(own.run, max_stall_s=own.run.max_stall_s * 2),
    )
    return own, weakenings(own, used)


def test_each_weakening_keeps_its_direction_for_the_metadata() -> None:
    own, weakened = _weakened()
    assert [w.key for w in weakened] == ["safety.force.max_force_N", "safety.run.max_stall_s"]
    assert [w.as_dict()["direction"] for w in weakened] == ["larger", "larger"]
    assert weakened[0].as_dict() == {"key": "safety.force.max_force_N", "profile_value": own.force.max_force_N,
                                     "value": own.force.max_force_N * 1.1, "direction": "larger"}


def test_an_unacknowledged_weakening_is_refused_naming_the_file_and_every_key() -> None:
    _, weakened = _weakened()
    with pytest.raises(ProfileError) as refused:
        require_acknowledged(weakened, allowed=False, source="profiles/lab.yaml")
    listed = "; ".join(w.describe() for w in weakened)
    assert refused.value.source == "profiles/lab.yaml"
    assert str(refused.value) == (
        f"profiles/lab.yaml: --overlay/--set weaken the profile's safety settings (profile's value -> new value): {listed}; "
        f"expected the profile's values or stricter ones, or {FLAG} to run with them anyway (recorded in metadata.json)"
    )
    assert " -> " in listed and listed.count("; ") == 1
    require_acknowledged(weakened, allowed=True, source="profiles/lab.yaml")  # acknowledged: no refusal
    require_acknowledged((), allowed=False)  # nothing weakened: nothing to acknowledge
