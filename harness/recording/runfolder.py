"""One run folder per run: create it, record into it, finish it.

Typical use by the loop::

    folder = RunFolder.create(Path("logs"), "nceer_4dof", "dry-run", profile_data, columns,
                              metadata={"total_weight_N": 39854.0, "controller": "eq23"})
    folder.start()
    folder.record_event(0.0, "lifecycle", "armed")
    ...                      # every tick: folder.record_row(row); folder.record_frame(msg)
    folder.finish("completed", summary={...})

Until :meth:`RunFolder.finish` runs, ``metadata.json`` says ``"outcome": "incomplete"``;
a process that dies leaves it so, and everything flushed stays readable.

:meth:`RunFolder.finish` also says whether the record is whole: ``"record_complete"`` is
false when the writer failed (disk full, file-size limit) or a queue dropped anything, and
``metadata["recorder"]`` then counts what was lost (``lost``: rows, frames, events) and
gives the error. The loop stops the run safely when the writer fails (``record_lost``); the
command reports the loss and exits 3 (docs/SAFETY.md, "A lost record"). When even the final
rewrite of ``metadata.json`` fails, the outcome is written in place, in the blocks the file holds.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

import can
import numpy as np

from drivers.protocol.frame_flags import FrameTap
from harness.recording.layout import (
    CAN_FILE,
    EVENTS_FILE,
    FORMAT_NAME,
    FORMAT_VERSION,
    METADATA_FILE,
    PROFILE_FILE,
    SIGNALS_FILE,
    TICKS_FILE,
    Outcome,
    RunFolderError,
    RunKind,
    check_columns,
    check_kind,
    check_outcome,
)
from harness.recording.metadata import (
    environment,
    iso,
    plain_data,
    safe_name,
    utc_now,
    write_json_atomic,
    write_json_in_place,
    write_profile,
)
from harness.recording.writer import RunWriter


class RunFolder:
    """A run folder being recorded. Build it with :meth:`create`.

    Attributes
    ----------
    path : Path
        The folder.
    columns : tuple of str
        The signal columns, in row order.
    metadata : dict
        What ``metadata.json`` holds (updated by :meth:`finish`).
    """

    def __init__(self, path: Path, columns: tuple[str, ...], metadata: dict[str, Any], writer: RunWriter):
        self.path = path
        self.columns = columns
        self.metadata = metadata
        self._writer = writer
        self._finished = False
        #: The error that kept :meth:`finish` from rewriting ``metadata.json`` atomically, if any.
        self.metadata_error: OSError | None = None
        #: What :meth:`finish` wrote in place of the atomic rewrite then ("" if nothing).
        self.metadata_fallback = ""

    @classmethod
    def create(
        cls,
        log_dir: Path | str,
        profile_name: str,
        kind: RunKind,
        resolved_profile_data: Mapping[str, Any],
        columns: Sequence[str],
        *,
        metadata: Mapping[str, Any] | None = None,
        with_can: bool | None = None,
        row_capacity: int = 8192,
        frame_capacity: int = 32768,
        flush_interval_s: float = 0.05,
        tick_columns: Sequence[str] = (),
    ) -> RunFolder:
        """Create ``log_dir/<UTC start>_<profile>_<kind>/`` and its files; the writer is not started yet.

        Parameters
        ----------
        log_dir : Path or str
            Parent folder (created if missing), normally ``logs/``.
        profile_name : str
            Profile name, used in the folder name.
        kind : {"dry-run", "run", "simulation"}
            What sort of run this is.
        resolved_profile_data : mapping
            The fully resolved profile as plain data; written to ``profile.yaml``.
        columns : sequence of str
            Signal column names (see :mod:`harness.signals.columns`), ``t_s`` first.
        metadata : mapping, optional
            Extra metadata, e.g. ``total_weight_N``, ``stroke_soft_limit_m``,
            ``stroke_hard_limit_m``, ``force_limit_N``, ``record``, ``controller``, ``case``.
        with_can : bool, optional
            Keep a CAN log; default True except for simulations.
        row_capacity, frame_capacity : int
            Ring sizes (rows, frames) before the recorder drops.
        flush_interval_s : float
            Seconds between writer drains (s), at most 0.1.
        tick_columns : sequence of str
            The loop's tick record (:mod:`harness.loop.tick_log`), kept exact in ``ticks.bin`` for
            ``harness replay``; empty for none (simulations).

        Raises
        ------
        RunFolderError
            For an unknown kind or bad column names.
        """
        kind = check_kind(kind)
        names = check_columns(list(columns))
        if names[0] != "t_s":
            raise RunFolderError(f"found first column {names[0]!r}, expected 't_s'")
        started = utc_now()
        path = _unique_folder(Path(log_dir), f"{started:%Y-%m-%dT%H-%M-%S}_{safe_name(profile_name)}_{kind}")
        keep_can = (kind != "simulation") if with_can is None else with_can
        data = _initial_metadata(profile_name, kind, names, started, keep_can, metadata or {})
        if tick_columns:
            data["files"]["ticks"] = TICKS_FILE
            data["tick_columns"] = list(tick_columns)
        try:
            write_profile(path / PROFILE_FILE, resolved_profile_data)
            write_json_atomic(path / METADATA_FILE, data)
            writer = RunWriter(
                path,
                names,
                signals_name=SIGNALS_FILE,
                events_name=EVENTS_FILE,
                can_name=CAN_FILE if keep_can else None,
                row_capacity=row_capacity,
                frame_capacity=frame_capacity,
                flush_interval_s=flush_interval_s,
                ticks_name=TICKS_FILE if tick_columns else None,
                tick_columns=len(tick_columns),
            )
        except OSError as err:  # a disk that filled after the check of its room: refused, nothing armed
            raise RunFolderError(f"cannot write the run folder ({type(err).__name__}: {err}), expected a disk with "
                                 "room for the run's record", str(path)) from err
        return cls(path, names, data, writer)

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> RunFolder:
        """Start the writer thread; returns ``self``."""
        self._writer.start()
        return self

    def finish(self, outcome: Outcome, trip_reason: str | None = None, summary: Mapping[str, Any] | None = None) -> None:
        """Stop recording, write what is left and rewrite ``metadata.json`` atomically (idempotent).

        Parameters
        ----------
        outcome : {"completed", "stopped", "tripped", "refused", "error", "incomplete"}
            How the run ended.
        trip_reason : str, optional
            The interlock or detector that tripped, or the error message.
        summary : mapping, optional
            JSON data to keep under ``metadata["summary"]`` (peaks, timing statistics ...).
        """
        if self._finished:
            return
        outcome = check_outcome(outcome)
        self._finished = True
        self._writer.close()
        self.metadata.update(
            outcome=outcome,
            trip_reason=trip_reason,
            end_time=iso(utc_now()),
            summary=dict(summary) if summary is not None else None,
        )
        status = self.recorder_status()
        self.metadata["recorder"] = status
        self.metadata["record_complete"] = status["error"] is None and not any(status["lost"].values())
        try:
            write_json_atomic(self.path / METADATA_FILE, self.metadata)
        except OSError as err:  # the disk that failed the writer may fail this too
            self.metadata_error = err
            self.metadata_fallback = self._mark_in_place()

    def _mark_in_place(self) -> str:
        """After the atomic rewrite failed: at least mark the outcome, in the blocks metadata.json holds.

        Returns what was written (for :meth:`record_problem`); "" if nothing could be: the file then
        keeps ``"outcome": "incomplete"``.
        """
        path = self.path / METADATA_FILE
        if write_json_in_place(path, self.metadata):
            return "rewritten in place"
        slim = {key: value for key, value in self.metadata.items() if key != "summary"}
        if write_json_in_place(path, slim):
            return "outcome written in place, without the summary"
        return ""

    @property
    def record_complete(self) -> bool:
        """After :meth:`finish`: True if every row, frame and event and the final metadata reached the disk."""
        return bool(self.metadata.get("record_complete")) and self.metadata_error is None

    def record_problem(self) -> str:
        """After :meth:`finish`: what the record lost and why, in one line ("" if it is complete)."""
        if self.record_complete:
            return ""
        status = self.metadata.get("recorder") or self.recorder_status()
        lost = status["lost"]
        texts = []
        if any(lost.values()) or status["error"]:
            parts = [f"{lost['rows']} of {lost['rows'] + status['rows_written']} rows"]
            parts += [f"{lost[key]} {key}" for key in ("frames", "events", "ticks") if lost.get(key)]
            cause = status["error"] or "the recorder's queues were full"
            texts.append(f"lost {', '.join(parts)} ({cause})")
        if self.metadata_error is not None:
            kept = self.metadata_fallback or "it still says incomplete"
            texts.append(f"metadata.json not rewritten ({type(self.metadata_error).__name__}: {self.metadata_error}; "
                         f"{kept})")
        return "; ".join(texts)

    def recorder_status(self) -> dict[str, Any]:
        """Counts written, dropped and lost (see :meth:`RunWriter.lost`), and any writer error."""
        writer = self._writer
        error = writer.error
        return {
            "rows_written": writer.rows_written,
            "frames_written": writer.frames_written,
            "events_written": writer.events_written,
            **({"ticks_written": writer.ticks_written} if writer.ticks is not None else {}),
            "dropped": writer.drops(),
            "lost": writer.lost(),
            "longest_hold_s": writer.longest_hold_s,
            "error": f"{type(error).__name__}: {error}" if error is not None else None,
        }

    def __enter__(self) -> RunFolder:
        if not self._writer.running:
            self.start()
        return self

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        if exc is None:
            self.finish("completed")
        elif isinstance(exc, Exception):  # a trip is a finish("tripped", ...) by the session, never an exception
            self.finish("error", trip_reason=f"{type(exc).__name__}: {exc}")
        else:  # KeyboardInterrupt, SystemExit: keep the data, but the run did not finish
            self.finish("incomplete", trip_reason=type(exc).__name__)

    # ------------------------------------------------------------------ producer side (the tick)
    def record_row(self, values: Sequence[float] | np.ndarray) -> bool:
        """Queue one row (ndarray or tuple of ``len(columns)`` floats); never blocks; False if dropped."""
        return self._writer.record_row(values)

    def record_frame(self, msg: can.Message) -> bool:
        """Queue a sent or received CAN frame; never blocks; False if dropped."""
        return self._writer.record_frame(msg)

    def frame_taps(self) -> tuple[FrameTap, FrameTap]:
        """The taps a link's reader and writer call with every frame: ``(received, sent)``.

        Both queue the frame straight into the recorder's ring with the direction its flags give
        (:data:`drivers.protocol.frame_flags.RX` set by the side that saw the frame: SocketCAN marks frames
        from other processes of the same host ``is_rx=False``) and the wall-clock time the side
        gives (the writer stamps sent frames when they go out; the reader keeps the bus's timestamp).
        """
        frames = self._writer.frames
        return frames.push_fields, frames.push_fields

    def record_tick(self, values: np.ndarray) -> bool:
        """Queue one tick record of the loop (:mod:`harness.loop.tick_log`); never blocks; False if dropped."""
        return self._writer.record_tick(values)

    @property
    def frames_recorded(self) -> int:
        """Frames handed to the CAN log so far (dropped ones not counted): the next frame's line in ``can.log``."""
        return self._writer.frames.pushed

    def record_event(self, t: float | None, kind: str, name: str, detail: Any = None) -> bool:
        """Queue an event (``kind`` e.g. lifecycle/trip/warning/interlock); never blocks; False if dropped."""
        return self._writer.record_event(t, kind, name, detail)

    @property
    def rows_written(self) -> int:
        """Rows written to ``signals.csv`` and flushed so far."""
        return self._writer.rows_written

    @property
    def writer_error(self) -> BaseException | None:
        """The error that stopped the writer thread, if any (the tick should raise an alarm)."""
        return self._writer.error

    def drops(self) -> dict[str, int]:
        """Rows, frames and events dropped so far."""
        return self._writer.drops()


def check_log_dir(log_dir: Path | str) -> None:
    """Refuse a log directory where run folders cannot be created; call it before the bus opens.

    Raises
    ------
    RunFolderError
        Saying what is wrong with it (a file, below a file, not writable) and what was expected.
    """
    from harness.recording.writable import directory_problem

    problem = directory_problem(log_dir)
    if problem is not None:
        raise RunFolderError(f"log directory {problem}")


def _unique_folder(log_dir: Path, base: str) -> Path:
    try:
        log_dir.mkdir(parents=True, exist_ok=True)
    except OSError as err:  # checked before the run (check_log_dir); the disk can still change under it
        raise RunFolderError(f"cannot create the log directory ({err.strerror or err}), expected a writable directory",
                             str(log_dir)) from err
    for index in range(1, 1000):
        candidate = log_dir / (base if index == 1 else f"{base}-{index}")
        try:
            candidate.mkdir()
        except FileExistsError:
            continue
        except OSError as err:
            raise RunFolderError(f"cannot create a run folder in it ({err.strerror or err}), expected a writable directory",
                                 str(log_dir)) from err
        return candidate
    raise RunFolderError(f"found 999 folders named {base}*, expected a free name", str(log_dir))


def _initial_metadata(
    profile_name: str, kind: str, columns: tuple[str, ...], started: Any, keep_can: bool, extra: Mapping[str, Any]
) -> dict[str, Any]:
    data: dict[str, Any] = {
        "format": FORMAT_NAME,
        "format_version": FORMAT_VERSION,
        "profile_name": profile_name,
        "kind": kind,
        "start_time": iso(started),
        "end_time": None,
        "outcome": "incomplete",
        "trip_reason": None,
        "record_complete": None,
        "columns": list(columns),
        "files": {
            "profile": PROFILE_FILE,
            "signals": SIGNALS_FILE,
            "events": EVENTS_FILE,
            "can": CAN_FILE if keep_can else None,
        },
    }
    data.update(environment())
    reserved = set(data) - {"controller"}
    clash = sorted(reserved & set(extra))
    if clash:
        raise RunFolderError(f"found reserved metadata keys {clash}, expected them to be set by the recorder")
    data.update(plain_data(dict(extra)))
    return data
