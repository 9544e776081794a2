"""A writer killed mid-run (SIGKILL) leaves a readable folder, marked incomplete, with the flushed rows."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from harness.recording import load_run

REPO = Path(__file__).resolve().parents[2]

CHILD = textwrap.dedent(
    """
    import os, signal, sys, time
    import can
    from harness.recording import RunFolder

    run = RunFolder.create(sys.argv[1], "crash", "dry-run", {"loop": {"rate_Hz": 1000.0}}, ("t_s", "x_m", "f_N"))
    run.start()
    run.record_event(0.0, "lifecycle", "started")
    for i in range(N_ROWS):
        run.record_row((i * 0.001, i * 1e-4, -2.5 * i))
        frame = can.Message(timestamp=100.0 + i * 0.001, arbitration_id=0x101, data=bytes([i % 256]), is_extended_id=False)
        run.record_frame(frame)
    deadline = time.monotonic() + 20.0
    while run.rows_written < N_ROWS and time.monotonic() < deadline:
        time.sleep(0.005)
    print(run.path, flush=True)
    os.kill(os.getpid(), signal.SIGKILL)
    """
)


@pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX SIGKILL")
def test_killed_writer_leaves_an_incomplete_but_readable_folder(tmp_path: Path) -> None:
    n_rows = 300
    env = dict(os.environ, PYTHONPATH=str(REPO) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    child = subprocess.run(
        [sys.executable, "-c", CHILD.replace("N_ROWS", str(n_rows)), str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=60,
        env=env,
        cwd=REPO,
    )
    assert child.returncode == -signal.SIGKILL, child.stderr
    run = load_run(Path(child.stdout.strip()))
    assert run.incomplete
    assert run.outcome == "incomplete"
    assert run.metadata["end_time"] is None
    assert any("did not finish cleanly" in w for w in run.warnings)
    assert run.n_rows == n_rows
    np.testing.assert_allclose(run["f_N"], -2.5 * np.arange(n_rows))
    assert [e["name"] for e in run.events] == ["started"]
    assert run.can_log is not None
    assert len(run.can_log.read_text().splitlines()) == n_rows
