"""No sustained oscillation above the controller's band after the record (issue 31, item 6).

On the rig's twin with one period of asynchrony (as a real-time run has it), the friction
estimator's pre-sliding stiffness, cancelled through the loop's delay, sustained a 48 Hz
limit cycle on a servo controller without feed-forward when the estimator used the bearing's
yield displacement (harness/control/estimator_margin.py derives the loop and the estimator's own
yield displacement that keeps it a 6 dB gain margin; benchmarks/limit_cycle.py). The check:
in the quiet tail (22-30 s) the load cell's RMS above 30 Hz is at most 5 % of its RMS over the record,
for the three records and at 0.01 g.
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.profile import load_profile
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study

#: The band above the controller's (Hz) and the quiet tail (s).
HIGH_HZ, TAIL_S = 30.0, (22.0, 30.0)
#: The most of the record's RMS the tail may hold above HIGH_HZ (%).
MAX_SHARE_PCT = 5.0
PLAIN_LOOP = ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0"]
#: The estimator on the bearing's own yield displacement (the source's design).
SOURCE_ESTIMATOR = ["control.estimator.yield_displacement_m=null"]
#: The oscillation detector (the backstop) would end the plain loop's run at the cycle's onset; it only
#: indicates here, so the tail shows what it stops.
INDICATE_OSCILLATION = ["safety.force.oscillation_action=indicate"]


def _tail_share(overrides: list[str], record: str, pga_g: float, records_dir) -> float:
    profile = load_profile(None, overrides=overrides)
    options = StudyOptions(record=record, records_dir=str(records_dir), pga_g=pga_g, time_scale=2.0, duration_s=30.0,
                           rig_effects=True, transport_delay_s=1.0 / profile.control.rate_hz)
    case = run_study(profile, options).cases["controlled"]
    assert case.extra["outcome"] == "completed"
    t, force = case.columns["t_s"], case.columns["force_measured_N"]
    tail = force[(t >= TAIL_S[0]) & (t <= TAIL_S[1])]
    spectrum = np.fft.rfft(tail - tail.mean())
    spectrum[np.fft.rfftfreq(tail.size, float(t[1] - t[0])) < HIGH_HZ] = 0.0
    high = np.sqrt(np.mean(np.fft.irfft(spectrum, tail.size) ** 2))
    return float(100.0 * high / np.sqrt(np.mean((force - force.mean()) ** 2)))


@pytest.mark.slow
@pytest.mark.parametrize(("record", "pga_g"), [("el_centro", 0.34), ("hachinohe", 0.23), ("pacoima", 0.40),
                                               ("el_centro", 0.01)])
def test_the_shipped_rig_has_no_sustained_oscillation_in_the_quiet_tail(records_dir, record: str, pga_g: float) -> None:
    assert _tail_share([], record, pga_g, records_dir) <= MAX_SHARE_PCT  # measured 1.4-3.0 %


@pytest.mark.slow
@pytest.mark.parametrize(("record", "pga_g"), [("el_centro", 0.34), ("hachinohe", 0.23), ("pacoima", 0.40),
                                               ("el_centro", 0.01)])
def test_without_the_feedforward_the_shipped_estimator_keeps_the_tail_quiet(records_dir, record: str, pga_g: float) -> None:
    assert _tail_share([*PLAIN_LOOP, *INDICATE_OSCILLATION], record, pga_g, records_dir) <= MAX_SHARE_PCT  # 1.2-2.9 %


@pytest.mark.slow
def test_without_the_feedforward_the_sources_estimator_fills_the_tail_with_the_48_hz_limit_cycle(records_dir) -> None:
    overrides = [*PLAIN_LOOP, *INDICATE_OSCILLATION, *SOURCE_ESTIMATOR]
    assert _tail_share(overrides, "el_centro", 0.01, records_dir) > 50.0  # measured 97 %
