"""Tests for scripts/with-vcan (real SocketCAN vcan0, natively or via User-Mode Linux).

At most two real boots (each about 2-10 s): one runs a python-can snippet that
sends and receives frames on vcan0 (same process and across two processes),
the other checks that a failing command's status and output reach the host.
The host-side failure paths (boot failure, timeout, unavailable) are checked
with a fake UML kernel, so they run everywhere and boot nothing.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
WITH_VCAN = ROOT / "scripts" / "with-vcan"
BOOT_TIMEOUT = 300  # generous: the whole boot + command, killed by with-vcan itself

NATIVE = Path("/sys/class/net/vcan0").exists()
UML = shutil.which("linux.uml") is not None and any(
    Path("/usr/lib/uml/modules").glob("*/kernel/drivers/net/can/vcan.ko")
)
needs_vcan = pytest.mark.skipif(
    not (NATIVE or UML),
    reason="no native vcan0 and no User-Mode Linux (linux.uml + CAN modules); "
    "run scripts/install-vcan-deps or create vcan0 (see docs/VCAN.md)",
)


def run(args, *, env=None, timeout=BOOT_TIMEOUT + 30):
    return subprocess.run(
        [str(WITH_VCAN), *args],
        cwd=ROOT,
        env=env,
        stdin=subprocess.DEVNULL,  # as in CI
        capture_output=True,
        text=True,
        timeout=timeout,
    )


# A python-can round trip on vcan0: own echo in one process, then a frame from
# this process to a receiver running as a second, independent python process.
CAN_SNIPPET = textwrap.dedent(
    """
    import os, subprocess, sys
    import can

    RX = (
        "import can\\n"
        "with can.Bus(interface='socketcan', channel='vcan0') as bus:\\n"
        "    print('ready', flush=True)\\n"
        "    m = bus.recv(20.0)\\n"
        "    print('none' if m is None else '%x %s' % (m.arbitration_id, bytes(m.data).hex()), flush=True)\\n"
    )

    with can.Bus(interface="socketcan", channel="vcan0", receive_own_messages=True) as bus:
        bus.send(can.Message(arbitration_id=0x123, data=b"\\x01\\x02\\x03", is_extended_id=False))
        m = bus.recv(5.0)
        assert m is not None and m.arbitration_id == 0x123 and bytes(m.data) == b"\\x01\\x02\\x03", m
    print("SAME-PROCESS-OK", flush=True)

    rx = subprocess.Popen([sys.executable, "-c", RX], stdout=subprocess.PIPE, text=True)
    assert rx.stdout.readline().strip() == "ready"
    with can.Bus(interface="socketcan", channel="vcan0") as bus:
        bus.send(can.Message(arbitration_id=0x42, data=b"hi", is_extended_id=False))
    got = rx.stdout.readline().strip()
    assert rx.wait(30) == 0
    assert got == "42 6869", got
    print("TWO-PROCESS-OK", got, flush=True)
    print("WITH_VCAN=" + os.environ.get("WITH_VCAN", ""), "HARNESS_PROBE=" + os.environ.get("HARNESS_PROBE", ""))
    print("to-stderr", file=sys.stderr)
    """
)


@needs_vcan
def test_python_can_round_trip_on_vcan0():
    env = dict(os.environ, HARNESS_PROBE="passed-through")
    t0 = time.monotonic()
    r = run(["--timeout", str(BOOT_TIMEOUT), "--", sys.executable, "-c", CAN_SNIPPET], env=env)
    elapsed = time.monotonic() - t0
    assert r.returncode == 0, f"rc={r.returncode}\nstdout:\n{r.stdout}\nstderr:\n{r.stderr}"
    assert "SAME-PROCESS-OK" in r.stdout
    assert "TWO-PROCESS-OK 42 6869" in r.stdout
    # HARNESS_* variables reach the command; WITH_VCAN tells where it ran
    assert "HARNESS_PROBE=passed-through" in r.stdout
    assert ("WITH_VCAN=native" if NATIVE else "WITH_VCAN=uml") in r.stdout
    # stderr is kept apart from stdout
    assert "to-stderr" in r.stderr and "to-stderr" not in r.stdout
    print(f"boot + python-can round trip: {elapsed:.1f} s")


@needs_vcan
def test_exit_status_and_output_of_failing_command_reach_host(tmp_path):
    # runs in a subdirectory: with-vcan must cd there inside UML too
    script = "pwd; echo out-line; echo err-line >&2; ip link show vcan0 >/dev/null && echo vcan0-present; exit 3"
    r = subprocess.run(
        [str(WITH_VCAN), "--timeout", str(BOOT_TIMEOUT), "--", "sh", "-c", script],
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        capture_output=True,
        text=True,
        timeout=BOOT_TIMEOUT + 30,
    )
    assert r.returncode == 3, f"rc={r.returncode}\nstdout:\n{r.stdout}\nstderr:\n{r.stderr}"
    lines = r.stdout.splitlines()
    assert os.path.realpath(lines[0]) == os.path.realpath(tmp_path)
    assert "out-line" in lines and "vcan0-present" in lines
    assert "err-line" in r.stderr


# ---- no boot: help, check, and host-side failure paths with a fake UML ----


def test_help_documents_exit_codes():
    r = run(["--help"], timeout=30)
    assert r.returncode == 0
    for code in ("77", "124", "125"):
        assert f"\n  {code} " in r.stdout, code


def test_usage_errors_exit_2():
    assert run([], timeout=30).returncode == 2
    assert run(["--no-such-option", "--", "true"], timeout=30).returncode == 2
    assert run(["--timeout", "soon", "--", "true"], timeout=30).returncode == 2


def test_check_matches_what_is_available():
    r = run(["--check"], timeout=30)
    if NATIVE:
        assert (r.returncode, r.stdout.split(":")[0]) == (0, "native")
    elif UML:
        assert (r.returncode, r.stdout.split(":")[0]) == (0, "uml")
    else:
        assert (r.returncode, r.stdout.split(":")[0]) == (77, "unavailable")


def _fake_uml(tmp_path: Path, body: str) -> dict:
    kernel = tmp_path / "fake-linux.uml"
    kernel.write_text("#!/bin/sh\n" + body + "\n")
    kernel.chmod(0o755)
    mods = tmp_path / "mods" / "0.0" / "kernel" / "drivers" / "net" / "can"
    mods.mkdir(parents=True)
    (mods / "vcan.ko").write_bytes(b"")
    return dict(
        os.environ,
        WITH_VCAN_UML=str(kernel),
        WITH_VCAN_UML_MODULES=str(tmp_path / "mods"),
        TMPDIR=str(tmp_path),
    )


def test_unavailable_exits_77_with_one_clear_line(tmp_path):
    env = dict(os.environ, WITH_VCAN_UML=str(tmp_path / "no-such-linux.uml"))
    r = run(["--uml", "--", "true"], env=env, timeout=30)
    assert r.returncode == 77
    msg = r.stderr.strip().splitlines()
    assert len(msg) == 1 and "cannot provide vcan0" in msg[0]
    assert "install-vcan-deps" in msg[0] and "user-mode-linux" in msg[0]
    c = run(["--uml", "--check"], env=env, timeout=30)
    assert c.returncode == 77 and c.stdout.startswith("unavailable:")


def test_uml_that_never_runs_the_command_is_not_success(tmp_path):
    # exits 0 without running init (as a UML that fails to boot might)
    env = _fake_uml(tmp_path, "echo 'Kernel panic - fake'; exit 0")
    r = run(["--uml", "--", "true"], env=env, timeout=60)
    assert r.returncode == 125, r.stderr
    assert "failed to boot" in r.stderr and "Kernel panic - fake" in r.stderr
    # temporary run directory removed
    assert not list(tmp_path.glob("with-vcan.*"))


def _alive(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except FileNotFoundError:
        return False
    return stat.rsplit(")", 1)[1].split()[0] != "Z"


def test_timeout_kills_uml_and_exits_124(tmp_path):
    # the fake kernel and a child of it hang; both must be killed
    env = _fake_uml(
        tmp_path, f"echo $$ > {tmp_path}/kernel.pid; sleep 300 & echo $! > {tmp_path}/child.pid; wait"
    )
    t0 = time.monotonic()
    r = run(["--uml", "--timeout", "1", "--", "true"], env=env, timeout=60)
    assert r.returncode == 124, r.stderr
    assert "timed out" in r.stderr
    assert time.monotonic() - t0 < 15
    pids = [int((tmp_path / f).read_text()) for f in ("kernel.pid", "child.pid")]
    deadline = time.monotonic() + 5
    while any(_alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(_alive(p) for p in pids), pids
    assert not list(tmp_path.glob("with-vcan.*"))
