"""The disk a run folder needs, and the refusal of a log folder that cannot hold it (before anything starts).

A run records one row per tick (``signals.csv``) and every CAN frame sent or received
(``can.log``), for the whole loop: arming, settle, the record, its tail and the closing ticks.
Its size is bounded from the format of each line, at the loop's rate and the bus's message
rates, so a run that starts has room for its whole record; the refusal gives the estimate:

    bytes = (rows/s * row bytes + frames/s * frame line bytes) * span + record copy + fixed files

The bound is written in docs/SAFETY.md ("A lost record ends the run with a safe stop, and exits 3").
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass
from pathlib import Path

from harness.recording.layout import RunFolderError

#: Longest text of one value of a row, its comma included: ``%.12g`` of a double, ``-1.23456789012e-308`` (bytes).
VALUE_BYTES = 20
#: Longest candump line of a frame besides its data's hex digits and the channel's name:
#: ``(1795834658.245711) `` 20, `` `` 1, a 29-bit ID 8, ``#`` 1, CAN FD's ``#`` and flags digit 2, `` R`` and newline 3.
FRAME_LINE_BYTES = 35
#: The files besides the rows and frames: profile.yaml and metadata.json (twice, for the atomic rewrite,
#: each under 20 kB) and events.jsonl (its ring holds at most ``safety.run.event_capacity`` events) (bytes).
FIXED_BYTES = 1 << 20
#: Room kept beyond the estimate (a fraction of it): the folder's own blocks, a late rewrite of metadata.json.
MARGIN = 0.25


@dataclass(frozen=True)
class RunSize:
    """What a run folder will hold at most.

    Attributes
    ----------
    span_s : float
        Loop time recorded (s): the longest arming, settle, the record, its tail and the closing ticks.
    row_bytes_per_s : float
        ``signals.csv`` (bytes/s).
    frame_bytes_per_s : float
        ``can.log`` (bytes/s); 0 for a run without a CAN log.
    other_bytes : int
        The record's copy (``target_motion.csv``) and :data:`FIXED_BYTES` (bytes).
    """

    span_s: float
    row_bytes_per_s: float
    frame_bytes_per_s: float
    other_bytes: int

    @property
    def bytes_per_s(self) -> float:
        """Bytes recorded per second of loop time (bytes/s)."""
        return self.row_bytes_per_s + self.frame_bytes_per_s

    @property
    def needed_bytes(self) -> int:
        """The estimate with :data:`MARGIN` (bytes): what the log folder's file system must have free."""
        return math.ceil((self.bytes_per_s * self.span_s + self.other_bytes) * (1.0 + MARGIN))

    def summary(self) -> str:
        """The estimate in one line, for the refusal."""
        return (f"{_mb(self.needed_bytes)}: {self.bytes_per_s / 1e3:.0f} kB/s (rows {self.row_bytes_per_s / 1e3:.0f} kB/s, "
                f"CAN frames {self.frame_bytes_per_s / 1e3:.0f} kB/s) for up to {self.span_s:.1f} s of loop, "
                f"{_mb(self.other_bytes)} of other files, and {MARGIN:.0%} margin")


def run_size(
    n_columns: int, rows_per_s: float, span_s: float, frames_per_s: float = 0.0, frame_data_bytes: float = 0.0,
    channel: str = "", record_values: int = 0,
) -> RunSize:
    """Bound the size of a run folder.

    Parameters
    ----------
    n_columns : int
        Values per row of ``signals.csv``.
    rows_per_s : float
        Rows per second: the loop's rate (Hz).
    span_s : float
        Loop time recorded (s).
    frames_per_s : float
        Frames per second on the bus, both directions (Hz); 0 without a CAN log.
    frame_data_bytes : float
        Mean data bytes of those frames (bytes), weighted by their rates.
    channel : str
        The channel's name (written on every candump line).
    record_values : int
        Values of the record's copy in the folder (samples times columns).
    """
    row = rows_per_s * n_columns * VALUE_BYTES
    frames = frames_per_s * (FRAME_LINE_BYTES + len(channel) + 2 * frame_data_bytes)
    return RunSize(float(span_s), row, frames, FIXED_BYTES + record_values * VALUE_BYTES)


def check_log_space(log_dir: Path | str, size: RunSize) -> None:
    """Refuse a log folder whose file system cannot hold the run (before the rig starts or the bus opens).

    Raises
    ------
    RunFolderError
        With the free space found and the estimate expected.
    """
    folder = Path(log_dir)
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))  # created later if missing
    free = shutil.disk_usage(existing).free
    if free < size.needed_bytes:
        raise RunFolderError(
            f"log directory {folder} has {_mb(free)} free, expected room for this run's record, "
            f"about {size.summary()}; free some space or choose another --log-dir (nothing was started)"
        )


def _mb(n_bytes: float) -> str:
    return f"{n_bytes / 1e6:.1f} MB"
