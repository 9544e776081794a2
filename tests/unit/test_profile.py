"""Profiles: loading, extends, variants, units, and a clear error for every kind of bad input."""

from __future__ import annotations

import subprocess
import sys

import pytest

from harness.errors import ProfileError
from harness.profile import load_profile, merge
from tests.conftest import PROFILES, REPO


def test_shipped_profiles_load_with_units_converted():
    eight = load_profile(PROFILES / "eight_story.yaml")
    assert eight.structure.floor_masses_kg == (345600.0,) * 8
    assert eight.structure.story_stiffness_N_per_m[0] == pytest.approx(3.40e8)
    assert eight.structure.story_damping_Ns_per_m[7] == pytest.approx(196e3)
    assert eight.bearing.a_mu_s_per_m == pytest.approx(20.0)
    assert eight.bearing.yield_displacement_m == pytest.approx(1.2e-4)
    assert set(eight.control.designs) == {"FSF-I", "FSF-II", "OF-I", "OF-II"}
    assert eight.control.rate_hz == 250
    rig = load_profile(PROFILES / "nceer_4dof.yaml")
    assert rig.bearing.a_mu_s_per_m == pytest.approx(90.16)
    assert rig.bearing.yield_displacement_m == pytest.approx(2.54e-5)
    phi = rig.control.designs["phi"]
    assert (phi.p1_per_s, phi.phi, phi.delta) == (8.0, 0.8, 0.0)
    assert "assumed" in rig.structure.assumptions


def test_variants_apply_and_are_named():
    variant = load_profile(PROFILES / "eight_story.yaml", variant="a_mu_0.5")
    assert variant.bearing.a_mu_s_per_m == pytest.approx(50.0)
    assert variant.variant == "a_mu_0.5"
    assert load_profile(PROFILES / "eight_story.yaml", variant="stiffness_minus_30").control.design_stiffness_scale == 0.7
    with pytest.raises(ProfileError, match="unknown variant 'nope'"):
        load_profile(PROFILES / "eight_story.yaml", variant="nope")


def test_extends_overrides_key_by_key(tmp_path):
    child = tmp_path / "experiment.yaml"
    child.write_text(f"extends: {PROFILES / 'nceer_4dof.yaml'}\nname: my_test\ncontrol:\n  designs:\n    phi: {{phi: 0.5}}\n")
    profile = load_profile(child)
    assert profile.name == "my_test"
    assert profile.control.designs["phi"].phi == 0.5
    assert profile.control.designs["phi"].p1_per_s == 8.0
    assert profile.structure.base_mass_kg == 1148.62


def test_extends_loop_is_refused(tmp_path):
    (tmp_path / "a.yaml").write_text("extends: b.yaml\n")
    (tmp_path / "b.yaml").write_text("extends: a.yaml\n")
    with pytest.raises(ProfileError, match="loop"):
        load_profile(tmp_path / "a.yaml")


def test_resolved_data_is_plain_and_reloadable(tmp_path):
    import yaml

    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    data = profile.resolved_data()
    data.pop("loaded_from")
    (tmp_path / "resolved.yaml").write_text(yaml.safe_dump(data))
    again = load_profile(tmp_path / "resolved.yaml")
    assert again.structure == profile.structure and again.control == profile.control


def test_merge_is_deep_and_does_not_mutate():
    base = {"a": {"b": 1, "c": 2}, "d": [1]}
    out = merge(base, {"a": {"b": 5}, "d": [2]})
    assert out == {"a": {"b": 5, "c": 2}, "d": [2]}
    assert base == {"a": {"b": 1, "c": 2}, "d": [1]}


def _rig_text() -> str:
    return (PROFILES / "nceer_4dof.yaml").read_text()


BAD_PROFILES = {
    "empty": ("", "empty"),
    "binary": (b"\x00\x01\xff\xfe\x89PNG\r\n", "not UTF-8|invalid YAML"),
    "not_a_mapping": ("- 1\n- 2\n", "expected a mapping"),
    "yaml_syntax": ("name: [unclosed\n", "invalid YAML at line"),
    "unknown_top_key": (_rig_text() + "\nsafetyy: {}\n", "unknown key 'safetyy'"),
    "unknown_nested_key": (_rig_text().replace("mu_max: 0.06", "mu_maxx: 0.06"), "bearing.mu_maxx"),
    "wrong_unit": (_rig_text().replace("base_mass_kg: 1148.62", 'base_mass_kg: "1148.62 m"'), "not a unit of the same kind"),
    "unknown_unit": (_rig_text().replace("base_mass_kg: 1148.62", 'base_mass_kg: "1148.62 furlongs"'), "unknown unit"),
    "negative_mass": (_rig_text().replace("base_mass_kg: 1148.62", "base_mass_kg: -5"), "expected a value > 0"),
    "string_for_number": (_rig_text().replace("mu_max: 0.06", "mu_max: lots"), "mu_max"),
    "bool_for_number": (_rig_text().replace("mu_max: 0.06", "mu_max: true"), "expected a number"),
    "phi_out_of_range": (_rig_text().replace("phi: 0.8", "phi: 1.5"), "expected a value >= 0 and <= 1"),
    "p1_zero": (_rig_text().replace("p1_per_s: 8.0\n      phi", "p1_per_s: 0\n      phi"), "> 0"),
    "missing_section": (_rig_text().replace("bearing:", "bearingx:"), "unknown key 'bearingx'"),
    "huge_value": (_rig_text().replace("mu_max: 0.06", "mu_max: 1e400"), "finite|<= 1"),
    "nan_value": (_rig_text().replace("mu_max: 0.06", "mu_max: .nan"), "finite"),
    "list_length": (_rig_text().replace("[0.73e6, 2.10e6, 1.48e6]", "[0.73e6, 2.10e6]"), "expected 3"),
    "bad_kind": (_rig_text().replace("kind: phi", "kind: magic"), "expected kind one of"),
    "unknown_controller": (_rig_text().replace("controller: phi", "controller: nope"), "not one of the designs"),
    "dy_zero": (_rig_text().replace('yield_displacement_m: "0.0254 mm"', "yield_displacement_m: 0"), "> 0"),
    # A second section used to replace the first silently (the stroke limits fell back to code defaults).
    "duplicate_section": (
        _rig_text() + "\nsafety:\n  force:\n    max_force_N: 5000\n",
        rf"duplicate key 'safety' at line \d+, column 1 "
        rf"\(first at line {_rig_text().splitlines().index('safety:') + 1}, column 1\)",
    ),
    "duplicate_nested_key": (
        _rig_text().replace("  mu_max: 0.06\n", "  mu_max: 0.06\n  mu_max: 0.07\n"),
        rf"duplicate key 'mu_max' at line {_rig_text().splitlines().index('  mu_max: 0.06') + 2}, column 3 "
        rf"\(first at line {_rig_text().splitlines().index('  mu_max: 0.06') + 1}, column 3\)",
    ),
    "rate_above_bound": (
        _rig_text().replace("  rate_hz: 500\n", "  rate_hz: 20000\n", 1), r"rate_hz: found 20000, expected .*<= 5000 Hz"
    ),
    "time_scale_too_large": (
        _rig_text().replace("time_scale: 2.0", "time_scale: 1e9"), r"time_scale: found 1e\+09, expected .*<= 10"
    ),
}


@pytest.mark.parametrize("case", sorted(BAD_PROFILES))
def test_bad_profile_gives_one_clear_error(tmp_path, case):
    content, pattern = BAD_PROFILES[case]
    path = tmp_path / f"{case}.yaml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    with pytest.raises(ProfileError, match=pattern) as info:
        load_profile(path)
    assert str(path) in str(info.value)


def test_missing_profile_names_the_shipped_ones(tmp_path):
    with pytest.raises(ProfileError, match="nceer_4dof.yaml"):
        load_profile(tmp_path / "nope.yaml")


@pytest.mark.parametrize("case", ["empty", "wrong_unit", "unknown_nested_key", "binary"])
def test_cli_reports_bad_profile_without_traceback(tmp_path, case):
    content, _ = BAD_PROFILES[case]
    path = tmp_path / f"{case}.yaml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    done = subprocess.run(
        [sys.executable, "-m", "harness.cli", "simulate", str(path), "--duration", "1"],
        capture_output=True, text=True, cwd=REPO, timeout=120,
    )
    assert done.returncode == 2
    assert "Traceback" not in done.stderr + done.stdout
    assert "error:" in done.stderr and path.name in done.stderr
