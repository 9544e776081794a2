"""Whether a run folder's record lets ``harness replay`` run its ticks again, read from its metadata and files alone.

One place says which run folders replay refuses, and why: :mod:`harness.replay.recorded` refuses
them before anything is replayed, and ``harness report`` says of a run whether, and how, it can be
replayed (:mod:`harness.report.replay_link`). Only the metadata and the presence of the files are
read here; what the files hold (the tick record's shape, the CAN log's frames) is checked where
replay reads them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from harness.recording.layout import CAN_FILE, TICKS_FILE

#: The version of the replay record this harness reads (metadata ``replay.version``).
REPLAY_VERSION = 1
#: The kinds of run folder whose ticks replay can run again: runs of the control loop.
REPLAYABLE_KINDS = ("dry-run", "run")
#: How a run's loop must have ended for its ticks to be replayed.
REPLAYABLE_OUTCOMES = ("completed", "stopped", "tripped")


def replay_refusal(folder: Path, metadata: dict[str, Any]) -> str:
    """Why replay cannot run the ticks of the run folder ``folder`` again, "" where it can.

    Parameters
    ----------
    folder : Path
        The run folder (its ``ticks.bin`` and ``can.log`` are looked for there).
    metadata : dict
        Its ``metadata.json``.

    Returns
    -------
    str
        The reason, naming the folder, what was found and what was expected; "" for a replayable run.
    """
    kind = metadata.get("kind")
    if kind not in REPLAYABLE_KINDS:
        return f"{folder}: found a run of kind {kind!r}, expected a run of the control loop (dry-run or run)"
    replay = metadata.get("replay")
    if not isinstance(replay, dict) or not (folder / TICKS_FILE).is_file():
        return (f"{folder}: logged before replay existed: it has no tick record ({TICKS_FILE}, metadata 'replay'), so "
                "which frames each tick consumed is not known; only runs recorded by this harness version or later can "
                "be replayed")
    if replay.get("version") != REPLAY_VERSION:
        return f"{folder}: found replay record version {replay.get('version')!r}, expected {REPLAY_VERSION}"
    if not replay.get("profile_controller", False):
        return (f"{folder}: the run commanded an identification's excitation, not the profile's controller; replay "
                "rebuilds the profile's controller only")
    outcome = metadata.get("outcome")
    if outcome not in REPLAYABLE_OUTCOMES:
        return f"{folder}: found outcome {outcome!r}, expected a run whose loop finished (completed, stopped or tripped)"
    if not metadata.get("record_complete"):
        return (f"{folder}: its record is incomplete (metadata record_complete false): frames or ticks are missing, so "
                "the ticks cannot be replayed exactly")
    can = metadata.get("files", {}).get("can")
    if can != CAN_FILE or not (folder / CAN_FILE).is_file():
        return f"{folder}: found no {CAN_FILE}, expected the run's CAN log"
    return ""
