"""The recorder thread: drains the rings and the event queue into the run folder's files.

The real-time tick only calls :meth:`RunWriter.record_row`, :meth:`record_frame` and
:meth:`record_event`; each copies into preallocated storage (or a bounded queue for
the rare events) and returns at once, counting a drop when full. A daemon thread
wakes every ``flush_interval_s`` (default 50 ms, so data reach the OS within about
100 ms even with a late wake-up), writes every pending row, frame and event, and
flushes the files; it fsyncs them every ``fsync_interval_s`` so a power cut loses at
most that much. It formats in chunks of :data:`CHUNK` rows and yields the GIL
between chunks, so the tick never waits long for the interpreter. If the disk
fails (full, or the file-size limit: ``OSError`` ENOSPC, EFBIG), the thread stops
writing, keeps the error in :attr:`RunWriter.error`, tries to note a
``recorder_failed`` event in the event file, and the tick carries on (rows then
drop and are counted). :meth:`RunWriter.lost` counts, after :meth:`RunWriter.close`,
every row, frame and event the tick handed over that did not reach the files.
"""

from __future__ import annotations

import math
import os
import queue
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any, BinaryIO, TextIO

import can
import numpy as np

import harness.recording.strict_json as strict_json
from harness.recording.metadata import json_default
from harness.recording.ring import FrameRing, RowRing

#: ``%.12g`` keeps microseconds on a clock of 10^5 s and 12 significant digits on every sensor.
VALUE_FORMAT = "%.12g"

#: Rows or frames formatted between GIL releases. Formatting is pure Python and holds
#: the GIL; 4 rows of 34 columns or 4 candump lines take about 30-40 us on the 2-vCPU VM
#: (three times that with the other core busy), so the loop's thread waits at most about
#: that long for the writer, well inside the 0.5 ms the loop allows a neighbour (issue 10),
#: not the 5 ms switch interval. `longest_hold_s` in metadata.json says what it was.
CHUNK = 4


class RunWriter:
    """Background writer of one run folder's signal, CAN and event files.

    Parameters
    ----------
    folder : Path
        The run folder (already created).
    columns : tuple of str
        Signal column names; the header of ``signals.csv`` is written on construction.
    signals_name, events_name : str
        File names inside ``folder``.
    can_name : str or None
        File name of the candump log, or None for a run without CAN traffic.
    row_capacity, frame_capacity, event_capacity : int
        Sizes of the row ring, frame ring and event queue.
    flush_interval_s : float
        Seconds between drains (s).
    fsync_interval_s : float
        Seconds between fsyncs (s); 0 fsyncs at every drain.
    ticks_name : str or None
        File name of the loop's tick record (what exact replay needs, :mod:`harness.loop.tick_log`):
        ``tick_columns`` little-endian float64 values per tick, exact; None for none.
    tick_columns : int
        Values per tick record (with ``ticks_name``).
    """

    def __init__(
        self,
        folder: Path,
        columns: tuple[str, ...],
        *,
        signals_name: str,
        events_name: str,
        can_name: str | None,
        row_capacity: int = 8192,
        frame_capacity: int = 32768,
        event_capacity: int = 1024,
        flush_interval_s: float = 0.05,
        fsync_interval_s: float = 1.0,
        ticks_name: str | None = None,
        tick_columns: int = 0,
    ):
        if not 0.0 < flush_interval_s <= 0.1:
            raise ValueError(f"found flush_interval_s={flush_interval_s}, expected 0 < value <= 0.1 s")
        self.columns = columns
        self.rows = RowRing(len(columns), row_capacity)
        self.frames = FrameRing(frame_capacity)
        #: The loop's tick record (None without one): bounded like the rows, written as exact binary.
        self.ticks = RowRing(tick_columns, row_capacity) if ticks_name else None
        self._events: queue.Queue[tuple[Any, ...]] = queue.Queue(maxsize=event_capacity)
        self.events_dropped = 0
        self.events_accepted = 0
        self.flush_interval_s = flush_interval_s
        self.fsync_interval_s = fsync_interval_s
        self._line = row_format(len(columns))
        self._signals: TextIO = open(folder / signals_name, "w", encoding="utf-8", newline="")
        self._signals.write(",".join(columns) + "\n")
        self._signals.flush()
        self._event_file: TextIO = open(folder / events_name, "w", encoding="utf-8", newline="")
        self._can: can.CanutilsLogWriter | None = can.CanutilsLogWriter(folder / can_name) if can_name else None
        self._ticks: BinaryIO | None = open(folder / ticks_name, "wb") if ticks_name else None  # noqa: SIM115 - closed in close()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name=f"recorder-{folder.name}", daemon=True)
        self._lock = threading.Lock()
        self._last_fsync = time.monotonic()
        self._reported_drops = (0, 0, 0)
        #: Rows, frames and queued events written AND flushed to the OS so far.
        self.rows_written = 0
        self.frames_written = 0
        self.events_written = 0
        self.ticks_written = 0
        self.error: BaseException | None = None
        #: Longest CPU time the writer thread ran between two yields of the interpreter lock (s):
        #: an upper bound of how long it can keep the loop's thread waiting for the lock.
        self.longest_hold_s = 0.0
        self._hold_started = 0.0
        self._closed = False

    # ----------------------------------------------------------------- producer side
    def record_row(self, values: Sequence[float] | np.ndarray) -> bool:
        """Queue one row of ``len(columns)`` values; never blocks. False if dropped."""
        return self.rows.push(values)

    def record_frame(self, msg: can.Message) -> bool:
        """Queue a sent or received CAN frame (its fields are copied); never blocks. False if dropped."""
        return self.frames.push(msg)

    def record_tick(self, values: np.ndarray) -> bool:
        """Queue one tick record (:mod:`harness.loop.tick_log`); never blocks. False if dropped (or none is kept)."""
        ticks = self.ticks
        return ticks.push(values) if ticks is not None else False

    def record_event(self, t: float | None, kind: str, name: str, detail: Any = None) -> bool:
        """Queue an event; never blocks. False if the event queue was full (the drop is counted).

        Parameters
        ----------
        t : float or None
            Run time of the event (s), the same clock as the ``t_s`` column.
        kind : str
            Category, e.g. ``"lifecycle"``, ``"trip"``, ``"warning"``, ``"interlock"``.
        name : str
            What happened, e.g. ``"armed"``, ``"stroke_hard_limit"``.
        detail : JSON-serialisable, optional
            Anything else (a message, a mapping of values). It is serialised later on
            the writer thread, so pass a value the caller will not change afterwards.
        """
        try:
            self._events.put_nowait((t, time.time(), kind, name, detail))
        except queue.Full:
            self.events_dropped += 1
            return False
        self.events_accepted += 1
        return True

    # ----------------------------------------------------------------- consumer side
    def start(self) -> None:
        """Start the writer thread."""
        self._thread.start()

    @property
    def running(self) -> bool:
        """True while the writer thread is alive."""
        return self._thread.is_alive()

    def drops(self) -> dict[str, int]:
        """Rows, frames and events dropped so far because a queue was full."""
        drops = {"rows": self.rows.dropped, "frames": self.frames.dropped, "events": self.events_dropped}
        if self.ticks is not None:
            drops["ticks"] = self.ticks.dropped
        return drops

    def lost(self) -> dict[str, int]:
        """Rows, frames and events handed to the recorder that are not (yet) confirmed in the files.

        Each count is what the queue accepted but the writer has not written and flushed,
        plus what the full queue dropped. After :meth:`close` that is what the record
        lost: after a write error, the rows of the failed drain and every row queued
        later. (Some of the failed drain's rows may have reached the file before the
        error; they are counted as lost because nothing confirmed them.) Frames count
        only for a run with a CAN log.
        """
        frames = self.frames.pushed - self.frames_written + self.frames.dropped if self._can is not None else 0
        lost = {
            "rows": self.rows.pushed - self.rows_written + self.rows.dropped,
            "frames": frames,
            "events": self.events_accepted - self.events_written + self.events_dropped,
        }
        if self.ticks is not None:
            lost["ticks"] = self.ticks.pushed - self.ticks_written + self.ticks.dropped
        return lost

    def _run(self) -> None:
        while not self._stop.wait(self.flush_interval_s):
            if not self._drain_safely():
                return
        self._drain_safely()

    def _drain_safely(self) -> bool:
        try:
            self.drain()
        except (OSError, ValueError) as err:
            self.error = err
            self._note_failure(err)
            return False
        return True

    def _note_failure(self, err: BaseException) -> None:
        """Best effort: say in the event file why the record stops (that file may still have room)."""
        detail = {"error": f"{type(err).__name__}: {err}", "rows_written": self.rows_written}
        try:
            with self._lock:
                if not self._closed:
                    self._write_event_line(None, time.time(), "fault", "recorder_failed", detail)
                    self._event_file.flush()
        except (OSError, ValueError):
            pass

    def drain(self) -> None:
        """Write everything pending and flush (called by the thread; safe to call after stop)."""
        with self._lock:
            if self._closed:
                return
            self._hold_started = time.thread_time()
            rows = self._write_rows()
            ticks = self._write_ticks()
            frames = self._write_frames()
            self._report_drops()
            events = self._write_events()
            self._yield_interpreter()
            self._flush()
            self._yield_interpreter()
            self.rows_written += rows
            self.ticks_written += ticks
            self.frames_written += frames if self._can is not None else 0
            self.events_written += events

    def _write_rows(self) -> int:
        """Write the rows pending now in chunks, yielding the GIL between chunks; return how many."""
        total, target = 0, self.rows.pending
        while total < target:
            block = self.rows.drain(CHUNK)
            self._signals.write(format_rows(self._line, block))
            total += len(block)
            self._yield_interpreter()
        return total

    def _write_ticks(self) -> int:
        """Write the tick records pending now, exact (little-endian float64); return how many."""
        ticks, handle = self.ticks, self._ticks
        if ticks is None or handle is None or not ticks.pending:
            return 0
        block = ticks.drain()
        handle.write(block.astype("<f8", copy=False).tobytes())
        return len(block)

    def _write_frames(self) -> int:
        """Write the frames pending now in chunks, yielding the GIL between chunks; return how many."""
        total, target = 0, self.frames.pending
        while total < target:
            frames = self.frames.drain(CHUNK)
            if self._can is not None:
                for msg in frames:
                    self._can.on_message_received(msg)
            total += len(frames)
            self._yield_interpreter()
        return total

    def _yield_interpreter(self) -> None:
        """Let the loop's thread have the interpreter lock; note how long this thread ran since the last yield."""
        now = time.thread_time()
        self.longest_hold_s = max(self.longest_hold_s, now - self._hold_started)
        time.sleep(0)
        self._hold_started = time.thread_time()

    def _restart_hold(self) -> None:
        """After a system call that released the interpreter lock (write, fsync): a new stretch starts.

        Its CPU time (kernel time, counted by ``thread_time``) was spent without the lock.
        """
        self._hold_started = time.thread_time()

    def _report_drops(self) -> None:
        now = (self.rows.dropped, self.frames.dropped, self.events_dropped)
        if now != self._reported_drops:
            new = {key: a - b for key, a, b in zip(("rows", "frames", "events"), now, self._reported_drops, strict=True)}
            self._reported_drops = now
            total = dict(zip(("rows", "frames", "events"), now, strict=True))
            self._write_event_line(None, time.time(), "warning", "recorder_dropped", {"new": new, "total": total})

    def _write_events(self) -> int:
        count = 0
        while True:
            try:
                t, wall, kind, name, detail = self._events.get_nowait()
            except queue.Empty:
                return count
            self._write_event_line(t, wall, kind, name, detail)
            count += 1

    def _write_event_line(self, t: float | None, wall: float, kind: str, name: str, detail: Any) -> None:
        record = {"t_s": _finite_or_none(t), "wall_time": wall, "kind": kind, "name": name, "detail": detail}
        self._event_file.write(strict_json.dumps(record, _event_default) + "\n")

    def _flush(self) -> None:
        """Flush every file, and fsync them every ``fsync_interval_s``; both release the interpreter lock."""
        handles: list[Any] = [self._signals, self._event_file] + ([self._can.file] if self._can is not None else [])
        handles += [self._ticks] if self._ticks is not None else []
        for handle in handles:
            handle.flush()
            self._restart_hold()
        now = time.monotonic()
        if now - self._last_fsync >= self.fsync_interval_s:
            for handle in handles:
                os.fsync(handle.fileno())
                self._restart_hold()
            self._last_fsync = now

    def close(self, timeout_s: float = 5.0) -> None:
        """Stop the thread, write what is left, fsync and close the files (idempotent).

        Parameters
        ----------
        timeout_s : float
            Seconds to wait for the thread (s).
        """
        if self._closed:
            return
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join(timeout_s)
        if self.error is None:
            self._drain_safely()
        with self._lock:
            self._closed = True
            for handle in (self._signals, self._event_file, self._ticks):
                if handle is not None:
                    _close_quietly(handle)
            if self._can is not None:
                try:
                    self._can.stop()
                except (OSError, ValueError):
                    pass


def row_format(n_columns: int) -> str:
    """The ``%``-format of one CSV line of ``n_columns`` values."""
    return ",".join([VALUE_FORMAT] * n_columns) + "\n"


def format_rows(line: str, block: np.ndarray) -> str:
    """CSV text of a block of rows; NaN and infinities spelled ``NaN``/``Inf`` as pandas and MATLAB read them.

    Parameters
    ----------
    line : str
        From :func:`row_format`.
    block : ndarray, shape (k, n_columns)
    """
    text = "".join([line % tuple(row) for row in block.tolist()])
    if "n" in text:
        text = text.replace("nan", "NaN").replace("inf", "Inf")
    return text


def _event_default(value: Any) -> Any:
    """Event details are free-form: keep numpy values as numbers, anything else as its text."""
    try:
        return json_default(value)
    except TypeError:
        return str(value)


def _finite_or_none(value: float | None) -> float | None:
    if value is None:
        return None
    number = float(value)
    return number if math.isfinite(number) else None


def _close_quietly(handle: TextIO | BinaryIO) -> None:
    try:
        handle.flush()
        os.fsync(handle.fileno())
    except (OSError, ValueError):
        pass
    try:
        handle.close()  # flushes again: after a write error the buffer still holds what failed
    except (OSError, ValueError):
        pass
