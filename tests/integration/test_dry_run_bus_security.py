"""A dry run's private ``seqpacket`` channel: a relay that sits on it first is refused (docs/SAFETY.md, "Threat model").

The relay is another process of the same user: the peer check by user cannot tell it from the
rig, so the dry run pins each end to the other's process (``SessionSettings.peer_pids``, the rig
process's ``parent_pid``). Its channel name carries random bytes (``private_bus``); here the name is
made known to the relay, as if it had guessed it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import main
from harness.runs import dry_run as dry_run_module

ROOT = Path(__file__).resolve().parents[2]
RELAY = """
import sys, time
from drivers.transports.seqpacket.bus import SeqPacketBus
bus = SeqPacketBus(sys.argv[1])
assert bus.is_hub
print("ready", flush=True)
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    bus.recv(timeout=0.05)  # relays between whoever connects
"""


def test_a_relay_sitting_on_the_private_channel_is_refused_before_anything_moves(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str],
) -> None:
    channel = f"harness-{os.getpid()}-guessed"
    monkeypatch.setattr(dry_run_module, "private_bus", lambda can, external_rig, suffix="": replace(can, channel=channel))
    relay = subprocess.Popen([sys.executable, "-c", RELAY, channel], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert relay.stdout is not None and relay.stdout.readline().strip() == "ready"
        status = main(["dry-run", "--lockstep", "--quiet", "--duration", "1", "--log-dir", str(tmp_path)])
        err = capsys.readouterr().err
    finally:
        relay.kill()
        relay.wait()
    assert status == exit_codes.INPUT_ERROR
    assert "refused the hub" in err and f"process {relay.pid} " in err and "not the process this bus expects" in err
