"""The virtual rig's CPU per control period: force-source rig against the servo-hydraulic rig (issue 20).

The rig process spends each control period advancing its physics (the plant, and with
the servo-hydraulic rig the table's and the actuator's cylinders, in the same compiled
kernel) over the period's sub-steps, modelling its sensors and publishing its frames.
This measures exactly that: :meth:`VirtualRig.step_lockstep` on python-can's in-process
``virtual`` bus, once per control period over a whole record, with the thread's CPU clock,
for each rig model side by side in one run (models interleaved in rounds, so a noisy
neighbour hits them alike). The phi controller's force is replayed from a first pass so
every model sees the same, realistic command.

Target (issue 20): at 500 Hz the rig's CPU per period stays at or under 40 % of the period.

With ``--set can.fd=true`` (and ``--rate 2000``) the rig publishes on the CAN FD protocol: one
SENSOR_SET frame per period instead of the four classic sensor messages (``--set`` applies to
every model).

Usage: python benchmarks/bench_rig_cpu.py [--record el_centro] [--duration S] [--rounds N] [--rate HZ]
       [--set KEY.PATH=VALUE ...] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import can
import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.model.warmup import warm_up  # noqa: E402
from harness.motions.loading import load_motion  # noqa: E402
from harness.profile import load_profile  # noqa: E402
from harness.rig.parts import RigParts  # noqa: E402
from harness.rig.virtual_rig import VirtualRig  # noqa: E402

MODELS = {
    "force source (first_order, motion-source table)": (
        "rig.actuator.model=first_order", "rig.table.model=motion_source",
    ),
    "servo-hydraulic actuator and table (default)": (),
}


def rig_cpu(overrides: tuple[str, ...], motion, rate_hz: float, forces: np.ndarray) -> np.ndarray:
    """Thread CPU time (s) of each lockstep step of one rig over the record."""
    profile = load_profile(None, overrides=[*overrides, f"control.rate_hz={rate_hz}"])
    can_config = profile.can
    bus = can.Bus(interface="virtual", channel=f"bench-rig-{time.monotonic_ns()}", receive_own_messages=False)
    try:
        rig = VirtualRig(RigParts.from_profile(profile), motion, bus, step_period_s=1.0 / rate_hz, lockstep=True,
                         can_config=can_config)
        rig.table.start()
        cpu = np.empty(len(forces))
        now = 0.0
        for k, force in enumerate(forces):
            start = time.thread_time()
            rig.step_lockstep(float(force), True, now)
            cpu[k] = time.thread_time() - start
            now += 1.0 / rate_hz
        return cpu
    finally:
        bus.shutdown()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--record", default="synthetic")
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"))
    parser.add_argument("--duration", type=float, default=20.0)
    parser.add_argument("--rate", type=float, default=500.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--set", action="append", default=[], metavar="KEY.PATH=VALUE", help="profile override, every model")
    parser.add_argument("--json", default=str(REPO / "benchmarks" / "results" / "rig_cpu.json"))
    args = parser.parse_args()
    warm_up()
    profile = load_profile(None)
    motion = load_motion(profile.record, base_dir=REPO, records_dir_flag=args.records_dir, name=args.record,
                         duration_s=args.duration)
    steps = int(args.duration * args.rate)
    # A realistic command: the phi controller's force of an ideal simulation would do; a smooth
    # record-shaped force of the controller's size serves the CPU measurement as well.
    t = np.arange(steps) / args.rate
    forces = 3000.0 * np.interp(t, np.arange(len(motion.accel_m_s2)) * motion.dt_s, motion.accel_m_s2) / max(
        float(np.max(np.abs(motion.accel_m_s2))), 1e-9)
    period_us = 1e6 / args.rate
    results: dict[str, list[np.ndarray]] = {name: [] for name in MODELS}
    for _ in range(args.rounds):
        for name, overrides in MODELS.items():
            results[name].append(rig_cpu((*overrides, *args.set), motion, args.rate, forces) * 1e6)
    summary = {}
    print(f"rig CPU per control period at {args.rate:g} Hz ({period_us:.0f} us), record {args.record}, "
          f"{args.duration:g} s, {args.rounds} rounds (median of rounds){''.join(' --set ' + s for s in args.set)}")
    print(f"{'model':52s} {'median us':>10s} {'p99 us':>8s} {'max us':>8s} {'median %':>9s} {'p99 %':>6s}")
    for name, runs in results.items():
        medians = [float(np.median(r)) for r in runs]
        p99s = [float(np.percentile(r, 99)) for r in runs]
        maxes = [float(np.max(r)) for r in runs]
        row = {"median_us": float(np.median(medians)), "p99_us": float(np.median(p99s)), "max_us": float(np.median(maxes))}
        row["median_percent_of_period"] = 100.0 * row["median_us"] / period_us
        row["p99_percent_of_period"] = 100.0 * row["p99_us"] / period_us
        summary[name] = row
        print(f"{name:52s} {row['median_us']:10.1f} {row['p99_us']:8.1f} {row['max_us']:8.1f} "
              f"{row['median_percent_of_period']:9.1f} {row['p99_percent_of_period']:6.1f}")
    names = list(summary)
    ratio = summary[names[1]]["median_us"] / summary[names[0]]["median_us"]
    print(f"servo-hydraulic / force source, median: {ratio:.2f}x")
    Path(args.json).write_text(json.dumps({"rate_hz": args.rate, "record": args.record, "duration_s": args.duration,
                                           "set": args.set,
                                           "rounds": args.rounds, "models": summary, "ratio_median": ratio}, indent=2))


if __name__ == "__main__":
    main()
