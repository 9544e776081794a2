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
    assert NO_RIG_NOTICE_S < 5.0, "the issue asks to be told within 5 s"
    notes: list[tuple[float, str]] = []
    coordinator = RigCoordinator(True, 0.002, appear_timeout_s=NO_RIG_NOTICE_S + 0.5,
                                 notify=lambda line: notes.append((time.monotonic(), line)))
    start = time.monotonic()
    with open_harness(CanConfig(interface="seqpacket", channel=f"norig-{uuid.uuid4().hex[:8]}")) as link, \
            pytest.raises(BusError, match=rf"no RIG_STATUS frame from a virtual rig within {NO_RIG_NOTICE_S + 0.5:g} s"):
        coordinator.on_link(link)
    assert len(notes) == 1, notes
    at, line = notes[0]
    assert NO_RIG_NOTICE_S <= at - start < 5.0, "told within 5 s"
    assert "no rig answers" in line and "waiting 0.5 s more" in line


def test_reset_drive_without_external_rig_says_why_even_when_quiet(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["dry-run", "--reset-drive", "--quiet"]) == exit_codes.INPUT_ERROR
    assert "--reset-drive resets the drive of a rig that already serves the channel" in capsys.readouterr().err


def test_a_start_the_rig_refused_is_reported_and_the_run_is_not_a_completed_test(
    tmp_path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
) -> None:
    # The rig's answer itself is proven in tests/integration/test_rig_bus.py; here, what the command makes of it.
    monkeypatch.setattr(RigCoordinator, "start_refused", lambda self: True)
    status = main(["dry-run", "--lockstep", "--quiet", "--duration", "1", "--log-dir", str(tmp_path)])
    out = capsys.readouterr().out
    assert status == exit_codes.STOPPED
    assert "the rig refused this run's table start" in out and "did not play this run's record" in out
