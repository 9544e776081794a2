"""``--overlay FILE``: a file of profile keys merged after the variant and before ``--set``,
validated like the profile, weakening refused unless acknowledged, recorded with its hash."""

from __future__ import annotations

import hashlib
import json

import pytest

from harness.cli import main
from harness.errors import ProfileError
from harness.profile import Profile, load_profile
from tests.conftest import PROFILES

NCEER = PROFILES / "nceer_4dof.yaml"


@pytest.fixture
def overlay(tmp_path):
    path = tmp_path / "identified.yaml"
    path.write_text("# identified\nbearing:\n  mu_max: 0.071\nrig:\n  actuator: {model: first_order}\n")
    return path


def test_the_overlay_goes_over_the_variant_and_under_set(overlay) -> None:
    plain = load_profile(NCEER)
    over = load_profile(NCEER, overlay=overlay)
    assert plain.bearing.mu_max == 0.06 and over.bearing.mu_max == 0.071
    # the variant's rig is a first-order actuator and a motion-source table; the overlay sets the actuator only
    both = load_profile(NCEER, variant="force_source", overlay=overlay)
    assert both.rig.actuator.model == "first_order" and both.rig.table.model == "motion_source"
    assert both.bearing.mu_max == 0.071
    last = load_profile(NCEER, overlay=overlay, overrides=["bearing.mu_max=0.065"])
    assert last.bearing.mu_max == 0.065, "--set goes last"


def test_the_profile_keeps_the_overlays_file_and_hash_through_a_resolved_copy(overlay) -> None:
    profile = load_profile(NCEER, overlay=overlay)
    digest = hashlib.sha256(overlay.read_bytes()).hexdigest()
    assert profile.overlay_record() == {"path": str(overlay.resolve()), "sha256": digest}
    again = Profile.from_resolved(json.loads(json.dumps(profile.resolved_data())))
    assert again.overlay_record() == profile.overlay_record() and again.bearing.mu_max == 0.071
    assert load_profile(NCEER).overlay_record() is None


def test_an_overlay_that_weakens_safety_is_listed_as_a_weakening(tmp_path) -> None:
    weak = tmp_path / "weak.yaml"
    weak.write_text("safety:\n  force:\n    tracking_tolerance_N: 2000\n")
    profile = load_profile(NCEER, overlay=weak)
    assert [w.key for w in profile.safety_weakened] == ["safety.force.tracking_tolerance_N"]
    strict = tmp_path / "strict.yaml"
    strict.write_text("safety:\n  force:\n    tracking_tolerance_N: 500\n")
    assert load_profile(NCEER, overlay=strict).safety_weakened == ()


def test_an_overlay_is_validated_like_the_profile_and_named_in_the_error(tmp_path) -> None:
    bad = tmp_path / "bad.yaml"
    bad.write_text("bearing:\n  mu_max: -0.1\n")
    with pytest.raises(ProfileError, match=r"with --overlay .*bad\.yaml.*bearing\.mu_max"):
        load_profile(NCEER, overlay=bad)
    variants = tmp_path / "variants.yaml"
    variants.write_text("variants:\n  x: {bearing: {mu_max: 0.1}}\n")
    with pytest.raises(ProfileError, match="an overlay holds values only; expected no 'variants'"):
        load_profile(NCEER, overlay=variants)


def test_a_simulated_run_records_the_overlay_in_its_metadata(overlay, tmp_path, capsys) -> None:
    out = tmp_path / "out"
    assert main(["simulate", "--overlay", str(overlay), "--duration", "1", "--out", str(out), "--quiet"]) == 0
    metadata = [json.loads(p.read_text()) for p in out.rglob("metadata.json")]
    assert metadata, "simulate wrote its cases"
    for entry in metadata:
        assert entry["overlay"] == {"path": str(overlay.resolve()), "sha256": hashlib.sha256(overlay.read_bytes()).hexdigest()}
