"""``harness simulate --out DIR``: both cases' time series as run folders for reports and plots."""

from __future__ import annotations

from pathlib import Path

from harness.recording.simcase import write_simulation_case


def write_study_folders(result, out_dir: str | Path) -> Path:
    """Write ``DIR/passive/`` and ``DIR/controlled/`` (complete run folders, kind ``simulation``).

    Parameters
    ----------
    result : harness.runs.simulate.StudyResult
    out_dir : str or Path

    Returns
    -------
    Path
        The case-set folder.
    """
    folder = Path(out_dir)
    summary = result.to_json()
    profile = result.profile
    for name, case in result.cases.items():
        columns = list(case.columns)
        suffix = " (rig effects)" if name == "controlled" and result.rig_effects else ""
        metadata = {
            "profile_name": profile.name,
            "label": f"{profile.name} simulate {name}{suffix}",
            "record": summary["record"],
            "controller": "none" if name == "passive" else result.controller_name,
            "sampling": summary["sampling"],
            "total_weight_N": profile.structure.total_weight_N,
            "peaks": case.peaks.as_json(),
            "integrator_steps": case.integrator_steps,
            "wall_time_s": case.wall_time_s,
        }
        write_simulation_case(folder, name, columns, case.columns, metadata, profile_data=profile.resolved_data())
    return folder
