"""``harness simulate --out DIR``: both cases' time series as run folders for reports and plots.

Each case's ``metadata.json`` says what it was run with (record, controller, sampling, variant,
``--set`` overrides), so a report can label runs by what differs between them
(:mod:`harness.report.labels`); ``label`` is written only when the user gave one
(``--label``). For a profile of a shaking-table rig (one with a ``table`` section) the
stroke limits of its safety section go in too, for the stroke plot.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from harness.recording.simcase import write_simulation_case
from harness.rig.truth import METADATA_KEY as RIG_TRUTH
from harness.signals.columns import SIMULATED_CONTROL


def unsampled_end(columns: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``columns`` with the controller's internals NaN in the last row, where the controller did not sample.

    The simulator records the controller at its samples ``0 .. n-1``; row ``n`` is the end
    state, with no sample of the controller, so its internals there are "not computed"
    (NaN, as ``logs/README.md`` says), not 0.
    """
    ended = dict(columns)
    for name in SIMULATED_CONTROL:
        values = ended.get(name)
        if values is not None and values.size > 1 and values[-1] == 0.0:
            ended[name] = np.concatenate((values[:-1], [np.nan]))
    return ended


def case_metadata(result: Any, name: str, summary: Mapping[str, Any], label: str | None,
                  overrides: Sequence[str]) -> dict[str, Any]:
    """The ``metadata.json`` entries of one simulated case (``harness.recording.write_simulation_case`` adds the rest)."""
    profile = result.profile
    case = result.cases[name]
    metadata: dict[str, Any] = {
        "profile_name": profile.name,
        "record": summary["record"],
        "controller": "none" if name == "passive" else result.controller_name,
        "sampling": summary["sampling"],
        "variant": profile.variant or None,
        "overlay": profile.overlay_record(),
        "overrides": list(overrides),
        "total_weight_N": profile.structure.total_weight_N,
        "peaks": case.peaks.as_json(),
        "integrator_steps": case.integrator_steps,
        "wall_time_s": case.wall_time_s,
    }
    if RIG_TRUTH in summary:  # the rig twin ran on a rig that is not the design (harness/rig/truth.py)
        metadata[RIG_TRUTH] = summary[RIG_TRUTH]
    if label:
        metadata["label"] = f"{label} {name}"
    if profile.table is not None:  # a rig profile: its safety limits are the rig's own
        metadata["stroke_soft_limit_m"] = profile.safety.stroke.soft_limit_m
        metadata["stroke_hard_limit_m"] = profile.safety.stroke.hard_limit_m
        metadata["force_limit_N"] = profile.safety.force.max_force_N
    return metadata


def write_study_folders(result: Any, out_dir: str | Path, label: str | None = None, overrides: Sequence[str] = ()) -> Path:
    """Write ``DIR/passive/`` and ``DIR/controlled/`` (complete run folders, kind ``simulation``).

    Parameters
    ----------
    result : harness.runs.simulate.StudyResult
    out_dir : str or Path
    label : str, optional
        The user's label of the study (``--label``); each case's is this and its case name.
    overrides : sequence of str
        The ``--set KEY.PATH=VALUE`` items the profile was loaded with.

    Returns
    -------
    Path
        The case-set folder.
    """
    folder = Path(out_dir)
    summary = result.to_json()
    for name, case in result.cases.items():
        metadata = case_metadata(result, name, summary, label, overrides)
        write_simulation_case(folder, name, list(case.columns), unsampled_end(case.columns), metadata,
                              profile_data=result.profile.resolved_data())
    return folder
