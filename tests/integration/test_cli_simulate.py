"""``harness simulate``: the table, the JSON document, run folders, and clear errors."""

from __future__ import annotations

import json

import pytest

from harness.cli import main
from harness.recording import strict_json
from harness.recording.reader import load_run
from tests.conftest import PROFILES


def _run(args, capsys):
    status = main(args)
    out = capsys.readouterr()
    return status, out.out, out.err


def test_simulate_writes_the_documented_json(tmp_path, capsys):
    path = tmp_path / "out.json"
    status, out, _ = _run(
        [
            "simulate", str(PROFILES / "eight_story.yaml"), "--duration", "4", "--controller", "OF-I",
            "--json", str(path),
        ],
        capsys,
    )
    assert status == 0
    assert "story 8 drift" in out and "reduction %" in out
    doc = strict_json.loads(path.read_text())  # null, never NaN: any parser reads it
    assert doc["profile"] == "eight_story" and doc["controller"] == "OF-I"
    assert set(doc["record"]) >= {"name", "pga_g", "pgv_m_s", "pgd_m", "time_scale", "duration_s"}
    assert doc["record"]["duration_s"] == pytest.approx(4.0)
    for case in ("passive", "controlled"):
        peaks = doc["cases"][case]
        assert set(peaks) == {
            "sliding_displacement_m", "base_acceleration_m_s2", "drift_m", "floor_acceleration_m_s2", "peak_force_pct_weight",
        }
        assert len(peaks["drift_m"]) == 8 and len(peaks["floor_acceleration_m_s2"]) == 8
    assert doc["cases"]["passive"]["peak_force_pct_weight"] == 0.0
    assert doc["cases"]["controlled"]["peak_force_pct_weight"] > 0.0
    assert max(doc["cases"]["controlled"]["drift_m"]) < max(doc["cases"]["passive"]["drift_m"])


def test_simulate_none_runs_passive_only(tmp_path, capsys):
    path = tmp_path / "none.json"
    status, out, _ = _run(["simulate", "--duration", "2", "--controller", "none", "--json", str(path), "--quiet"], capsys)
    doc = strict_json.loads(path.read_text())  # null, never NaN: any parser reads it
    assert status == 0 and doc["controller"] == "none"
    assert doc["cases"]["controlled"] == doc["cases"]["passive"]
    assert "reduction" not in out


def test_simulate_out_writes_loadable_run_folders(tmp_path, capsys):
    status, _, _ = _run(["simulate", "--duration", "2", "--out", str(tmp_path / "study"), "--quiet"], capsys)
    assert status == 0
    controlled = load_run(tmp_path / "study" / "controlled")
    passive = load_run(tmp_path / "study" / "passive")
    assert controlled.n_rows == passive.n_rows == 1001  # 2 s at 500 Hz, both ends
    assert controlled["force_command_N"].any() and not passive["force_command_N"].any()


@pytest.mark.parametrize(
    "args, message",
    [
        (["--record", "no_such_record"], "no_such_record"),
        (["--controller", "FSF-IX"], "unknown controller"),
        (["--record", "/nonexistent/file.AT2"], "file.AT2"),
    ],
)
def test_simulate_bad_input_exits_2_with_a_clear_message(args, message, capsys):
    status, _, err = _run(["simulate", "--duration", "1", "--quiet", *args], capsys)
    assert status == 2
    assert message in err and "Traceback" not in err


def test_design_stiffness_scale_changes_the_controlled_result(tmp_path, capsys):
    results = {}
    for scale in ("1.0", "0.7"):
        path = tmp_path / f"{scale}.json"
        main(["simulate", str(PROFILES / "eight_story.yaml"), "--duration", "3", "--controller", "FSF-I",
              "--design-stiffness-scale", scale, "--json", str(path), "--quiet"])
        results[scale] = json.loads(path.read_text())
    capsys.readouterr()
    assert results["0.7"]["sampling"]["design_stiffness_scale"] == 0.7
    assert results["0.7"]["cases"]["controlled"]["drift_m"] != results["1.0"]["cases"]["controlled"]["drift_m"]
    assert results["0.7"]["cases"]["passive"] == results["1.0"]["cases"]["passive"]


def test_rig_effects_keep_the_design_stiffness_scale(tmp_path, capsys, monkeypatch):
    """--rig-effects with --design-stiffness-scale: the rig twin's controller is designed with the scale too."""
    import harness.control.factory as factory

    scales = []
    original = factory.make_controller

    def spy(profile, name, design_stiffness_scale=1.0):
        scales.append(design_stiffness_scale)
        return original(profile, name, design_stiffness_scale)

    monkeypatch.setattr(factory, "make_controller", spy)
    path = tmp_path / "twin.json"
    status = main(["simulate", "--duration", "1", "--rig-effects", "--design-stiffness-scale", "0.7",
                   "--json", str(path), "--quiet"])
    capsys.readouterr()
    assert status == 0
    assert scales == [0.7]  # before the fix: 1.0, the scale silently dropped
    assert json.loads(path.read_text())["sampling"]["design_stiffness_scale"] == 0.7


def test_simulate_takes_set_validated_like_the_file(tmp_path, capsys):
    peaks = {}
    for p1 in ("0.315", "8.0"):
        path = tmp_path / f"p1_{p1}.json"
        status, _, _ = _run(["simulate", "--duration", "2", "--set", f"control.designs.phi.p1_per_s={p1}",
                             "--json", str(path), "--quiet"], capsys)
        assert status == 0
        peaks[p1] = json.loads(path.read_text())["cases"]["controlled"]
    assert peaks["8.0"] != peaks["0.315"]  # the override reached the controller
    status, _, err = _run(["simulate", "--duration", "1", "--set", "control.designs.phi.p1_per_s=-1", "--quiet"], capsys)
    assert status == 2 and "p1_per_s" in err and "Traceback" not in err


@pytest.mark.parametrize("command", ["simulate", "dry-run", "rig", "run", "records"])
def test_every_command_that_loads_a_profile_refuses_a_bad_set_the_same_way(command, capsys):
    """--set and --variant are accepted by every profile-loading command and validated before anything runs."""
    profile_args = ["--profile", str(PROFILES / "nceer_4dof.yaml")] if command == "records" else []
    status, _, err = _run([command, *profile_args, "--set", "control.designs.phi.p1_per_s=-1"], capsys)
    assert status == 2 and "control.designs.phi.p1_per_s" in err and "> 0" in err and "Traceback" not in err
    status, _, err = _run([command, *profile_args, "--variant", "no_such_variant"], capsys)
    assert status == 2 and "no_such_variant" in err and "Traceback" not in err


def test_records_applies_set_to_the_profile_it_loads(capsys):
    """`records --set` reaches the profile: a smaller table stroke refuses the same record."""
    base = ["records", "synthetic", "--profile", str(PROFILES / "nceer_4dof.yaml"), "--pga", "0.34"]
    status, out, _ = _run(base, capsys)
    assert status == 0 and "fits the table" in out
    status, out, _ = _run([*base, "--set", "table.stroke_limit_m=0.005"], capsys)
    assert status == 2 and "exceeds the table's stroke" in out and "the largest PGA that fits" in out
