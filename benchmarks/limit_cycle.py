"""The 48 Hz limit cycle after the record (issue 31, item 6): the loop that sustains it, and the quiet tails.

The loop. After the motion ends the bearing sticks: its Bouc-Wen friction (Eq. 3-5) is a
spring of ``k0 = mu(0) W / D_y`` (46.6 MN/m) below the yield displacement, and the friction
estimator, run on the measured sliding displacement with its own yield displacement, is a
spring fed back positively through the loop's delay. Its loop gain ``L`` on the stuck base mat,
the design rule (a 6 dB gain margin) and the estimator's yield displacement it sets are in
harness/control/estimator_margin.py; the table gives ``L`` with the bearing's ``D_y`` (the
source's design, the 48 Hz limit cycle) and with the profile's
``control.estimator.yield_displacement_m``.

The tails. On the rig's twin with one period of asynchrony (real time), for the three records
and El Centro at 0.01 g: the load cell's RMS above 30 Hz over the quiet tail (22-30 s) against
its RMS over the record.

Usage: python benchmarks/limit_cycle.py [--records-dir DIR] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from harness.control.estimator_margin import (  # noqa: E402
    LOCKSTEP_DELAY_S,
    REALTIME_DELAY_S,
    estimator_loop,
    estimator_yield_displacement_m,
    phase_crossings,
)
from harness.profile import Profile, load_profile  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study  # noqa: E402

#: The records of the check: the three of SPEC 6b and El Centro at 0.01 g.
TAIL_CASES = (("el_centro", 0.34), ("hachinohe", 0.23), ("pacoima", 0.40), ("el_centro", 0.01))
#: The quiet tail (s of record time) and the band above the controller's (Hz).
TAIL_S, HIGH_HZ = (22.0, 30.0), 30.0


def high_band_share(t_s: np.ndarray, force_N: np.ndarray) -> tuple[float, float]:
    """The force's RMS above :data:`HIGH_HZ` over the quiet tail, in % of its RMS over the record; and that RMS (N)."""
    dt = float(np.median(np.diff(t_s)))
    tail = force_N[(t_s >= TAIL_S[0]) & (t_s <= TAIL_S[1])]
    spectrum = np.fft.rfft(tail - tail.mean())
    spectrum[np.fft.rfftfreq(tail.size, dt) < HIGH_HZ] = 0.0
    high = float(np.sqrt(np.mean(np.fft.irfft(spectrum, tail.size) ** 2)))
    overall = float(np.sqrt(np.mean((force_N - force_N.mean()) ** 2)))
    return 100.0 * high / overall, high


def tail_share(profile: Profile, record: str, pga_g: float, records_dir: str, delay_s: float) -> tuple[float, float, str]:
    """:func:`high_band_share` of one twin run with ``delay_s`` of asynchrony, and its outcome."""
    options = StudyOptions(record=record, records_dir=records_dir, pga_g=pga_g, time_scale=2.0, duration_s=30.0,
                           rig_effects=True, transport_delay_s=delay_s)
    case = run_study(profile, options).cases["controlled"]
    share, high = high_band_share(case.columns["t_s"], case.columns["force_measured_N"])
    return share, high, str(case.extra.get("outcome"))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"))
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE")
    args = parser.parse_args()
    profile = load_profile(None, overrides=args.overrides)
    print("| estimator D_y | loop | alpha | L(48.3 Hz) gain, phase | phase-0 crossing: f, gain |")
    print("|---|---|---|---|---|")
    yields = dict.fromkeys((profile.bearing.yield_displacement_m, estimator_yield_displacement_m(profile)))
    for own_yield in yields:
        for name, delay in (("lockstep, 3 ms", LOCKSTEP_DELAY_S), ("real time, 5 ms", REALTIME_DELAY_S)):
            for alpha in (0.0, 1.0):
                at48 = complex(estimator_loop(profile, np.array([48.3]), delay, alpha, own_yield)[0])
                crossings = ", ".join(f"{f:.1f} Hz, {g:.2f}" for f, g in phase_crossings(profile, delay, alpha, own_yield))
                print(f"| {own_yield * 1e3:.4g} mm | {name} | {alpha:g} | {abs(at48):.2f}, "
                      f"{math.degrees(math.atan2(at48.imag, at48.real)):+.0f} deg | {crossings} |")
    print()
    print("| record | feed-forward | RMS > 30 Hz in the tail, % of the record's RMS (N) | outcome |")
    print("|---|---|---|---|")
    # The oscillation detector would safe-stop the plain loop at the cycle's onset: it only indicates here.
    plain = ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0",
             "safety.force.oscillation_action=indicate"]
    for alpha_name, extra in (("none", plain), ("shipped", [])):
        case_profile = load_profile(None, overrides=[*args.overrides, *extra])
        for record, pga in TAIL_CASES:
            share, high, outcome = tail_share(case_profile, record, pga, args.records_dir, 1.0 / case_profile.control.rate_hz)
            print(f"| {record} {pga:.2f} g | {alpha_name} | {share:.1f} ({high:.0f}) | {outcome} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
