"""Through the real command line: a weaker safety setting needs --allow-weaker-safety and is recorded;
a force the protocol cannot carry is refused whatever the flag; a stricter setting needs nothing."""

from __future__ import annotations

import json
from pathlib import Path

from harness import exit_codes
from harness.cli import main
from tests.unit.test_safety_weakening import CONSISTENT_SHORT_LOOK_AHEAD

SHORT_DRY_RUN = ["dry-run", "--lockstep", "--duration", "1", "--quiet"]


def _sets(items: list[str]) -> list[str]:
    return [arg for item in items for arg in ("--set", item)]


def _dry_run(tmp_path: Path, capsys, *args: str) -> tuple[int, str, str]:
    status = main([*SHORT_DRY_RUN, "--log-dir", str(tmp_path), *args])
    out, err = capsys.readouterr()
    return status, " ".join(out.split()), " ".join(err.split())


def _metadata(tmp_path: Path) -> dict:
    (folder,) = [p for p in tmp_path.iterdir() if p.is_dir()]
    return json.loads((folder / "metadata.json").read_text())


def _no_run_folder(tmp_path: Path) -> bool:
    return not any(p.is_dir() for p in tmp_path.iterdir())


def test_a_weaker_look_ahead_is_refused_without_the_flag_and_recorded_with_it(tmp_path, capsys):
    status, _, err = _dry_run(tmp_path, capsys, *_sets(CONSISTENT_SHORT_LOOK_AHEAD))
    assert status == exit_codes.INPUT_ERROR
    assert "safety.stroke.stop_time_s 0.05 -> 0.02" in err and "--allow-weaker-safety" in err
    assert "max_stall_s" not in err  # the stricter ones are not listed
    assert _no_run_folder(tmp_path)

    status, out, _ = _dry_run(tmp_path, capsys, *_sets(CONSISTENT_SHORT_LOOK_AHEAD), "--allow-weaker-safety")
    assert status == exit_codes.OK
    assert _metadata(tmp_path)["safety_weakened"] == [
        {"key": "safety.stroke.stop_time_s", "profile_value": 0.05, "value": 0.02, "direction": "smaller"}
    ]
    outcome = out[out.index("outcome:"):]
    assert "safety weakened (--allow-weaker-safety): safety.stroke.stop_time_s 0.05 -> 0.02" in outcome


def test_a_milder_detector_action_is_refused_without_the_flag(tmp_path, capsys):
    status, _, err = _dry_run(tmp_path, capsys, "--set", "safety.comms.error_frame_action=indicate")
    assert status == exit_codes.INPUT_ERROR
    assert "safety.comms.error_frame_action safe_stop -> indicate" in err
    assert _no_run_folder(tmp_path)


def test_max_force_beyond_the_protocol_is_refused_whatever_the_flag(tmp_path, capsys):
    for flag in ([], ["--allow-weaker-safety"]):
        # a load-cell limit and a supply force above it, so that the protocol's bound is the one that speaks
        roomy = ("--set", "safety.force.load_cell_limit_N=60000", "--set", "safety.force.supply_force_N=60000")
        status, _, err = _dry_run(tmp_path, capsys, "--set", "safety.force.max_force_N=40000", *roomy, *flag)
        assert status == exit_codes.INPUT_ERROR
        assert "safety.force.max_force_N: found 40000 N, expected at most 30000 N" in err and "ACTUATOR_CMD" in err
        assert _no_run_folder(tmp_path)


def test_a_stricter_hard_limit_needs_no_flag(tmp_path, capsys):
    # the fade band must narrow with it to stay inside the soft-to-hard gap (check_config)
    status, _, err = _dry_run(tmp_path, capsys, *_sets(["safety.stroke.hard_limit_m=0.09", "safety.stroke.fade_band_m=0.01"]))
    assert status == exit_codes.OK, err
    metadata = _metadata(tmp_path)
    assert metadata["safety_weakened"] == [] and metadata["stroke_hard_limit_m"] == 0.09


def test_the_rig_and_run_commands_refuse_a_weakening_without_the_flag(capsys):
    for command in ("rig", "run"):
        status = main([command, "--duration", "1", "--set", "safety.run.max_stall_s=0.03",
                       "--set", "safety.stroke.stop_time_s=0.06"])
        err = " ".join(capsys.readouterr().err.split())
        assert status == exit_codes.INPUT_ERROR, command
        assert "safety.run.max_stall_s 0.02 -> 0.03" in err and "stop_time_s" not in err, command
