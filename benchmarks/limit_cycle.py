"""The 48 Hz limit cycle after the record (issue 31, item 6): the loop that sustains it, and the quiet tails.

The loop. After the motion ends the bearing sticks: its Bouc-Wen friction (Eq. 3-5) is a
spring of ``k0 = mu(0) W / D_y`` (46.6 MN/m) below the yield displacement. The friction
estimator runs the same Bouc-Wen on the measured sliding displacement and the controller
adds its estimate to the force, a spring of the same ``k0`` fed back positively: it cancels
the bearing's only through the loop's delay ``T``. With the actuator's command-to-force
response ``A(s)`` (force loop, valve, natural velocity feedback and the servo controller's
velocity feed-forward, SPEC 7a') and the base mat on the stuck bearing, the estimator's loop is

    L(s) = k0 e^(-sT) x_b / u_c,   x_b / u_c = w_f V / [(m_b s^2 + k0)(s + w_f V) - k_h (alpha V H - 1) s]

with ``V`` the valve, ``H`` the feed-forward's LVDT delay and filter. Positive feedback: a
crossing of phase 0 with ``|L| > 1`` is linearly unstable, and the estimator's saturation
(``|nu| <= 1``) turns it into a limit cycle of about ``D_y`` in displacement and ``2 mu W`` peak
to peak in force. The controller's own terms (``m_b p1 ydot_b``, ``phi k_b x_b``) are small at
these frequencies and left out; the superstructure's first story (0.73 MN/m) is small beside ``k0``.

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

from harness.profile import Profile, load_profile  # noqa: E402
from harness.runs.options import StudyOptions  # noqa: E402
from harness.runs.simulate import run_study  # noqa: E402

#: Delay around the estimator's loop (s): sensor 1 ms, half the 2 ms hold, command transport 1 ms ...
LOCKSTEP_DELAY_S = 0.003
#: ... and in real time one more period of asynchrony on average.
REALTIME_DELAY_S = 0.005
#: The records of the check: the three of SPEC 6b and El Centro at 0.01 g.
TAIL_CASES = (("el_centro", 0.34), ("hachinohe", 0.23), ("pacoima", 0.40), ("el_centro", 0.01))
#: The quiet tail (s of record time) and the band above the controller's (Hz).
TAIL_S, HIGH_HZ = (22.0, 30.0), 30.0


def estimator_loop(profile: Profile, freq_hz: np.ndarray, delay_s: float, feedforward_gain: float | None = None) -> np.ndarray:
    """``L(j 2 pi f)`` of the friction estimator's loop on the stuck bearing (module docstring)."""
    hydraulics = profile.rig.actuator.hydraulics
    cylinder, feedforward = hydraulics.cylinder, hydraulics.feedforward
    alpha = feedforward.gain if feedforward_gain is None else feedforward_gain
    bearing, m_b = profile.bearing, profile.structure.base_mass_kg
    k0 = (bearing.mu_max - bearing.mu_delta) * profile.structure.total_weight_N / bearing.yield_displacement_m
    w_f = 2.0 * math.pi * hydraulics.force_loop_bandwidth_hz
    w_v, z_v = 2.0 * math.pi * cylinder.valve_bandwidth_hz, cylinder.valve_damping_ratio
    s = 2j * math.pi * np.asarray(freq_hz, dtype=float)
    valve = w_v**2 / (s * s + 2.0 * z_v * w_v * s + w_v**2)
    sampled = feedforward.lvdt.delay_s + 0.5 * profile.rig.physics_substep_s  # the LVDT and the backward difference
    lvdt = np.exp(-s * sampled) / (1.0 + s / (2.0 * math.pi * feedforward.velocity_filter_hz))
    k_h = cylinder.hydraulic_stiffness_N_per_m
    plant = w_f * valve / ((m_b * s * s + k0) * (s + w_f * valve) - k_h * (alpha * valve * lvdt - 1.0) * s)
    return k0 * np.exp(-s * delay_s) * plant


def phase_crossings(profile: Profile, delay_s: float, feedforward_gain: float) -> list[tuple[float, float]]:
    """``(f Hz, |L|)`` where the loop's phase crosses 0 between 5 and 150 Hz."""
    freq = np.linspace(5.0, 150.0, 14_501)
    loop = estimator_loop(profile, freq, delay_s, feedforward_gain)
    phase = np.angle(loop)
    found = np.nonzero(np.diff(np.sign(phase)) != 0)[0]
    return [(float(freq[i]), float(abs(loop[i]))) for i in found if abs(phase[i]) < 0.5]


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
    print("| loop | alpha | L(48.3 Hz) gain, phase | phase-0 crossing: f, gain |")
    print("|---|---|---|---|")
    for name, delay in (("lockstep, 3 ms", LOCKSTEP_DELAY_S), ("real time, 5 ms", REALTIME_DELAY_S)):
        for alpha in (0.0, 1.0):
            at48 = complex(estimator_loop(profile, np.array([48.3]), delay, alpha)[0])
            crossings = ", ".join(f"{f:.1f} Hz, {g:.2f}" for f, g in phase_crossings(profile, delay, alpha))
            print(f"| {name} | {alpha:g} | {abs(at48):.2f}, {math.degrees(math.atan2(at48.imag, at48.real)):+.0f} deg "
                  f"| {crossings} |")
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
