"""How ``harness report`` links a run to its replay: the command that replays it, the replays found, or why it cannot be.

For a dry run or run, :func:`replay_links` gives the exact ``harness replay`` command, says that
its tick record (``ticks.bin``) makes an exact replay possible, and names the replays' run
folders (``harness replay --out``) found beside the run or among the runs reported; where the
run cannot be replayed (logged before replay existed, no ``ticks.bin``; an identification's
excitation; an incomplete record) it says so and why
(:func:`harness.recording.replayable.replay_refusal`). A replay's own run folder is named as the
replay of its run. Simulations have no replay and get no line.
"""

from __future__ import annotations

import json
import shlex
from collections.abc import Sequence
from pathlib import Path

from harness.recording.layout import METADATA_FILE
from harness.recording.reader import RunData
from harness.recording.replayable import REPLAYABLE_KINDS, replay_refusal


def replay_links(runs: Sequence[RunData]) -> list[str]:
    """The report's lines on replay, a few per run of the control loop or replay of one; [] if there is none.

    Parameters
    ----------
    runs : sequence of RunData
        The runs of the report, in order.
    """
    lines: list[str] = []
    for run in runs:
        lines += _run_lines(run, runs)
    return ["Replay:", *lines] if lines else []


def _run_lines(run: RunData, runs: Sequence[RunData]) -> list[str]:
    """What the report says of one run's replay."""
    replay_of = run.metadata.get("replay_of")
    if replay_of:
        changes = run.metadata.get("what_if") or []
        how = f"a what-if replay ({', '.join(changes)}; open loop)" if changes else "an exact replay"
        return [f"  {run.label}: {how} of {replay_of}"]
    if run.kind not in REPLAYABLE_KINDS:
        return []
    refusal = replay_refusal(run.path, run.metadata)
    if refusal:
        return [f"  {run.label}: replay is not possible: {refusal.removeprefix(f'{run.path}: ')}"]
    lines = [f"  {run.label}: its tick record (ticks.bin) makes an exact replay possible, tick for tick:",
             f"    {replay_command(run.path)}"]
    lines += [f"    replayed in {folder}" for folder in replays_of(run.path, runs)]
    return lines


def replay_command(folder: Path) -> str:
    """The exact command that replays the run folder ``folder`` (its path quoted for a POSIX shell)."""
    return f"harness replay {shlex.quote(str(folder))}"


def replays_of(folder: Path, runs: Sequence[RunData] = ()) -> list[Path]:
    """The run folders of replays of ``folder`` (their metadata's ``replay_of`` names it), in name order.

    Looked for among ``runs`` and where ``harness replay --out DIR`` puts them beside the run: the
    folders next to it and one level below those (``logs/whatif/<replay>`` beside ``logs/<run>``).
    Only ``metadata.json`` files are read.
    """
    target = folder.resolve()
    found = {run.path.resolve() for run in runs if _names(run.metadata.get("replay_of"), target)}
    for candidate in _beside(folder):
        if _names(_replay_of(candidate), target):
            found.add(candidate.resolve())
    return sorted(found)


def _beside(folder: Path) -> list[Path]:
    """The folders next to ``folder`` and one level below them (``folder`` itself excluded)."""
    parent = folder.resolve().parent
    try:
        siblings = [path for path in parent.iterdir() if path.is_dir() and path.resolve() != folder.resolve()]
    except OSError:
        return []
    nested = []
    for sibling in siblings:
        if not (sibling / METADATA_FILE).is_file():
            try:
                nested += [path for path in sibling.iterdir() if path.is_dir()]
            except OSError:
                continue
    return siblings + nested


def _replay_of(folder: Path) -> str | None:
    """The ``replay_of`` of the run folder ``folder``'s metadata, None where it has none or cannot be read."""
    try:
        metadata = json.loads((folder / METADATA_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    replay_of = metadata.get("replay_of") if isinstance(metadata, dict) else None
    return replay_of if isinstance(replay_of, str) else None


def _names(replay_of: object, target: Path) -> bool:
    """``replay_of`` names the folder ``target`` (a resolved path).

    A replay records its run's absolute path; one recorded relative (to wherever the replay ran)
    is matched by the run folder's name, which holds its start time.
    """
    if not isinstance(replay_of, str) or not replay_of:
        return False
    path = Path(replay_of)
    return path.resolve() == target if path.is_absolute() else path.name == target.name
