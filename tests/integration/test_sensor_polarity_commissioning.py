"""Commissioning step 1 (README, "Commissioning a rig"), run as the README gives it, against the virtual rig.

A whole sensor of reversed polarity (displacement, velocity and acceleration flipped together: the
rig's ``polarity`` fault) is self-consistent, so the pair checks cannot see it. At the README's level
the table check judges, and a reversed table sensor stops the run (exit 4) with the polarity named; a
reversed base-mat sensor completes the run with a warning on the outcome line; a sound rig completes
with the table check a match and the base mat moving with the table. A level at which nothing can
judge is never a silent pass: the outcome carries a warning (issue 33, item 1). Lockstep, so each
run is deterministic; the fault is on from the start of the record.
"""

from __future__ import annotations

import json
import re

from harness import exit_codes
from harness.cli import main
from harness.paths import PROJECT_ROOT

#: The README's step 1 command: its record (the level is in the name) and its duration.
STEP_1 = re.search(r"1\. \*\*Sensor signs\.\*\* Play a low-level table motion \(`harness run PROFILE --record\s+"
                   r"(white_noise:\S+) --duration (\d+)`", (PROJECT_ROOT / "README.md").read_text())


def _step_1(tmp_path, capsys, *extra: str, record: str | None = None, duration: str | None = None):
    assert STEP_1, "README's commissioning step 1 no longer gives its command as this test reads it"
    status = main(["dry-run", "--lockstep", "--record", record or STEP_1.group(1), "--duration", duration or STEP_1.group(2),
                   "--log-dir", str(tmp_path), *extra])
    out = capsys.readouterr().out
    folder = next(p for p in tmp_path.iterdir() if p.is_dir())
    outcome = next(line for line in out.splitlines() if line.startswith("outcome:"))
    return status, out, outcome, json.loads((folder / "metadata.json").read_text())


def _polarity(target: str) -> tuple[str, str]:
    return "--set", f"rig.faults=[{{kind: polarity, target: {target}}}]"


def test_a_sound_rig_passes_step_1_with_both_signs_judged(tmp_path, capsys) -> None:
    status, out, outcome, metadata = _step_1(tmp_path, capsys)
    assert status == exit_codes.OK, out[-3000:]
    assert metadata["summary"]["table_record"]["verdict"] == "match"
    assert "with a warning" not in outcome, outcome
    assert re.search(r"base-mat sensor sign: moves with the table \(correlation of ydot_b with xdot_0 over the record "
                     r"\+0\.[3-9]", out), out[-2000:]


def test_a_reversed_table_sensor_is_stopped_at_the_readmes_level(tmp_path, capsys) -> None:
    status, out, outcome, metadata = _step_1(tmp_path, capsys, *_polarity("TABLE_SENSORS"))
    assert status == exit_codes.STOPPED, out[-3000:]
    assert metadata["trip_reason"] == "table_record_mismatch"
    assert "stopped (table_record_mismatch)" in outcome
    assert "a table sensor of reversed polarity" in " ".join(out.split())


def test_a_reversed_base_mat_sensor_is_a_warning_on_the_outcome(tmp_path, capsys) -> None:
    status, out, outcome, metadata = _step_1(tmp_path, capsys, *_polarity("BASE_SENSORS"))
    assert metadata["summary"]["table_record"]["verdict"] == "match"  # the table's sensor is sound
    assert status == exit_codes.OK  # nothing stopped the run: the outcome must say it
    assert "with a warning: the base-mat sensor moved against the table" in outcome, outcome
    assert "WARNING: the base mat moved against the table" in out


def test_a_level_the_table_check_cannot_judge_is_a_warning_not_a_silent_pass(tmp_path, capsys) -> None:
    """The level the README gave before (0.01 g): the record never swings beyond the table check's floor."""
    status, out, outcome, metadata = _step_1(tmp_path, capsys, record="white_noise:0.5-5:0.01", duration="5")
    assert status == exit_codes.OK
    assert metadata["summary"]["table_record"]["verdict"] == "waiting"
    assert "with a warning: the table check never judged" in outcome, outcome
    assert "WARNING: neither the record the table played nor the table sensor's polarity was checked" in " ".join(out.split())
