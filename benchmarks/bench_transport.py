"""Round-trip latency of one CAN frame: the ``seqpacket`` bus across two processes beside python-can's ``virtual``.

Each case sends one 8-byte frame, an echo sends it back, and the round trip is timed
with ``perf_counter_ns`` from before ``send`` to after the echo's ``recv``; all cases
run side by side in one session, in this order:

1. ``seqpacket``, two processes, both polling: the echo process spins on
   ``recv(timeout=0)`` and echoes; the main process sends and spins on ``recv(timeout=0)``
   (each at its own pace, as two real-time loops that poll in their tick).
2. ``seqpacket``, two processes, both blocking: the echo blocks in ``recv(timeout=None)``,
   the main process in ``recv(timeout=1)``; every frame costs a wake-up on each side.
3. ``seqpacket``, one thread: two buses in this process, send / recv / send back / recv
   (the cost of the calls and syscalls alone, no scheduling).
4. ``virtual``, one thread: the same on python-can's in-process virtual bus (today's dry run).
5. ``virtual``, echo thread blocking in ``recv`` (a Notifier-style reader thread).

Usage: python benchmarks/bench_transport.py [--count N] [--warmup N] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Callable
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

import can  # noqa: E402

from drivers.transports import seqpacket  # noqa: E402

seqpacket.register()  # can.Bus(interface="seqpacket") below, with or without the installed entry point

STOP_ID = 0x7FF
FRAME = can.Message(arbitration_id=0x30, is_extended_id=False, data=bytes(range(8)))
STOP = can.Message(arbitration_id=STOP_ID, is_extended_id=False, data=b"")


def echo_main(channel: str, mode: str) -> None:
    """The echo process: send every frame back until STOP_ID; poll or block per ``mode``."""
    bus = can.Bus(interface="seqpacket", channel=channel)
    print("ready", flush=True)
    timeout = 0.0 if mode == "poll" else None
    recv, send = bus.recv, bus.send
    while True:
        msg = recv(timeout=timeout)
        if msg is None:
            continue
        if msg.arbitration_id == STOP_ID:
            break
        send(msg)
    bus.shutdown()


def stats_us(samples_ns: list[int]) -> dict[str, float]:
    values = np.asarray(samples_ns, dtype=float) / 1e3
    return {
        "median_us": float(np.median(values)),
        "p99_us": float(np.percentile(values, 99)),
        "max_us": float(values.max()),
        "count": int(values.size),
    }


def time_round_trips(
    send: Callable[[], None], wait_reply: Callable[[], can.Message | None], count: int, warmup: int
) -> list[int]:
    samples = []
    clock = time.perf_counter_ns
    for k in range(warmup + count):
        t0 = clock()
        send()
        reply = wait_reply()
        t1 = clock()
        if reply is None:
            raise RuntimeError(f"no echo for round trip {k}")
        if k >= warmup:
            samples.append(t1 - t0)
    return samples


def two_processes(mode: str, count: int, warmup: int) -> dict[str, float]:
    """Main process is the hub; an echo process joins; ``mode`` is ``poll`` or ``block`` for both sides."""
    channel = f"bench-{uuid.uuid4().hex}"
    bus = can.Bus(interface="seqpacket", channel=channel)
    code = (
        f"import sys; sys.path.insert(0, {str(REPO)!r}); "
        "from benchmarks.bench_transport import echo_main; echo_main(*sys.argv[1:])"
    )
    child = subprocess.Popen([sys.executable, "-c", code, channel, mode], stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        assert child.stdout is not None and child.stdout.readline().strip() == "ready"
        bus.send(FRAME)  # accepts the echo process
        if bus.recv(timeout=5.0) is None:
            raise RuntimeError("the echo process did not answer")
        if mode == "poll":
            recv = bus.recv

            def wait_reply() -> can.Message | None:
                deadline = time.monotonic() + 1.0
                while (msg := recv(timeout=0)) is None:
                    if time.monotonic() > deadline:
                        return None
                return msg
        else:
            def wait_reply() -> can.Message | None:
                return bus.recv(timeout=1.0)

        samples = time_round_trips(lambda: bus.send(FRAME), wait_reply, count, warmup)
        bus.send(STOP)
        child.wait(timeout=10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait()
        bus.shutdown()
    return stats_us(samples)


def one_thread(interface: str, count: int, warmup: int) -> dict[str, float]:
    """Two buses in this thread: A sends, B receives and sends back, A receives."""
    channel = f"bench-{uuid.uuid4().hex}"
    a = can.Bus(interface=interface, channel=channel)
    b = can.Bus(interface=interface, channel=channel)
    try:
        a.send(FRAME)  # the seqpacket hub accepts B here
        if b.recv(timeout=1.0) is None:
            raise RuntimeError(f"{interface}: no frame")

        def send() -> None:
            a.send(FRAME)

        def wait_reply() -> can.Message | None:
            msg = b.recv(timeout=0)
            if msg is None:
                return None
            b.send(msg)
            return a.recv(timeout=0)

        return stats_us(time_round_trips(send, wait_reply, count, warmup))
    finally:
        a.shutdown()
        b.shutdown()


def virtual_echo_thread(count: int, warmup: int) -> dict[str, float]:
    channel = f"bench-{uuid.uuid4().hex}"
    a = can.Bus(interface="virtual", channel=channel)
    b = can.Bus(interface="virtual", channel=channel)

    def echo() -> None:
        while True:
            msg = b.recv(timeout=None)
            if msg is None:
                continue
            if msg.arbitration_id == STOP_ID:
                return
            b.send(msg)

    thread = threading.Thread(target=echo, daemon=True)
    thread.start()
    try:
        return stats_us(time_round_trips(lambda: a.send(FRAME), lambda: a.recv(timeout=1.0), count, warmup))
    finally:
        a.send(STOP)
        thread.join(timeout=5)
        a.shutdown()
        b.shutdown()


CASES: list[tuple[str, Callable[[int, int], dict[str, float]]]] = [
    ("seqpacket, 2 processes, both poll recv(timeout=0)", lambda n, w: two_processes("poll", n, w)),
    ("seqpacket, 2 processes, both block in recv", lambda n, w: two_processes("block", n, w)),
    ("seqpacket, 1 thread, 2 buses", lambda n, w: one_thread("seqpacket", n, w)),
    ("virtual, 1 thread, 2 buses", lambda n, w: one_thread("virtual", n, w)),
    ("virtual, echo thread blocking in recv", virtual_echo_thread),
]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--count", type=int, default=20_000, help="timed round trips per case")
    parser.add_argument("--warmup", type=int, default=1_000, help="untimed round trips first")
    parser.add_argument("--json", default="", help="also write the results here")
    args = parser.parse_args()
    rows = []
    load_before = os.getloadavg()[0]
    for name, case in CASES:
        result = case(args.count, args.warmup)
        rows.append({"case": name, **result})
        print(json.dumps(rows[-1]), flush=True)
    load = (load_before, os.getloadavg()[0])
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        document = {"count": args.count, "warmup": args.warmup, "loadavg_1min": load, "rows": rows}
        Path(args.json).write_text(json.dumps(document, indent=2) + "\n")
    print(f"\nRound trip of one 8-byte frame, {args.count} timed after {args.warmup} warm-up (python-can {can.__version__}, "
          f"{os.cpu_count()} CPUs, 1-min load average {load[0]:.2f} before / {load[1]:.2f} after):\n")
    print("| case | median (us) | p99 (us) | max (us) |")
    print("|---|---|---|---|")
    for row in rows:
        print(f"| {row['case']} | {row['median_us']:.1f} | {row['p99_us']:.1f} | {row['max_us']:.0f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
