"""``harness run``'s run on the real rig (harness/runs/run.py): the table link, which answers arm, the session.

Nothing here opens a bus: the command's terminal side is tested through ``harness run`` in
tests/integration/test_run_command.py.
"""

from __future__ import annotations

import pytest

from harness.loop.table_link import CanTableLink
from harness.profile import load_profile
from harness.runs.options import StudyOptions, resolve_profile
from harness.runs.run import (
    NO_TABLE_CHECK,
    NO_TABLE_LINK,
    TABLE_LINK_CAN,
    answer_arms,
    arm_question,
    prepare_rig_run,
    session_settings,
)

OPTIONS = StudyOptions(record="synthetic", duration_s=1.0, pga_g=0.2)


def _run(*overrides: str):
    profile = resolve_profile(load_profile(None, overrides=list(overrides)), OPTIONS)
    return prepare_rig_run(profile, "seqpacket", "nowhere")


@pytest.mark.parametrize("answer", ["y", "yes", "Y", " YES \n", "Yes"])
def test_only_yes_arms(answer: str) -> None:
    assert answer_arms(answer)


@pytest.mark.parametrize("answer", ["", "\n", "n", "no", "yes please", "ye", "y y", "ok", "1", "sure"])
def test_anything_else_does_not_arm(answer: str) -> None:
    assert not answer_arms(answer)


def test_a_table_on_can_is_started_by_the_run_and_checked_against_its_record(tmp_path) -> None:
    run = _run()
    assert isinstance(run.table_link, CanTableLink) and run.table_link_note == TABLE_LINK_CAN
    assert (run.can.interface, run.can.channel) == ("seqpacket", "nowhere")
    settings = session_settings(run, tmp_path, show_console=False, reset_drive=True)
    assert settings.kind == "run" and settings.table_record is run.motion and settings.reset_drive
    assert settings.duration_s == run.motion.duration_s == pytest.approx(1.0)
    assert settings.metadata["table_link"] == "can" and settings.metadata["record"]["pga_g"] == pytest.approx(0.2)


def test_a_table_started_by_hand_has_no_link_and_no_table_check(tmp_path) -> None:
    run = _run("table.link=none")
    assert run.table_link is None and run.table_link_note == NO_TABLE_LINK
    settings = session_settings(run, tmp_path)
    assert settings.table_record is None and settings.table_check_off == NO_TABLE_CHECK
    assert settings.metadata["table_link"] == "none"


def test_the_arm_question_names_the_bus_the_record_and_the_limits() -> None:
    run = _run()
    question = arm_question(run)
    assert question.startswith("Arm the actuator on seqpacket:nowhere with ") and question.endswith("? [y/N] ")
    for part in ("PGA 0.200 g", "1.0 s", f"{run.profile.safety.force.max_force_N / 1e3:g} kN", "hard stroke"):
        assert part in question, part
    assert arm_question(run, reset_drive=True).startswith("Reset the drive's latched fault and arm the actuator")
