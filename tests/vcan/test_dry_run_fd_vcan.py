"""The CAN FD protocol on real SocketCAN (vcan0, MTU 72): the drivers, and a dry run across two processes.

Run inside User-Mode Linux by ``scripts/run-tests`` where the host kernel has no CAN
(scripts/with-vcan creates vcan0 with MTU 72). As the classic runs of test_dry_run_vcan.py,
the dry run is in lockstep: UML makes every system call slow, and lockstep's results do not
depend on timing. It runs at 2 kHz, the rate the FD protocol is for.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import can
import pytest

from drivers.link import open_harness, open_rig
from harness import exit_codes
from harness.canbus.config import CanConfig

pytestmark = pytest.mark.vcan

REPO = Path(__file__).resolve().parents[2]
HARNESS = [sys.executable, "-m", "harness.cli"]
SLOW_HOST = ["--set", "rig.drive.watchdog_timeout_s=0.5"]  # as test_dry_run_vcan.py: behaviour, not timing
SENSOR_SET_ID, CLASSIC_SENSOR_IDS = 0x32, {0x30, 0x31, 0x200, 0x201}


def test_fd_frames_of_the_protocol_cross_vcan0(vcan_fd_channel):
    rates = CanConfig(fd=True, loop_rate_hz=2000.0).rates_hz()
    with open_rig("socketcan", vcan_fd_channel, 1_000_000, rates, fd=True, data_bitrate_bps=5_000_000) as rig, \
            open_harness("socketcan", vcan_fd_channel, 1_000_000, rates, fd=True, data_bitrate_bps=5_000_000) as harness:
        values = [0.012345, -0.5, 3.0, 0.0101, 0.25, -1.0, 0.001, -0.002, 0.003, 9.0, -8.0, 7.0]
        assert rig.writer.sensor_set(values, 0.0)
        received = 0
        for _ in range(100):
            received += harness.reader.poll(0.0, keep_fresh=True, block_s=0.05)
            if harness.reader.table.count:
                break
        assert harness.reader.decoder.rejected_total == 0, harness.reader.decoder.counts
        assert harness.reader.sample("TABLE_SENSORS").values == pytest.approx(values[:3], abs=1e-5)
        assert harness.reader.sample("FLOOR_ACCELS").values == pytest.approx(values[9:], abs=2e-3)


def test_fd_dry_run_at_2_khz_across_processes_over_vcan0(vcan_fd_channel, tmp_path):
    done = subprocess.run(
        [*HARNESS, "dry-run", "--interface", "socketcan", "--channel", vcan_fd_channel, "--lockstep", "--quiet",
         "--rate", "2000", "--set", "can.fd=true", "--duration", "1", "--log-dir", str(tmp_path), *SLOW_HOST],
        capture_output=True, text=True, timeout=900, cwd=REPO, stdin=subprocess.DEVNULL,
    )
    assert done.returncode == exit_codes.OK, done.stdout[-2000:] + done.stderr[-2000:]
    folders = [p for p in tmp_path.iterdir() if p.is_dir()]
    assert len(folders) == 1, folders
    metadata = json.loads((folders[0] / "metadata.json").read_text())
    assert metadata["outcome"] == "completed"
    assert metadata["can"]["interface"] == "socketcan" and metadata["can"]["fd"] is True
    assert metadata["rate_hz"] == 2000
    frames = list(can.LogReader(str(folders[0] / "can.log")))
    assert frames and all(m.is_fd and m.bitrate_switch for m in frames), "every frame on the bus is FD with BRS"
    sent = {m.arbitration_id for m in frames if not m.is_rx}
    received = {m.arbitration_id for m in frames if m.is_rx}
    assert {0x20, 0x50, 0x300} <= sent  # the harness: command, heartbeat, rig control
    assert {SENSOR_SET_ID, 0x40, 0x301} <= received  # the rig process: the sensor set, status, rig status
    assert not CLASSIC_SENSOR_IDS & received, "the rig sent the set, not the four classic sensor messages"
    sets = sum(1 for m in frames if m.is_rx and m.arbitration_id == SENSOR_SET_ID)
    assert sets >= 2000 * 1.0, "a sensor set every lockstep step of the 1 s record"
    assert all(m.channel == vcan_fd_channel for m in frames)

