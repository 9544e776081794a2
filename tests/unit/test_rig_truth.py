"""``rig.truth``: the virtual rig's own building and bearing, separate from the design (harness/rig/truth.py).

What each test would catch: an override section that no longer mirrors its design section,
a ``--set`` form that does not parse or land, a bad override accepted or refused without
naming its key, a merge that loses derived quantities (carried weight, damping), the rig
built on the design instead of the truth, and the notes (metadata, console, report) saying
something when nothing differs or nothing when something does.
"""

from __future__ import annotations

import dataclasses
import io
import typing
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

from harness.console.live import LiveConsole, view_command
from harness.errors import ProfileError
from harness.loop.status import LoopStatus
from harness.model.bearing import MU_MAX, WEIGHT, BearingConfig
from harness.model.building import BuildingConfig, fixed_base_modes
from harness.profile import load_profile
from harness.recording.reader import RunData
from harness.report.build import truth_note
from harness.rig.parts import RigParts
from harness.rig.truth import (
    METADATA_KEY,
    BearingTruth,
    StructureTruth,
    truth_metadata,
    truth_summary,
)
from tests.conftest import PROFILES

RIG = PROFILES / "nceer_4dof.yaml"
MU_SET = "rig.truth.bearing.mu_max=0.075"
STIFFNESS_SET = "rig.truth.structure.story_stiffness_N_per_m=[0.6e6,2.1e6,1.5e6]"


def _load(*overrides: str):
    return load_profile(RIG, overrides=list(overrides))


def _refusal(*overrides: str) -> ProfileError:
    with pytest.raises(ProfileError) as caught:
        _load(*overrides)
    return caught.value


# --- the section's shape ---------------------------------------------------------------------


@pytest.mark.parametrize(("override", "design"), [(StructureTruth, BuildingConfig), (BearingTruth, BearingConfig)])
def test_each_override_section_has_every_design_field_optional_with_its_unit_and_range(override, design):
    design_fields = {f.name: f for f in dataclasses.fields(design)}
    override_fields = {f.name: f for f in dataclasses.fields(override)}
    assert list(override_fields) == list(design_fields)  # a field added to the design needs its override
    design_hints, override_hints = typing.get_type_hints(design), typing.get_type_hints(override)
    for name, field in override_fields.items():
        assert field.default is None, name
        assert override_hints[name] == design_hints[name] | None, name
        assert dict(field.metadata) == dict(design_fields[name].metadata), name


def test_the_shipped_profile_has_no_truth_overrides():
    profile = _load()
    truth = profile.rig_truth()
    assert truth.building == profile.structure and truth.bearing == profile.bearing
    assert truth.differences == ()
    assert truth_summary(truth.differences) == "" and truth_metadata(truth.differences) == {}


# --- --set forms ----------------------------------------------------------------------------------


def test_a_scalar_and_a_list_set_on_the_command_line_land_in_the_truth_only():
    profile = _load(MU_SET, STIFFNESS_SET)
    assert profile.rig.truth.bearing.mu_max == 0.075
    assert profile.rig.truth.structure.story_stiffness_N_per_m == (0.6e6, 2.1e6, 1.5e6)
    design = _load()
    assert profile.bearing == design.bearing and profile.structure == design.structure  # the design is untouched
    truth = profile.rig_truth()
    assert truth.bearing.mu_max == 0.075 and truth.bearing.mu_delta == design.bearing.mu_delta
    assert truth.building.story_stiffness_N_per_m == (0.6e6, 2.1e6, 1.5e6)
    assert truth.building.floor_masses_kg == design.structure.floor_masses_kg


def test_a_truth_value_may_carry_its_unit_like_the_top_level():
    profile = _load('rig.truth.bearing.yield_displacement_m="0.05 mm"')
    assert profile.rig_truth().bearing.yield_displacement_m == pytest.approx(5e-5)


def test_an_unknown_key_under_rig_truth_is_refused_naming_it():
    err = _refusal("rig.truth.bearing.mu_maxx=0.07")
    assert err.key_path == "rig.truth.bearing.mu_maxx" and "unknown key 'mu_maxx'" in str(err)
    err = _refusal("rig.truth.building.base_mass_kg=1000")
    assert err.key_path == "rig.truth.building" and "expected one of: structure, bearing" in str(err)


def test_a_list_of_the_wrong_length_gives_the_top_level_message_at_the_truth_key():
    top = _refusal("structure.story_stiffness_N_per_m=[0.6e6,2.1e6]")
    err = _refusal("rig.truth.structure.story_stiffness_N_per_m=[0.6e6,2.1e6]")
    assert err.key_path == "rig.truth.structure" and top.key_path == "structure"
    assert err.detail == top.detail and "has 2 values, expected 3" in err.detail


def test_a_malformed_list_is_refused_naming_the_override_and_the_list_form():
    err = _refusal("rig.truth.structure.story_stiffness_N_per_m=[0.6e6,2.1e6")
    assert "rig.truth.structure.story_stiffness_N_per_m" in str(err) and "expected a list as [v1, v2, ...]" in str(err)


def test_an_out_of_range_truth_value_is_refused_at_its_key():
    err = _refusal("rig.truth.bearing.mu_max=1.5")
    assert err.key_path == "rig.truth.bearing.mu_max" and "expected a value >= 0 and <= 1" in str(err)


def test_a_truth_inconsistent_with_the_design_it_overrides_is_refused():
    err = _refusal("rig.truth.bearing.mu_delta=0.07")  # the design's mu_max is 0.06
    assert err.key_path == "rig.truth.bearing" and "exceeds mu_max = 0.06" in str(err)


def test_a_true_building_with_another_number_of_stories_is_refused():
    err = _refusal("rig.truth.structure.floor_masses_kg=[958,958,958,958]",
                   "rig.truth.structure.story_stiffness_N_per_m=[0.7e6,2e6,1.5e6,1e6]")
    assert err.key_path == "rig.truth.structure" and "4 stories, expected the design's 3" in str(err)


# --- derived quantities follow the true building --------------------------------------------------


def test_true_damping_given_either_way_replaces_the_designs():
    truth = _load("rig.truth.structure.story_damping_Ns_per_m=[100,200,300]").rig_truth()
    assert truth.building.first_mode_damping_ratio is None
    np.testing.assert_allclose(truth.building.story_damping(), [100.0, 200.0, 300.0])
    (difference,) = truth.differences
    assert difference.key == "structure.story_damping_Ns_per_m"
    np.testing.assert_allclose(difference.design_value, _load().structure.story_damping())  # the design's resolved


def test_stiffness_proportional_damping_follows_the_true_stiffness():
    design = _load().structure
    true_building = _load(STIFFNESS_SET).rig_truth().building
    assert fixed_base_modes(true_building)[1][0] == pytest.approx(0.01, rel=1e-6)
    assert fixed_base_modes(true_building)[0][0] < fixed_base_modes(design)[0][0]  # softer first story
    assert not np.allclose(true_building.story_damping(), design.story_damping())


def test_the_rig_is_built_on_the_truth_with_the_true_carried_weight():
    from harness.motions import load_motion
    from harness.rig.table import TablePlant

    profile = _load(MU_SET, "rig.truth.structure.floor_masses_kg=[1000,1000,1000]")
    parts = RigParts.from_profile(profile)
    assert parts.bearing.mu_max == 0.075 and parts.building.floor_masses_kg == (1000.0, 1000.0, 1000.0)
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=1.0)
    plant = TablePlant(parts.building, parts.bearing, motion, parts.rtol).record
    assert plant.bearing_params[MU_MAX] == 0.075
    assert plant.bearing_params[WEIGHT] == pytest.approx(parts.building.total_weight_N)
    assert plant.bearing_params[WEIGHT] > profile.structure.total_weight_N  # 3 x 42 kg more than the design carries
    design_parts = RigParts.from_profile(_load())
    assert design_parts.bearing == profile.bearing and design_parts.building == profile.structure


# --- the notes: metadata, console, report ---------------------------------------------------------


def test_the_note_names_each_difference_with_the_design_value_and_skips_equal_ones():
    truth = _load(MU_SET, "rig.truth.bearing.mu_delta=0.03", STIFFNESS_SET).rig_truth()  # mu_delta is the design's
    text = truth_summary(truth.differences)
    assert text.startswith("rig truth differs from design: ")
    assert "bearing.mu_max 0.075 (design 0.06)" in text
    assert "structure.story_stiffness_N_per_m [600000, 2.1e+06, 1.5e+06] (design [730000, 2.1e+06, 1.48e+06])" in text
    assert "mu_delta" not in text
    entry = truth_metadata(truth.differences)[METADATA_KEY]
    assert entry["summary"] == text
    assert {"key": "bearing.mu_max", "true": 0.075, "design": 0.06} in entry["differences"]
    assert truth_summary(_load("rig.truth.bearing.mu_max=0.06").rig_truth().differences) == ""  # set, but the design's


def _panel_text(notes: tuple[str, ...]) -> str:
    console = Console(file=io.StringIO(), width=200, color_system=None)
    with LoopStatus(state="RUNNING", duration_s=1.0) as status:
        console.print(LiveConsole(status, 0.08, 0.1, 10_000.0, "title", enabled=False, notes=notes))
    return console.file.getvalue()  # type: ignore[attr-defined]


def test_the_live_console_header_shows_the_note_and_nothing_without_one():
    line = "rig truth differs from design: bearing.mu_max 0.075 (design 0.06)"
    text = _panel_text((line,))
    assert "NOTE" in text and line in text
    assert text.index(line) < text.index("state")  # at the top, above the run's state
    assert "NOTE" not in _panel_text(()) and "rig truth" not in _panel_text(())
    command = view_command("/dev/null", 0.08, 0.1, 10_000.0, "title", parent_pid=1, notes=(line,))
    assert f"--note={line}" in command  # the drawing child gets it too


def _run_data(metadata: dict) -> RunData:
    return RunData(Path("run"), {"controller": "phi", **metadata}, {}, (), {}, [], None, False)


def test_the_report_names_the_difference_and_says_nothing_without_one():
    differences = _load(MU_SET).rig_truth().differences
    note = truth_note(_run_data(truth_metadata(differences)))
    assert note.startswith("rig truth differs from design: bearing.mu_max 0.075 (design 0.06)")
    assert "used the design values" in note
    assert truth_note(_run_data({})) == ""


def test_the_truth_survives_the_resolved_profile_the_rig_process_is_given():
    from harness.profile import Profile

    profile = _load(MU_SET, STIFFNESS_SET)
    again = Profile.from_resolved(profile.resolved_data())  # what `harness dry-run` hands its rig process
    assert again.rig_truth() == profile.rig_truth()
    assert again.bearing == profile.bearing and again.structure == profile.structure
