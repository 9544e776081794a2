"""What the table check says: its reasons in words and the summary a run's metadata keeps.

The operator reads these when a table is stopped or flagged, and the report withholds or flags
reductions from the summary, so their content is tested value by value, not only their verdict.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.motions.tracking import tracking
from harness.safety.table_record import (
    MATCH_AMPLITUDE,
    MATCH_CORRELATION,
    MATCH_DELAY_S,
    MAX_LAG_S,
    MISMATCH_AMPLITUDE,
    MISMATCH_CORRELATION,
    TableRecordCheck,
    TableVerdict,
    why,
)

PERIOD_S = 0.002


def _record_velocity(seconds: float = 8.0, seed: int = 3) -> np.ndarray:
    """A band-limited random table velocity (0.5-4 Hz, 0.1 m/s RMS) on the tick grid."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, PERIOD_S)
    v = sum(rng.normal() * np.sin(2 * np.pi * f * t + rng.uniform(0, 6.28)) for f in rng.uniform(0.5, 4.0, 20))
    return 0.1 * v / np.std(v)


def _delayed(signal: np.ndarray, delay_s: float, gain: float = 1.0) -> np.ndarray:
    t = np.arange(signal.size) * PERIOD_S
    return gain * np.interp(t - delay_s, t, signal, left=0.0)


def _played(told: np.ndarray, table: np.ndarray) -> TableRecordCheck:
    check = TableRecordCheck(0.02)
    check.expect(told, PERIOD_S, (told.size - 1) * PERIOD_S, PERIOD_S)
    for n, value in enumerate(table):
        check.update(n * PERIOD_S, float(value))
    return check


# ---------------------------------------------------------------- why: each bound missed, in words

def test_a_match_misses_nothing() -> None:
    assert why(0.99, 0.008, 1.0, False) == ""
    assert why(MATCH_CORRELATION, MATCH_DELAY_S[0], MATCH_AMPLITUDE[0], False) == ""
    assert why(MATCH_CORRELATION, MATCH_DELAY_S[1], MATCH_AMPLITUDE[1], False) == ""


def test_a_low_correlation_names_the_bound_it_missed() -> None:
    marginal = (MATCH_CORRELATION + MISMATCH_CORRELATION) / 2
    assert why(marginal, 0.008, 1.0, False) == f"correlation {marginal:.2f} < {MATCH_CORRELATION:.2f}"
    assert why(MISMATCH_CORRELATION, 0.008, 1.0, False) == f"correlation {MISMATCH_CORRELATION:.2f} < {MATCH_CORRELATION:.2f}"
    low = MISMATCH_CORRELATION - 0.1
    assert why(low, 0.008, 1.0, False) == f"correlation {low:.2f} < {MISMATCH_CORRELATION:.2f}"
    assert why(math.nan, 0.008, 1.0, False) == f"correlation nan < {MISMATCH_CORRELATION:.2f}"


def test_a_delay_outside_the_band_is_named_with_the_band() -> None:
    band = f"{MATCH_DELAY_S[0] * 1e3:+.0f}..{MATCH_DELAY_S[1] * 1e3:+.0f} ms"
    assert why(0.99, 0.050, 1.0, False) == f"delay +50.0 ms outside {band}"
    assert why(0.99, -0.020, 1.0, False) == f"delay -20.0 ms outside {band}"


def test_no_peak_within_the_search_replaces_the_delay() -> None:
    edge = f"no correlation peak within +/-{MAX_LAG_S * 1e3:.0f} ms"
    assert why(0.99, MAX_LAG_S, 1.0, True) == edge, "at the edge the delay found means nothing: not named"
    assert why(0.99, 0.008, 1.0, True) == edge


def test_an_amplitude_outside_names_the_band_of_its_verdict() -> None:
    match = f"{MATCH_AMPLITUDE[0]:.2f}..{MATCH_AMPLITUDE[1]:.2f}"
    mismatch = f"{MISMATCH_AMPLITUDE[0]:.2f}..{MISMATCH_AMPLITUDE[1]:.2f}"
    assert why(0.99, 0.008, 0.6, False) == f"amplitude ratio 0.60 outside {match}"  # marginal: the match band
    assert why(0.99, 0.008, 1.5, False) == f"amplitude ratio 1.50 outside {match}"
    assert why(0.99, 0.008, 0.3, False) == f"amplitude ratio 0.30 outside {mismatch}"  # a mismatch: its band
    assert why(0.99, 0.008, 2.5, False) == f"amplitude ratio 2.50 outside {mismatch}"


def test_every_miss_is_listed_in_order() -> None:
    assert why(0.3, 0.050, 0.3, False) == "; ".join((
        f"correlation 0.30 < {MISMATCH_CORRELATION:.2f}",
        f"delay +50.0 ms outside {MATCH_DELAY_S[0] * 1e3:+.0f}..{MATCH_DELAY_S[1] * 1e3:+.0f} ms",
        f"amplitude ratio 0.30 outside {MISMATCH_AMPLITUDE[0]:.2f}..{MISMATCH_AMPLITUDE[1]:.2f}",
    ))


# ---------------------------------------------------------------- the summary kept in metadata.json

def test_a_matching_run_keeps_its_worst_evaluation_and_the_whole_record_compared() -> None:
    told = _record_velocity()
    table = _delayed(told, 0.008, 1.02)
    check = _played(told, table)
    assert check.worst is TableVerdict.MATCH
    summary = check.summary()
    assert set(summary) == {"verdict", "signal", "gate_s", "record_s_compared", "evaluations", "judged_at_s",
                            "correlation", "delay_s", "amplitude_ratio", "at_edge", "reason", "final"}
    assert summary["verdict"] == "match" and summary["signal"] == "table velocity xdot_0"
    assert summary["gate_s"] == pytest.approx(check.gate_s, abs=1e-6) and 1.0 <= summary["gate_s"] < 8.0
    assert summary["record_s_compared"] == pytest.approx(told.size * PERIOD_S, abs=1e-6)
    assert summary["evaluations"] == check.evaluations > 1
    assert summary["judged_at_s"] == pytest.approx(check.worst_at_s, abs=1e-6)
    correlation, delay_s, ratio, at_edge = check.worst_measures
    assert (summary["correlation"], summary["delay_s"], summary["amplitude_ratio"], summary["at_edge"]) == (
        round(correlation, 4), round(delay_s, 6), round(ratio, 4), at_edge)
    assert summary["reason"] == check.measures_text() and "correlation" in summary["reason"]
    # the final measures are those of the whole record, as an offline comparison gives them
    offline = tracking(table, told, PERIOD_S, MAX_LAG_S)
    final = summary["final"]
    assert final == {"correlation": round(check.tracking.correlation, 4), "delay_s": round(check.tracking.delay_s, 6),
                     "amplitude_ratio": round(check.tracking.amplitude_ratio, 4)}, "the whole record, rounded as kept"
    assert final["delay_s"] == pytest.approx(offline.delay_s, abs=PERIOD_S / 2)
    assert final["delay_s"] == pytest.approx(0.008, abs=PERIOD_S)
    assert final["amplitude_ratio"] == pytest.approx(offline.amplitude_ratio, rel=0.01)
    assert final["correlation"] == pytest.approx(offline.correlation, abs=0.01)


def test_a_mismatch_keeps_the_measures_that_stopped_the_run_and_no_final() -> None:
    told = _record_velocity(seed=3)
    check = _played(told, _delayed(_record_velocity(seed=11), 0.008))
    summary = check.summary()
    assert summary["verdict"] == "mismatch" and "final" not in summary
    assert summary["evaluations"] == 1 and summary["judged_at_s"] == pytest.approx(check.gate_s, abs=2 * PERIOD_S)
    assert summary["record_s_compared"] < 8.0 / 2, "the comparison stopped at the mismatch"
    assert summary["reason"] == check.measures_text()
    assert summary["reason"].endswith(f"({why(*check.worst_measures)})")


def test_a_marginal_run_names_what_it_missed_and_keeps_the_final_measures() -> None:
    told = _record_velocity()
    check = _played(told, _delayed(told, 0.008, 0.6))
    summary = check.summary()
    assert summary["verdict"] == "marginal" and summary["amplitude_ratio"] == pytest.approx(0.6, abs=0.02)
    assert summary["reason"].endswith(f"(amplitude ratio {summary['amplitude_ratio']:.2f} outside "
                                      f"{MATCH_AMPLITUDE[0]:.2f}..{MATCH_AMPLITUDE[1]:.2f})")
    assert summary["final"]["amplitude_ratio"] == pytest.approx(0.6, abs=0.02)


def test_measures_in_words_give_the_worst_or_the_latest_evaluation() -> None:
    told = _record_velocity()
    table = _delayed(told, 0.008)
    table[: int(3.0 / PERIOD_S)] *= 0.6  # marginal at first, a match once the amplitude recovers
    check = _played(told, table)
    assert check.worst is TableVerdict.MARGINAL and check.verdict is TableVerdict.MATCH
    worst, latest = check.measures_text(), check.measures_text(latest=True)
    assert worst.startswith(f"table velocity against the told record over {check.worst_at_s:.1f} s of record: correlation ")
    assert latest.startswith(f"table velocity against the told record over {check.judged_at_s:.1f} s of record: ")
    correlation, delay_s, ratio, _ = check.latest_measures
    assert f"correlation {correlation:.2f}, delay {delay_s * 1e3:+.1f} ms, amplitude ratio {ratio:.2f}" in latest
    assert "(" not in latest and latest.endswith(f"amplitude ratio {ratio:.2f}"), "a match misses nothing"
    assert worst.endswith(")") and "amplitude ratio" in worst.split("(")[-1]


def test_a_run_never_judged_says_why_and_from_when_it_would_have_been() -> None:
    told = _record_velocity()
    check = _played(told, _delayed(told, 0.008)[: int(0.8 / PERIOD_S)])  # stopped before the gate
    summary = check.summary()
    assert summary["verdict"] == "waiting" and summary["evaluations"] == 0
    assert summary["reason"] == (f"not judged: the told record had too little motion in the "
                                 f"{summary['record_s_compared']:.2f} s compared (it has from {check.gate_s:.2f} s)")
    assert "judged_at_s" not in summary and "final" not in summary

    quiet = np.full(2000, 1e-4)  # a record that never moves enough to judge by
    never = _played(quiet, quiet).summary()
    assert never["gate_s"] is None and never["reason"].endswith("(it never has)")
