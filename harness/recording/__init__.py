"""Run recording: one folder per run (profile, metadata, signals CSV, CAN log, events).

Public API::

    RunFolder.create(log_dir, profile_name, kind, resolved_profile_data, columns, metadata=...)
    folder.start(); folder.record_row(row); folder.record_frame(msg); folder.record_event(t, kind, name, detail)
    folder.finish(outcome, trip_reason=None, summary=None)
    write_simulation_case(folder, name, columns, arrays, metadata)
    load_run(path) -> RunData;  load_runs(paths) -> list[RunData]
"""

from harness.recording.layout import FORMAT_VERSION, RunFolderError
from harness.recording.reader import RunData, case_folders, load_run, load_runs
from harness.recording.ring import RecordingError
from harness.recording.runfolder import RunFolder
from harness.recording.simcase import write_simulation_case
from harness.signals.columns import canonical_columns, drift, floor_acceleration, unit_of

__all__ = [
    "FORMAT_VERSION",
    "RecordingError",
    "RunData",
    "RunFolder",
    "RunFolderError",
    "canonical_columns",
    "case_folders",
    "drift",
    "floor_acceleration",
    "load_run",
    "load_runs",
    "unit_of",
    "write_simulation_case",
]
