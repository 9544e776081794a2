"""What the table check (harness/safety/table_record.py) means for a run's numbers, in words.

A run whose table did not follow the record the harness was told has no reductions: they
compare the specimen's response to another record with a passive reference under the told
one. :func:`table_check` reads the check's summary (``metadata.json``: ``summary.table_record``,
or :attr:`harness.loop.runner.LoopResult.table_record`) and says, for the console, the report
and the peak tables, what to print:

- ``mismatch``: the reductions are withheld (shown as absent), with the reason; a table that
  moved against its record (a negative amplitude ratio, and a correlation at most
  -:data:`REVERSED_CORRELATION` at the best of the delays searched) is named as a reversed table
  sensor (or drive file);
- ``marginal``: the reductions are shown, flagged as doubtful, with the reason;
- ``waiting`` (the record never had enough motion to judge): a warning, never a silent pass:
  neither the record the table played nor the table sensor's polarity was checked
  (:data:`NOT_JUDGED_WARNING`);
- otherwise they are shown as they are.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from harness.safety.table_record import MISMATCH_CORRELATION, NO_RECORD

#: Metadata key (inside ``summary``) of the table check's summary.
SUMMARY_KEY = "table_record"
#: A mismatch whose best correlation over the delays searched is this negative or more, with a negative
#: amplitude ratio, is the told record played against its sign (a table sensor of reversed polarity, or a
#: negated drive file): every delay anti-correlates. Another record's best correlation was -0.13 or more in
#: the 12 pairs of shipped records (docs/SAFETY.md, "The table against its record"); white noise 0.5-5 Hz
#: played reversed gives -0.68.
REVERSED_CORRELATION = MISMATCH_CORRELATION
#: What a check that never judged leaves unchecked, and the level at which commissioning step 1 judges
#: (README, "Commissioning a rig": ``white_noise:0.5-5:0.05`` passes the gate at 7.1 s of record).
NOT_JUDGED_WARNING = (
    "WARNING: neither the record the table played nor the table sensor's polarity was checked. A "
    "commissioning sign check needs a record the check can judge: 8 swings beyond 10 mm/s of table "
    "velocity (white_noise:0.5-5:0.05 for 20 s judges from 7.1 s; README, Commissioning a rig)"
)


@dataclass(frozen=True)
class TableCheck:
    """The table check's verdict on a run and what follows for its numbers.

    Attributes
    ----------
    verdict : str
        ``match``, ``marginal``, ``mismatch``, ``waiting`` (not judged: too little record
        motion), ``off`` (no check), or ``unknown`` (a run without the check's summary).
    line : str
        One line for the outcome and the report ("" for ``unknown``).
    withheld : str
        Why the run's reductions are not shown ("" when they are).
    flagged : str
        Why the run's reductions are shown but doubtful ("" when they are not).
    """

    verdict: str
    line: str = ""
    withheld: str = ""
    flagged: str = ""


def table_check(summary: Mapping[str, Any] | None) -> TableCheck:
    """The :class:`TableCheck` of the check's summary dict (None or empty: ``unknown``)."""
    if not isinstance(summary, Mapping) or not summary.get("verdict"):
        return TableCheck("unknown")
    verdict = str(summary["verdict"])
    reason = str(summary.get("reason", ""))
    if verdict == "mismatch":
        if _reversed(summary):
            reason += ("; the table moved against its record at every delay searched: a table sensor of reversed "
                       "polarity (displacement and velocity flipped together), or a negated drive file")
        withheld = ("the table did not play the record the harness was told (table check: mismatch); "
                    "reductions against the told record's passive reference would be meaningless")
        return TableCheck(verdict, f"table check: MISMATCH: {reason}; the run was stopped and its reductions are not "
                                   "shown. Check the drive file loaded on the table controller against the test plan",
                          withheld=withheld)
    if verdict == "marginal":
        flagged = ("the table followed the told record, but not as a healthy table does (table check: marginal): "
                   "the reductions compare with the told record's passive reference and may be off")
        return TableCheck(verdict, f"table check: marginal: {reason}; the reductions are doubtful. Check the table's "
                                   "drive (scale, delay) against the test plan", flagged=flagged)
    if verdict == "match":
        final = summary.get("final") if isinstance(summary.get("final"), Mapping) else None
        if final is not None:
            compared = summary.get("record_s_compared")
            over = f" over {compared:.1f} s of record" if isinstance(compared, (int, float)) else ""
            reason = (f"table velocity against the told record{over}: correlation {final['correlation']:.2f}, "
                      f"delay {final['delay_s'] * 1e3:+.1f} ms, amplitude ratio {final['amplitude_ratio']:.2f}")
        return TableCheck(verdict, f"table check: match ({reason})")
    if verdict == "waiting":
        return TableCheck(verdict, f"table check: {reason}. {NOT_JUDGED_WARNING}")
    if not reason or reason == NO_RECORD:  # a run with no record (an identification): nothing to say
        return TableCheck(verdict)
    return TableCheck(verdict, f"table check: off ({reason})")


def _reversed(summary: Mapping[str, Any]) -> bool:
    """True when a mismatch's measures say the table played the record against its sign."""
    correlation, ratio = summary.get("correlation"), summary.get("amplitude_ratio")
    if not (isinstance(correlation, (int, float)) and isinstance(ratio, (int, float))):
        return False
    return correlation <= -REVERSED_CORRELATION and ratio < 0.0


def run_table_check(metadata: Mapping[str, Any]) -> TableCheck:
    """The :class:`TableCheck` of a run folder's ``metadata.json`` contents."""
    summary = metadata.get("summary")
    return table_check(summary.get(SUMMARY_KEY) if isinstance(summary, Mapping) else None)
