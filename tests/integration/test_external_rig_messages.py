"""What a dry run says about the external rig it expects (issue 30, messages): nothing is left unexplained."""

from __future__ import annotations

import time
import uuid

import pytest

from harness import exit_codes
from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness
from harness.cli import main
from harness.errors import BusError
from harness.runs.dry_run import NO_RIG_NOTICE_S, RigCoordinator


def test_no_external_rig_is_said_within_five_seconds_with_the_wait_left() -> None:
    notes: list[tuple[float, str]] = []
    coordinator = RigCoordinator(True, 0.002, appear_timeout_s=NO_RIG_NOTICE_S + 0.5,
                                 notify=lambda line: notes.append((time.monotonic(), line)))
    start = time.monotonic()
    with open_harness(CanConfig(interface="seqpacket", channel=f"norig-{uuid.uuid4().hex[:8]}")) as link, \
            pytest.raises(BusError, match=r"no RIG_STATUS frame from a virtual rig within 5.5 s"):
        coordinator.on_link(link)
    assert len(notes) == 1, notes
    at, line = notes[0]
    assert NO_RIG_NOTICE_S <= at - start < NO_RIG_NOTICE_S + 0.4
    assert NO_RIG_NOTICE_S <= 5.0, "the issue asks to be told within 5 s"
    assert "no rig answers" in line and "waiting 0.5 s more" in line


def test_reset_drive_without_external_rig_says_why_even_when_quiet(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["dry-run", "--reset-drive", "--quiet"]) == exit_codes.INPUT_ERROR
    out = capsys.readouterr()
    assert "--reset-drive resets the drive of a rig that already serves the channel" in out.out + out.err
