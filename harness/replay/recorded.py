"""What a run folder keeps for replay, read and checked: refused with a clear message when it cannot be replayed.

A run of the control loop recorded since replay exists holds, besides its profile, signals,
events and CAN log, the loop's tick record (``ticks.bin``, :mod:`harness.loop.tick_log`) and a
``replay`` entry in ``metadata.json``. Anything else (a run logged before, a simulation, a run
whose record is incomplete) is refused, before anything is replayed.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from harness.errors import HarnessError
from harness.loop.tick_log import CAN_FRAMES, TICK_COLUMNS
from harness.recording.layout import CAN_FILE, EVENTS_FILE, METADATA_FILE, PROFILE_FILE, TICKS_FILE
from harness.recording.replayable import replay_refusal
from harness.replay.canlog import LoggedFrame, read_can_log


class ReplayRefused(HarnessError, ValueError):
    """A run folder that cannot be replayed: recorded before replay existed, incomplete, or of a kind replay does not cover."""


@dataclass
class RecordedRun:
    """One run folder as replay reads it.

    Attributes
    ----------
    ticks : ndarray, shape (n_ticks, len(TICK_COLUMNS))
        The loop's tick record, one row per tick (the loop's start mark removed).
    loop_start_frame : int
        Frames of ``can.log`` before the loop's first tick (the traffic before the loop).
    frames : list of LoggedFrame
        Every frame of ``can.log``, in order.
    """

    path: Path
    metadata: dict[str, Any]
    profile_data: dict[str, Any]
    ticks: np.ndarray
    loop_start_frame: int
    frames: list[LoggedFrame]
    events: list[dict[str, Any]] = field(default_factory=list)

    @property
    def facts(self) -> dict[str, Any]:
        """The metadata's ``replay`` entry (duration, the table check, ...)."""
        return dict(self.metadata["replay"])

    @property
    def lockstep(self) -> bool:
        """The run was in lockstep with its rig."""
        return bool(self.metadata.get("lockstep"))


def load_recorded(path: Path | str) -> RecordedRun:
    """Read what ``path`` keeps for replay.

    Raises
    ------
    ReplayRefused
        Saying why the folder cannot be replayed and what was expected.
    """
    folder = Path(path)
    metadata = _metadata(folder)
    _check_replayable(folder, metadata)
    columns = list(metadata.get("tick_columns") or ())
    if columns != list(TICK_COLUMNS):
        raise ReplayRefused(f"{folder}: found tick columns {columns}, expected {list(TICK_COLUMNS)}")
    raw = np.fromfile(folder / TICKS_FILE, dtype="<f8")
    if raw.size == 0 or raw.size % len(columns):
        raise ReplayRefused(f"{folder / TICKS_FILE}: found {raw.size} values, expected whole records of {len(columns)}")
    ticks = raw.reshape(-1, len(columns))
    if not np.isnan(ticks[0, 0]):
        raise ReplayRefused(f"{folder / TICKS_FILE}: found no mark of the loop's start in its first record")
    frames = read_can_log(folder / CAN_FILE)
    if any(frame.is_error_frame for frame in frames):
        raise ReplayRefused(
            f"{folder}: its can.log holds error frames, whose error class the candump format does not keep: the "
            "bus's error accounting cannot be run again, so the ticks cannot be replayed exactly")
    end = int(ticks[-1, CAN_FRAMES])
    if end > len(frames):
        raise ReplayRefused(f"{folder}: the tick record reaches frame {end} of can.log, which holds {len(frames)}")
    import yaml

    profile_data = yaml.safe_load((folder / PROFILE_FILE).read_text(encoding="utf-8"))
    events = [json.loads(line) for line in (folder / EVENTS_FILE).read_text(encoding="utf-8").splitlines() if line.strip()]
    return RecordedRun(folder, metadata, profile_data, ticks[1:], int(ticks[0, CAN_FRAMES]), frames, events)


def _metadata(folder: Path) -> dict[str, Any]:
    file = folder / METADATA_FILE
    if not file.is_file():
        raise ReplayRefused(f"{folder}: found no {METADATA_FILE}, expected a run folder of `harness dry-run` or `harness run`")
    try:
        return json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise ReplayRefused(f"{file}: cannot read it as JSON ({err}), expected run metadata") from err


def _check_replayable(folder: Path, metadata: dict[str, Any]) -> None:
    """Refuse what replay cannot run again exactly, saying why (:func:`harness.recording.replayable.replay_refusal`)."""
    refusal = replay_refusal(folder, metadata)
    if refusal:
        raise ReplayRefused(refusal)
