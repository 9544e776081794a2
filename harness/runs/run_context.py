"""What a dry run's console printed beside its data, kept in its run folder for ``harness report``.

After the session, a dry run simulates its passive reference and its rig twin; the console
prints the peaks beside them. :func:`write_dry_run_context` keeps those in the run folder so
the report shows the same: ``metadata.json`` gains a ``reference`` entry (the passive
reference's and the twin's peaks, SI, and the span they cover), and ``target_motion.csv``
holds the processed record the table was asked to follow (record time, SI), against which
the report draws the table motion the sensors measured; ``passive_reference.csv`` holds the
passive reference's drift histories (record time, SI), which the report overlays on the run's.
"""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from typing import Any

import numpy as np

from harness.recording.layout import METADATA_FILE
from harness.recording.metadata import write_json_atomic
from harness.signals.columns import TIME, count_stories, drift
from harness.simulation.case import CaseResult

#: The processed record the table was asked to follow (columns: :data:`TARGET_COLUMNS`).
TARGET_MOTION_FILE = "target_motion.csv"
TARGET_COLUMNS = ("t_s", "table_acceleration_m_s2", "table_velocity_m_s", "table_displacement_m")
#: The passive reference's drift histories (record time, SI): ``t_s``, ``drift_1_m`` ...
PASSIVE_REFERENCE_FILE = "passive_reference.csv"
#: The ``metadata.json`` key of the simulated references.
REFERENCE_KEY = "reference"


def reference_entry(passive: CaseResult | None, twin: CaseResult | None, span_s: float | None, lockstep: bool) -> dict:
    """The ``reference`` entry of ``metadata.json``: both simulated cases' peaks (SI) and what they cover.

    Parameters
    ----------
    passive, twin : CaseResult or None
        The simulated passive reference and the rig twin (``harness simulate --rig-effects``).
    span_s : float or None
        Record time a run that ended early covered (s); None: the whole record.
    lockstep : bool
        Whether the twin was simulated without the real-time asynchrony (one period of delay).
    """
    entry: dict[str, Any] = {"span_s": span_s, "twin_delay": "none (lockstep)" if lockstep else "one loop period"}
    if passive is not None:
        entry["passive_peaks"] = dataclasses.asdict(passive.peaks)
    if twin is not None:
        entry["twin_peaks"] = dataclasses.asdict(twin.peaks)
        entry["twin_outcome"] = twin.extra.get("outcome", "completed")
    return entry


def write_target_motion(folder: Path, motion: Any) -> Path:
    """Write the processed record (``motion``: a GroundMotion) as ``target_motion.csv`` in ``folder``."""
    path = folder / TARGET_MOTION_FILE
    table = np.column_stack([motion.t_s, motion.accel_m_s2, motion.velocity_m_s, motion.displacement_m])
    np.savetxt(path, table, delimiter=",", header=",".join(TARGET_COLUMNS), comments="", fmt="%.12g")
    return path


def write_passive_reference(folder: Path, passive: CaseResult) -> Path | None:
    """Write the passive reference's drift histories (:data:`PASSIVE_REFERENCE_FILE`); None if it has none."""
    names = [drift(j) for j in range(1, count_stories(tuple(passive.columns)) + 1)]
    if TIME not in passive.columns or not names:
        return None
    path = folder / PASSIVE_REFERENCE_FILE
    table = np.column_stack([passive.columns[TIME], *(passive.columns[name] for name in names)])
    np.savetxt(path, table, delimiter=",", header=",".join((TIME, *names)), comments="", fmt="%.12g")
    return path


def write_dry_run_context(
    run_path: Path, motion: Any, passive: CaseResult | None, twin: CaseResult | None, span_s: float | None,
    lockstep: bool,
) -> None:
    """Add the simulated references and the target motion to a finished dry run's folder.

    Parameters
    ----------
    run_path : Path
        The finished run folder (its ``metadata.json`` is rewritten atomically).
    motion : GroundMotion
        The processed record the table was asked to follow.
    passive, twin : CaseResult or None
    span_s : float or None
    lockstep : bool

    Raises
    ------
    OSError
        If the folder cannot be written (the run's own data are untouched).
    """
    folder = Path(run_path)
    write_target_motion(folder, motion)
    metadata_path = folder / METADATA_FILE
    metadata = json.loads(metadata_path.read_text(encoding="utf-8"))
    metadata[REFERENCE_KEY] = reference_entry(passive, twin, span_s, lockstep)
    metadata["target_motion_file"] = TARGET_MOTION_FILE
    if passive is not None and write_passive_reference(folder, passive) is not None:
        metadata["passive_reference_file"] = PASSIVE_REFERENCE_FILE
    write_json_atomic(metadata_path, metadata)
