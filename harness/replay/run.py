"""``harness replay``'s work: read the run folder, replay it (exactly, or with changes) and say what it found."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

from harness.loop.tick_log import T
from harness.replay.recorded import ReplayRefused, load_recorded


@dataclass
class ReplayOutput:
    """What a replay found: the lines to print, and whether an exact replay gave the run back bit for bit.

    Attributes
    ----------
    identical : bool or None
        Exact replay: every frame, event and the outcome are the run's. None for a what-if replay.
    seconds : float
        Wall-clock time the replay took, reading the run folder included (s).
    run_span_s : float
        Loop time the run spanned, its first tick to its last (s).
    """

    lines: list[str]
    identical: bool | None
    seconds: float
    run_span_s: float
    ticks: int = 0


def replay(path: Path | str, overrides: tuple[str, ...] = (), overlay: str | None = None,
           variant: str | None = None, out_dir: Path | str | None = None) -> ReplayOutput:
    """Replay the run folder ``path``: exactly without changes, open loop with them (what-if).

    ``out_dir``: also write the replayed ticks there as a run folder (``harness report path out_dir``
    overlays recorded and replayed).

    Raises
    ------
    ReplayRefused
        A folder that cannot be replayed (logged before replay existed, incomplete, ...), or a change
        that replay cannot apply to the recorded frames (the bus, the rate).
    ProfileError
        A change that makes an invalid profile.
    """
    from harness.canbus.link import prepare
    from harness.replay.compare import exact_lines, exact_report, whatif_lines, whatif_report
    from harness.replay.engine import replay_profile, run_replay

    started = time.perf_counter()
    recorded = load_recorded(path)
    run_profile = replay_profile(recorded)
    changed = bool(overrides) or overlay is not None or variant is not None
    profile = replay_profile(recorded, overrides, overlay, variant) if changed else run_profile
    if changed:
        _check_same_input(recorded.path, run_profile, profile)
    changes = tuple(([f"--overlay {overlay}"] if overlay else []) + [f"--set {item}" for item in overrides])
    result = run_replay(recorded, profile, Path(out_dir) if out_dir is not None else None, changes)
    protocol, _ = prepare(profile.can)
    span_s = float(recorded.ticks[-1, T] - recorded.ticks[0, T]) if len(recorded.ticks) else 0.0
    if not changed:
        report = exact_report(recorded, result)
        lines = exact_lines(report, recorded, protocol) + _written(result.out_path)
        return ReplayOutput(lines, report.identical_run, time.perf_counter() - started, span_s, len(result.ticks))
    lines = whatif_lines(whatif_report(recorded, result, protocol), changes) + _written(result.out_path)
    return ReplayOutput(lines, None, time.perf_counter() - started, span_s, len(result.ticks))


def _written(out_path: Path | None) -> list[str]:
    """The line naming the replayed run folder ``--out`` wrote (none without ``--out``)."""
    return [f"replayed signals written to {out_path}"] if out_path is not None else []


def _check_same_input(path: Path, run_profile, profile) -> None:
    """A what-if must consume the recorded frames as the run did: the same bus, protocol and loop rate."""
    if profile.can != run_profile.can:
        raise ReplayRefused(f"{path}: a what-if replay feeds the run's recorded frames, so it keeps the run's CAN "
                            "settings; a change under can.* cannot be replayed")
    if profile.control.rate_hz != run_profile.control.rate_hz:
        raise ReplayRefused(f"{path}: a what-if replay keeps the run's ticks, so it keeps its loop rate "
                            f"({run_profile.control.rate_hz:g} Hz)")
