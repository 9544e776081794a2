"""The table against the record the harness was told: is the table playing the test plan's record?

On a real rig the drive file loaded on the table controller is the table's business; the
harness is told the record in its profile or on its command line. When the two differ the
test is silently invalid: the controller still acts on the table motion it measures, but
every comparison with the record (the passive reference, the reductions) is wrong. This
check compares, online, the achieved table velocity (``xdot_0``, the table sensors as the
loop reads them) with the told record's velocity, from the first seconds of the record:
the cross-correlation's delay, the correlation there and the amplitude ratio
(:class:`~harness.motions.online_tracking.OnlineTracking`, the measures the report's
table-tracking section computes offline).

Verdicts (:func:`judge`; the bounds are derived in docs/SAFETY.md, "The table against its
record"):

- ``match``: correlation >= :data:`MATCH_CORRELATION`, delay within :data:`MATCH_DELAY_S`,
  amplitude ratio within :data:`MATCH_AMPLITUDE`: a healthy servo-hydraulic table;
- ``mismatch``: correlation < :data:`MISMATCH_CORRELATION`, or no correlation peak inside
  the +/- :data:`MAX_LAG_S` searched, or an amplitude ratio outside :data:`MISMATCH_AMPLITUDE`:
  the table plays another record (or the told one at another scale or time);
- ``marginal``: between the two: a warning.

It judges only once the told record has had enough motion to judge by (the gate, fixed
before the run from the record alone: :data:`MIN_RECORD_S` of record, an RMS velocity of at
least :data:`VELOCITY_FLOOR_M_S`, and :data:`MIN_HALF_CYCLES` swings beyond that floor), and
then every :data:`EVALUATE_EVERY_S` of record time, over the whole record played so far.

Cost in the tick: :meth:`TableRecordCheck.update` adds one sample to the running sums, a
compiled loop over the 2 * lags + 1 lags searched (101 at 500 Hz), without allocation;
every :data:`EVALUATE_EVERY_S` it also evaluates the sums, a few operations on arrays of
that length. Nothing is proportional to the samples of the record. A tick after a stall
fills the samples it skipped with the value it reads, at most as many as the stall budget
spans (a longer stall trips ``loop_stall``).
"""

from __future__ import annotations

import math
from enum import IntEnum

import numpy as np

from harness.motions.online_tracking import OnlineTracking
from harness.safety.detector_base import Detector
from harness.safety.events import Action
from harness.safety.health import TickHealth

#: Delays searched each way (s): five times the largest delay of a healthy table (MATCH_DELAY_S).
MAX_LAG_S = 0.1
#: Smallest correlation of a match, and the correlation below which the table plays something else.
MATCH_CORRELATION = 0.9
MISMATCH_CORRELATION = 0.5
#: Delay of the table behind its record for a match (s): a table's servo delay, the start frame's
#: period and the sensors' own delay (docs/SAFETY.md derives it).
MATCH_DELAY_S = (-0.010, 0.030)
#: Amplitude ratio (achieved over told) for a match, and outside which it is a mismatch.
MATCH_AMPLITUDE = (0.75, 1.33)
MISMATCH_AMPLITUDE = (0.5, 2.0)
#: The gate: no verdict before this much record time (s) ...
MIN_RECORD_S = 1.0
#: ... nor before the told record's RMS velocity over the record so far reaches this (m/s) ...
VELOCITY_FLOOR_M_S = 0.01
#: ... nor before it has swung beyond +/- VELOCITY_FLOOR_M_S this many times, alternately.
MIN_HALF_CYCLES = 8
#: Record time between two evaluations once the gate is open (s).
EVALUATE_EVERY_S = 0.5
_NO_MEASURES = (math.nan, math.nan, math.nan, False)
#: Why the check is off when the run was given no record (an identification): nothing to say about the table.
NO_RECORD = "no record to compare the table with"


class TableVerdict(IntEnum):
    """The check's verdict; the live console shows it by name (harness/loop/status.py keeps the same names)."""

    OFF = 0
    """No record to compare with (the run has none, or its record time is not the table's)."""
    WAITING = 1
    """Not judged yet: the record has not had enough motion (the gate)."""
    MATCH = 2
    MARGINAL = 3
    MISMATCH = 4


def judge(correlation: float, delay_s: float, amplitude_ratio: float, at_edge: bool) -> TableVerdict:
    """The verdict on one evaluation (MATCH, MARGINAL or MISMATCH; a NaN measure is a mismatch).

    Parameters
    ----------
    correlation : float
        Normalized cross-correlation at its peak.
    delay_s : float
        Delay of the achieved motion behind the told record (s).
    amplitude_ratio : float
        Least-squares gain of the achieved motion on the shifted record.
    at_edge : bool
        The peak lies at the end of the delays searched (no peak inside +/- MAX_LAG_S).
    """
    if not (correlation >= MISMATCH_CORRELATION) or at_edge:  # NaN: the table did not move while the record did
        return TableVerdict.MISMATCH
    if not (MISMATCH_AMPLITUDE[0] <= amplitude_ratio <= MISMATCH_AMPLITUDE[1]):
        return TableVerdict.MISMATCH
    if (correlation >= MATCH_CORRELATION and MATCH_DELAY_S[0] <= delay_s <= MATCH_DELAY_S[1]
            and MATCH_AMPLITUDE[0] <= amplitude_ratio <= MATCH_AMPLITUDE[1]):
        return TableVerdict.MATCH
    return TableVerdict.MARGINAL


def why(correlation: float, delay_s: float, amplitude_ratio: float, at_edge: bool) -> str:
    """Which bounds the measures miss, in words ("" for a match; allocates: for events and reports)."""
    misses = []
    if not (correlation >= MATCH_CORRELATION):
        limit = MISMATCH_CORRELATION if not (correlation >= MISMATCH_CORRELATION) else MATCH_CORRELATION
        misses.append(f"correlation {correlation:.2f} < {limit:.2f}")
    if at_edge:
        misses.append(f"no correlation peak within +/-{MAX_LAG_S * 1e3:.0f} ms")
    elif not (MATCH_DELAY_S[0] <= delay_s <= MATCH_DELAY_S[1]):
        misses.append(f"delay {delay_s * 1e3:+.1f} ms outside {MATCH_DELAY_S[0] * 1e3:+.0f}..{MATCH_DELAY_S[1] * 1e3:+.0f} ms")
    if not (MATCH_AMPLITUDE[0] <= amplitude_ratio <= MATCH_AMPLITUDE[1]):
        low, high = MISMATCH_AMPLITUDE if judge(1.0, 0.0, amplitude_ratio, False) is TableVerdict.MISMATCH else MATCH_AMPLITUDE
        misses.append(f"amplitude ratio {amplitude_ratio:.2f} outside {low:.2f}..{high:.2f}")
    return "; ".join(misses)


def gate_index(velocity_m_s: np.ndarray, dt_s: float) -> int | None:
    """First sample at which the told record has had enough motion to judge by; None if it never has.

    The later of: :data:`MIN_RECORD_S`; an RMS velocity since the start of at least
    :data:`VELOCITY_FLOOR_M_S`; :data:`MIN_HALF_CYCLES` alternate swings beyond +/- that floor.
    """
    v = np.asarray(velocity_m_s, dtype=float)
    first = int(math.ceil(MIN_RECORD_S / dt_s - 1e-9))
    mean_square = np.cumsum(v * v) / np.arange(1, v.size + 1)
    loud = np.flatnonzero(mean_square >= VELOCITY_FLOOR_M_S**2)
    beyond = np.flatnonzero(np.abs(v) > VELOCITY_FLOOR_M_S)
    signs = np.sign(v[beyond])
    swings = beyond[np.concatenate(([True], signs[1:] != signs[:-1]))] if beyond.size else beyond  # each swing's start
    if first >= v.size or loud.size == 0 or swings.size < MIN_HALF_CYCLES:
        return None
    return max(first, int(loud[0]), int(swings[MIN_HALF_CYCLES - 1]))  # each an index of v: first < v.size


class TableRecordCheck:
    """The state the two table checks share: the told record, the running sums and the verdict.

    Parameters
    ----------
    max_stall_s : float
        The stall budget (``safety.run.max_stall_s``, s): a tick fills at most the samples a stall
        this long skipped.

    Attributes
    ----------
    verdict : TableVerdict
        The latest evaluation's verdict (OFF, WAITING before the gate); MISMATCH is kept once reached.
    worst : TableVerdict
        The worst verdict of any evaluation of this run (OFF or WAITING before one).
    evaluations : int
        Evaluations so far.
    judged_at_s, worst_at_s : float
        Record time of the latest evaluation and of the one that gave :attr:`worst` (s; NaN before).
    off_reason : str
        Why there is no check (read only while :attr:`tracking` is None).
    """

    __slots__ = (
        "max_stall_s", "period_s", "max_catch_up", "tracking", "gate", "verdict", "worst", "evaluations", "judged_at_s",
        "worst_at_s", "worst_measures", "latest_measures", "off_reason", "_next_evaluation", "_last_value", "_finished",
    )

    def __init__(self, max_stall_s: float) -> None:
        self.max_stall_s = float(max_stall_s)
        self.period_s = math.nan
        self.max_catch_up = 1
        self.tracking: OnlineTracking | None = None
        self.gate: int | None = None
        self.off_reason = NO_RECORD
        #: (correlation, delay_s, amplitude_ratio, at_edge) of the evaluation that gave :attr:`worst`, and of the latest.
        self.worst_measures: tuple[float, float, float, bool] = _NO_MEASURES
        self.latest_measures: tuple[float, float, float, bool] = _NO_MEASURES
        self.reset()

    def expect(self, velocity_m_s: np.ndarray, dt_s: float, duration_s: float, period_s: float) -> None:
        """Compare the table with this record from the next arm on (before the run: allocates).

        Parameters
        ----------
        velocity_m_s : ndarray
            The told record's table velocity (m/s), sample ``i`` at ``i * dt_s``.
        dt_s : float
            Its sample step (s).
        duration_s : float
            Record time the run plays (s).
        period_s : float
            The loop's tick period (s): the record is compared on this grid.
        """
        if not (period_s > 0.0 and math.isfinite(period_s)):
            raise ValueError(f"the table check needs the loop's period, got {period_s!r} s")
        self.period_s = float(period_s)
        self.max_catch_up = int(self.max_stall_s / self.period_s) + 1
        samples = int(duration_s / self.period_s + 1e-9) + 1
        grid = np.arange(samples) * self.period_s
        record_t = np.arange(len(velocity_m_s)) * dt_s
        drive = np.interp(grid, record_t, np.asarray(velocity_m_s, dtype=float), right=0.0)
        self.tracking = OnlineTracking(drive, self.period_s, MAX_LAG_S)
        self.gate = gate_index(drive, self.period_s)
        self.reset()

    def ignore(self, reason: str) -> None:
        """No check for this run, and why (e.g. record time not the table's)."""
        self.tracking = None
        self.gate = None
        self.off_reason = reason
        self.reset()

    @property
    def gate_s(self) -> float:
        """Record time from which the check judges (s; NaN when the record never has enough motion, or off)."""
        return self.gate * self.period_s if self.gate is not None else math.nan

    def reset(self) -> None:
        """Forget the run (on arm and reset); the told record stays."""
        if self.tracking is not None:
            self.tracking.reset()
        self.verdict = TableVerdict.OFF if self.tracking is None else TableVerdict.WAITING
        self.worst = self.verdict
        self.evaluations = 0
        self.judged_at_s = self.worst_at_s = math.nan
        self.worst_measures = self.latest_measures = _NO_MEASURES
        self._next_evaluation = self.gate if self.gate is not None else -1
        self._last_value = 0.0
        self._finished = False

    def update(self, record_time_s: float, velocity_m_s: float) -> TableVerdict:
        """Add this tick's table velocity at ``record_time_s`` (NaN: no record playing) and judge when due."""
        tracking = self.tracking
        if tracking is None or self._finished or not record_time_s >= 0.0:
            return self.verdict
        n = int(record_time_s / self.period_s + 0.5)
        if n >= tracking.length:  # the record has ended: judge once more over the whole of it
            self._finished = True
            if self.gate is not None and tracking.count > self.gate:
                self._evaluate(tracking)
            return self.verdict
        filled = 0
        while tracking.count < n and filled < self.max_catch_up:  # ticks skipped by a stall: hold the last value
            tracking.add(self._last_value)
            filled += 1
        if tracking.count == n:
            tracking.add(velocity_m_s)
        self._last_value = velocity_m_s
        if self._next_evaluation >= 0 and tracking.count > self._next_evaluation:
            self._evaluate(tracking)
            self._next_evaluation += max(1, int(EVALUATE_EVERY_S / self.period_s + 0.5))
        return self.verdict

    def _evaluate(self, tracking: OnlineTracking) -> None:
        tracking.evaluate()
        verdict = judge(tracking.correlation, tracking.delay_s, tracking.amplitude_ratio, tracking.at_edge)
        self.evaluations += 1
        self.judged_at_s = (tracking.count - 1) * self.period_s
        self.verdict = verdict
        self.latest_measures = (tracking.correlation, tracking.delay_s, tracking.amplitude_ratio, tracking.at_edge)
        if verdict >= self.worst:
            self.worst = verdict
            self.worst_at_s = self.judged_at_s
            self.worst_measures = self.latest_measures
        if verdict is TableVerdict.MISMATCH:
            self._finished = True  # latched: the run stops

    def measures_text(self, latest: bool = False) -> str:
        """The worst (or the latest) evaluation's measures and what they miss, in words (allocates)."""
        correlation, delay_s, ratio, at_edge = self.latest_measures if latest else self.worst_measures
        at_s = self.judged_at_s if latest else self.worst_at_s
        text = (f"table velocity against the told record over {at_s:.1f} s of record: correlation "
                f"{correlation:.2f}, delay {delay_s * 1e3:+.1f} ms, amplitude ratio {ratio:.2f}")
        missed = why(correlation, delay_s, ratio, at_edge)
        return text + (f" ({missed})" if missed else "")

    def summary(self) -> dict:
        """The run's verdict and measures, for metadata.json and the outcome (allocates)."""
        tracking = self.tracking
        result: dict = {"verdict": self.worst.name.lower(), "signal": "table velocity xdot_0"}
        if tracking is None:
            result["reason"] = self.off_reason
            return result
        result["gate_s"] = None if self.gate is None else round(self.gate_s, 6)
        result["record_s_compared"] = round(tracking.count * self.period_s, 6)
        result["evaluations"] = self.evaluations
        if self.worst in (TableVerdict.OFF, TableVerdict.WAITING):
            needed = "it never has" if self.gate is None else f"it has from {self.gate_s:.2f} s"
            result["reason"] = (f"not judged: the told record had too little motion in the "
                                f"{tracking.count * self.period_s:.2f} s compared ({needed})")
            return result
        correlation, delay_s, ratio, at_edge = self.worst_measures
        result.update({"judged_at_s": round(self.worst_at_s, 6), "correlation": round(correlation, 4),
                       "delay_s": round(delay_s, 6), "amplitude_ratio": round(ratio, 4), "at_edge": at_edge,
                       "reason": self.measures_text()})
        if self.worst is not TableVerdict.MISMATCH:
            tracking.evaluate()  # the whole record compared: the final measures
            result["final"] = {"correlation": round(tracking.correlation, 4), "delay_s": round(tracking.delay_s, 6),
                               "amplitude_ratio": round(tracking.amplitude_ratio, 4)}
        return result


class TableRecordMismatch(Detector):
    """The table plays another record than the one the harness was told.

    The bounds are :data:`MISMATCH_CORRELATION`, :data:`MAX_LAG_S` and :data:`MISMATCH_AMPLITUDE`;
    the gate is :func:`gate_index`, evaluations every :data:`EVALUATE_EVERY_S` of record time. A safe
    stop, not a trip: the force ramps to zero and the table is stopped; the mismatch does not
    endanger the specimen, and a trip's force step would be the harsher act (docs/SAFETY.md).
    """

    NAME = "table_record_mismatch"
    ACTION = Action.SAFE_STOP
    DETECTS = (
        "table velocity xdot_0 against the told record's: correlation < 0.5, no peak within +/-100 ms, "
        "or amplitude ratio outside 0.5..2"
    )
    BOUND = "first evaluation after the record's gate (>= 1 s, 8 swings beyond 10 mm/s), then every 0.5 s of record"
    RESET = "DONE, then reset; the next arm compares afresh"

    __slots__ = ("check",)

    def __init__(self, check: TableRecordCheck) -> None:
        super().__init__()
        self.check = check

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """Add this tick's sample; True once the verdict is a mismatch."""
        return self.check.update(health.record_time_s, health.meas.table_velocity_m_s) is TableVerdict.MISMATCH

    def detail(self, health: TickHealth) -> str:
        """The measures and the bounds they miss."""
        return self.check.measures_text() + "; the table does not play the record the harness was told"

    def reset(self) -> None:
        """A new comparison from the start of the next record."""
        self.check.reset()


class TableRecordMarginal(Detector):
    """The table follows the told record, but not as a healthy table does: a warning.

    The verdict of :class:`TableRecordMismatch`'s comparison; the event, the console, the outcome
    and the report warn, and the reductions are flagged.
    """

    NAME = "table_record_marginal"
    ACTION = Action.INDICATE
    DETECTS = (
        "table velocity against the told record neither a match nor a mismatch: correlation 0.5..0.9, "
        "delay outside -10..+30 ms, or amplitude ratio in 0.5..0.75 or 1.33..2"
    )
    BOUND = "as table_record_mismatch"
    RESET = "none (judged again at every evaluation)"

    __slots__ = ("check",)

    def __init__(self, check: TableRecordCheck) -> None:
        super().__init__()
        self.check = check

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while the latest evaluation is marginal (runs after ``table_record_mismatch``, which updates the check)."""
        return self.check.verdict is TableVerdict.MARGINAL

    def detail(self, health: TickHealth) -> str:
        """The measures and the bounds they miss."""
        check = self.check
        return check.measures_text(latest=True) + "; the table follows the told record, but not as a healthy table does"
