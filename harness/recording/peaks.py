"""The peaks of a run folder read back, over its comparison window (:mod:`harness.signals.peaks`)."""

from __future__ import annotations

from harness.recording.reader import RunData
from harness.signals.peaks import Peaks, peak_responses, run_window


def run_peaks(run: RunData) -> Peaks:
    """Peaks of a run folder read back (:func:`harness.recording.load_run`), over its comparison window.

    The window is :func:`run_window` (the record and :data:`COMPARISON_TAIL_S`; every row of a
    run without a record). The weight is the metadata's ``total_weight_N``; a run is passive
    when its case or controller is ``"passive"``.
    """
    weight = run.metadata.get("total_weight_N")
    return peak_responses(run.signals, weight if isinstance(weight, (int, float)) else None, passive=run.is_passive,
                          window=run_window(run.metadata))
