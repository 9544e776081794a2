"""The 2 kHz dry run on the CAN FD protocol, in real time: `harness dry-run --rate 2000 --set can.fd=true`.

No lockstep and no fake clock: the loop runs against the wall clock at 2 kHz, the virtual rig
(the default servo-hydraulic actuator and table) in its own process on the private ``seqpacket``
bus, every frame a CAN FD frame and the sensors one SENSOR_SET frame per period. Classic CAN
cannot carry this rate (the bus-load check refuses it, tests/unit/test_busload_fd.py). It must
complete on the machine that runs the suite, as the 500 Hz run of test_realtime_dry_run.py must
(a run the pre-flight refuses is run again, as there; marked ``realtime``: the serial pass).
"""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import can
import numpy as np
import pytest

from harness import exit_codes
from harness.recording import load_run
from harness.safety.lifecycle import State
from tests.integration.test_realtime_dry_run import DURATION_S, quiet_dry_run

pytestmark = pytest.mark.realtime

RATE_HZ = 2000
SENSOR_SET_ID, TABLE_ID, COMMAND_ID = 0x32, 0x30, 0x20


@pytest.fixture(scope="module")
def fd_run(tmp_path_factory) -> tuple[subprocess.CompletedProcess, Path]:
    return quiet_dry_run(tmp_path_factory.mktemp("realtime_fd"), "--rate", str(RATE_HZ), "--set", "can.fd=true",
                         rate_hz=RATE_HZ)


def test_the_2_khz_fd_real_time_dry_run_completes(fd_run):
    done, folder = fd_run
    assert done.returncode == exit_codes.OK, done.stdout[-3000:] + done.stderr[-3000:]
    assert "outcome: completed" in done.stdout
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["outcome"] == "completed"
    assert metadata["rate_hz"] == RATE_HZ
    assert metadata["can"]["fd"] is True and metadata["can"]["data_bitrate_bps"] == 5_000_000
    assert metadata["can"]["interface"] == "seqpacket"
    timing = metadata["summary"]["timing"]
    assert timing["lockstep"] is False  # the real-time path, not lockstep
    assert timing["longest_stall_s"] <= timing["stall_budget_s"]
    run = load_run(folder)
    running = run["state"].astype(int) == int(State.RUNNING)
    assert running.sum() >= DURATION_S * RATE_HZ * 0.95  # ticks at 2 kHz, the whole record
    assert np.abs(run["force_command_N"][running]).max() > 100.0  # the controller acted on a moving rig


def test_every_frame_of_the_run_was_fd_and_the_sensors_came_as_sets_at_the_rate(fd_run):
    _, folder = fd_run
    received_sets = sent_commands = 0
    first = last = None
    for msg in can.LogReader(str(folder / "can.log")):
        assert msg.is_fd and msg.bitrate_switch, f"classic frame 0x{msg.arbitration_id:x} in an FD run"
        assert msg.arbitration_id != TABLE_ID, "the classic sensor messages are not sent on the FD bus"
        if msg.arbitration_id == SENSOR_SET_ID and msg.is_rx:
            assert len(msg.data) == 32
            received_sets += 1
            first = msg.timestamp if first is None else first
            last = msg.timestamp
        elif msg.arbitration_id == COMMAND_ID and not msg.is_rx:
            sent_commands += 1
    assert first is not None and last is not None
    # A set in (nearly) every period: the rig's process, on the same two cores, skips a period now and then
    # (1891 sets/s seen on a quiet CI host); the run's sensor-age check bounds what it may skip, and the run
    # completed (the test above). The rate the rig holds is a benchmark figure (benchmarks/README.md, 2 kHz).
    assert 0.8 * RATE_HZ <= received_sets / (last - first) <= 1.02 * RATE_HZ
    assert sent_commands >= DURATION_S * RATE_HZ * 0.95
