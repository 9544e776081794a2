"""What the live console shows, in a fixed-size shared memory block another process can read.

The control loop overwrites a :class:`LoopStatus` in place every tick; the live console
runs in a child process (:mod:`harness.console_view`) that attaches to the same block and
draws it, so rendering never holds the loop process's interpreter lock.

The block is a small temporary file (in ``/dev/shm`` where it exists), mapped with
:mod:`mmap` by both processes and removed by :meth:`LoopStatus.close`. Its layout:

==============  ======================================================================
bytes           contents
==============  ======================================================================
0 .. 512        64 float64 cells: a magic number, the numeric fields, the state code,
                the finished flag, the lateness count, for each text slot a sequence
                number and a length, the event count, and each story's drift (m)
                and floor acceleration (m/s^2), up to 8 stories
512 .. 4608     ring of the most recent 512 lateness values (float64, s)
4608 .. 6016    UTF-8 text slots: phase (64 bytes), last_event (256), trip_reason (128),
                then a ring of the 6 most recent event lines (160 each)
==============  ======================================================================

Writes from the loop allocate nothing: numeric fields go straight into the float64 cells;
a text field is encoded and copied only when it differs from the last string written
(one string comparison otherwise). A text field is guarded by a sequence number (odd while
it is being written) so a reader never shows a half-written string. The story values
(:meth:`LoopStatus.set_story`) are two cell stores per story; an event line
(:meth:`LoopStatus.add_event`) is encoded when the event happens, which is rare.
"""

from __future__ import annotations

import mmap
import os
import tempfile
import weakref
from typing import TYPE_CHECKING, Generic, TypeVar

import numpy as np

#: The run states by code; the same names and values as :class:`harness.safety.lifecycle.State`
#: (not imported here so the console's child process starts without the safety layer).
STATE_NAMES = ("IDLE", "ARMED", "RUNNING", "STOPPING", "DONE", "TRIPPED")
_STATE_CODES = {name: code for code, name in enumerate(STATE_NAMES)}
_N_STATES = len(STATE_NAMES)

#: Lateness values kept for the console's percentiles (a power of two: the index is ``count & mask``).
LATENESS_RING_SIZE = 512
_RING_MASK = LATENESS_RING_SIZE - 1

#: Numeric fields: (name, is integer, description with unit).
NUMBER_FIELDS = (
    ("t_s", False, "loop time of the last tick (s)"),
    ("run_t_s", False, "time since RUNNING began (s); 0 before"),
    ("duration_s", False, "seconds of record to run (s)"),
    ("stroke_m", False, "sliding displacement x_b (m)"),
    ("force_N", False, "commanded actuator force (N)"),
    ("sliding_variable", False, "the controller's sliding variable S (m/s)"),
    ("overruns", True, "deadlines the scheduler missed"),
    ("e2e_rejects", True, "frames rejected by the end-to-end protection"),
    ("error_frames", True, "CAN error frames seen"),
    ("send_failures", True, "frames that could not be sent"),
    ("stalls", True, "stalls ridden through (two periods or more between two ticks' starts, within budget)"),
    ("longest_stall_s", False, "longest time between the starts of two consecutive ticks in a stall (s)"),
    ("missed_periods", True, "whole periods missed in stalls (the gaps between two ticks' starts), in total"),
    ("fault_code", True, "the servo's fault code in the latest ACTUATOR_STATUS (drivers.protocol_values.FaultCode); 0 none"),
    ("n_stories", True, "stories whose drift and floor acceleration are published (set_story); 0 none"),
    ("table_verdict", True, "the table against its record: a code of TABLE_VERDICT_NAMES"),
    ("table_correlation", False, "the table check's latest correlation (NaN before its first evaluation)"),
    ("table_delay_s", False, "the table check's latest delay of the table behind its record (s)"),
    ("table_amplitude_ratio", False, "the table check's latest amplitude ratio, achieved over told"),
)
#: The table check's verdicts by code; the same names and values as
#: :class:`harness.safety.table_record.TableVerdict` (not imported, as for :data:`STATE_NAMES`).
TABLE_VERDICT_NAMES = ("OFF", "WAITING", "MATCH", "MARGINAL", "MISMATCH")
#: Text fields: (name, capacity in UTF-8 bytes, default).
TEXT_FIELDS = (("phase", 64, "starting"), ("last_event", 256, ""), ("trip_reason", 128, ""))
#: Event lines kept for the console's scrolling list, and the UTF-8 bytes kept of each.
EVENT_LINES = 6
EVENT_LINE_BYTES = 160
#: Stories whose drift and floor acceleration the block holds.
MAX_STORIES = 8
#: Every text slot: the text fields, then the ring of event lines.
_TEXT_SLOTS = (*TEXT_FIELDS, *((f"event_{i}", EVENT_LINE_BYTES, "") for i in range(EVENT_LINES)))
_FIRST_EVENT_SLOT = len(TEXT_FIELDS)

_MAGIC = float(0x53_5441_5403)  # "STAT" v3 (v3: the table check's cells); exact in a float64 (40 bits)
_N_CELLS = 64
_CELL_MAGIC = 0
_CELL_FIRST_NUMBER = 1
_CELL_STATE = _CELL_FIRST_NUMBER + len(NUMBER_FIELDS)
_CELL_FINISHED = _CELL_STATE + 1
_CELL_LATENESS_COUNT = _CELL_FINISHED + 1
_CELL_FIRST_TEXT = _CELL_LATENESS_COUNT + 1  # then (sequence, length) per text slot
_CELL_EVENT_COUNT = _CELL_FIRST_TEXT + 2 * len(_TEXT_SLOTS)
_CELL_FIRST_DRIFT = _CELL_EVENT_COUNT + 1  # story j's drift at _CELL_FIRST_DRIFT + j - 1
_CELL_FIRST_ACCEL = _CELL_FIRST_DRIFT + MAX_STORIES  # floor j's acceleration at _CELL_FIRST_ACCEL + j - 1
assert _CELL_FIRST_ACCEL + MAX_STORIES <= _N_CELLS

_CELLS_BYTES = 8 * _N_CELLS
_RING_OFFSET = _CELLS_BYTES
_TEXT_OFFSET = _RING_OFFSET + 8 * LATENESS_RING_SIZE
_TEXT_OFFSETS = tuple(_TEXT_OFFSET + sum(capacity for _, capacity, _ in _TEXT_SLOTS[:i]) for i in range(len(_TEXT_SLOTS)))
BLOCK_BYTES = _TEXT_OFFSET + sum(capacity for _, capacity, _ in _TEXT_SLOTS)
_READ_ATTEMPTS = 1000


if TYPE_CHECKING:
    _T = TypeVar("_T")

    class _Field(Generic[_T]):
        """How a type checker sees the properties :class:`LoopStatus` gets from the field tables."""

        def __get__(self, status: LoopStatus | None, owner: type | None = None) -> _T: ...

        def __set__(self, status: LoopStatus, value: _T) -> None: ...


def truncate_utf8(encoded: bytes, capacity: int) -> bytes:
    """``encoded`` cut to at most ``capacity`` bytes without splitting a character.

    Parameters
    ----------
    encoded : bytes
        Valid UTF-8.
    capacity : int
        Most bytes kept.
    """
    if len(encoded) <= capacity:
        return encoded
    cut = capacity
    while cut > 0 and encoded[cut] & 0xC0 == 0x80:  # a continuation byte: its character began before the cut
        cut -= 1
    return encoded[:cut]


def _shared_memory_dir() -> str | None:
    """``/dev/shm`` (memory, never written back to a disk) where it is usable, else the default temp dir."""
    return "/dev/shm" if os.path.isdir("/dev/shm") and os.access("/dev/shm", os.W_OK) else None


def _create_block() -> tuple[mmap.mmap, str]:
    """A new zeroed block file, mapped read-write with every page already resident; returns (map, path)."""
    fd, path = tempfile.mkstemp(prefix="harness-status-", suffix=".bin", dir=_shared_memory_dir())
    try:
        os.ftruncate(fd, BLOCK_BYTES)
        block = mmap.mmap(fd, BLOCK_BYTES)
    except BaseException:
        os.close(fd)
        os.unlink(path)
        raise
    os.close(fd)  # the map keeps its own reference to the file
    block[:] = bytes(BLOCK_BYTES)  # touch every page now, not as a page fault inside a tick
    return block, path


def _open_block(path: str, writable: bool) -> mmap.mmap:
    """Map an existing block file."""
    fd = os.open(path, os.O_RDWR if writable else os.O_RDONLY)
    try:
        if os.fstat(fd).st_size < BLOCK_BYTES:
            raise ValueError(f"{path} is not a loop status block (too short)")
        return mmap.mmap(fd, BLOCK_BYTES, access=mmap.ACCESS_WRITE if writable else mmap.ACCESS_READ)
    finally:
        os.close(fd)


def _release_block(block: mmap.mmap | None, path: str | None) -> None:
    """Unmap ``block`` (unless views of it are still alive elsewhere) and remove the file at ``path``."""
    if block is not None:
        try:
            block.close()
        except BufferError:
            pass  # someone still holds a numpy view of it: unmapped when that view dies
    if path is not None:
        try:
            os.unlink(path)
        except FileNotFoundError:
            pass


class _Views:
    """Typed views of a block's bytes: the cells and the ring as float64 (numpy for reading,
    memoryview for writing, which costs about a third of a numpy item assignment), and the raw bytes."""

    __slots__ = ("raw", "cells", "numbers", "ring_cells", "ring")

    def __init__(self, buffer: mmap.mmap | bytearray):
        self.raw = memoryview(buffer)
        self.cells = self.raw[:_CELLS_BYTES].cast("d")
        self.numbers: np.ndarray | None = np.frombuffer(buffer, dtype=np.float64, count=_N_CELLS)  # None once released
        self.ring_cells = self.raw[_RING_OFFSET:_TEXT_OFFSET].cast("d")
        self.ring: np.ndarray | None = np.frombuffer(buffer, dtype=np.float64, count=LATENESS_RING_SIZE, offset=_RING_OFFSET)

    def release(self) -> None:
        """Drop every export of the underlying buffer held here."""
        self.cells.release()
        self.ring_cells.release()
        self.raw.release()
        self.numbers = self.ring = None


class LoopStatus:
    """The loop's status for the live console, in shared memory.

    ``LoopStatus(**fields)`` creates a new block (this object owns it and removes it at
    :meth:`close`); :meth:`attach` maps an existing one (read-only by default) in another
    process. After :meth:`close` the object keeps its last values in private memory and
    stays readable and writable.

    Parameters
    ----------
    **fields
        Initial values of any of the attributes below.

    Attributes
    ----------
    phase : str
        Free text (at most 64 UTF-8 bytes are kept).
    state : str
        The run state's name (``IDLE`` ... ``TRIPPED``); set it from the name or a ``State``.
    t_s, run_t_s, duration_s : float
        Loop time, time since RUNNING began, seconds of record (s).
    stroke_m : float
        Sliding displacement (m).
    force_N : float
        Commanded force (N).
    sliding_variable : float
        Sliding variable S (m/s).
    overruns, e2e_rejects, error_frames, send_failures : int
        Loop and bus counters.
    stalls : int
        Stalls ridden through.
    longest_stall_s : float
        Longest gap between two ticks' commands (s).
    missed_periods : int
        Whole periods missed in stalls, in total.
    fault_code : int
        The servo's fault code in the latest ACTUATOR_STATUS (0 none).
    n_stories : int
        Stories published with :meth:`set_story` (0: none).
    last_event, trip_reason : str
        At most 256 and 128 UTF-8 bytes are kept.
    finished : bool
        Set by the loop's side when the run is over; the console's child then draws its last frame.
    path : str
        The block's file (what :meth:`attach` takes).
    """

    __slots__ = ("_views", "_cells", "_ring_cells", "_block", "_path", "_owner", "_last_text", "_lateness_count", "_finalizer",
                 "__weakref__")

    if TYPE_CHECKING:  # the properties installed below the class, from NUMBER_FIELDS and TEXT_FIELDS
        t_s = _Field[float]()
        run_t_s = _Field[float]()
        duration_s = _Field[float]()
        stroke_m = _Field[float]()
        force_N = _Field[float]()
        sliding_variable = _Field[float]()
        overruns = _Field[int]()
        e2e_rejects = _Field[int]()
        error_frames = _Field[int]()
        send_failures = _Field[int]()
        stalls = _Field[int]()
        longest_stall_s = _Field[float]()
        missed_periods = _Field[int]()
        fault_code = _Field[int]()
        n_stories = _Field[int]()
        table_verdict = _Field[int]()
        table_correlation = _Field[float]()
        table_delay_s = _Field[float]()
        table_amplitude_ratio = _Field[float]()
        phase = _Field[str]()
        last_event = _Field[str]()
        trip_reason = _Field[str]()

    def __init__(self, **fields: object):
        block, path = _create_block()
        self._bind(block, path, owner=True)
        try:
            self._cells[_CELL_MAGIC] = _MAGIC
            for name, _, default in TEXT_FIELDS:
                setattr(self, name, default)
            for name, value in fields.items():
                if name not in _FIELD_NAMES:
                    raise TypeError(f"LoopStatus() got an unexpected keyword argument {name!r}")
                setattr(self, name, value)
        except BaseException:
            self.close()
            raise

    @classmethod
    def attach(cls, path: str | os.PathLike, writable: bool = False) -> LoopStatus:
        """Map the block another process created at ``path`` (it stays that process's to remove).

        Parameters
        ----------
        path : str or path-like
        writable : bool
            Map it read-write (tests); a console only reads.

        Raises
        ------
        ValueError
            The file is not a loop status block.
        """
        status = cls.__new__(cls)
        status._bind(_open_block(os.fspath(path), writable), os.fspath(path), owner=False)
        if status._cells[_CELL_MAGIC] != _MAGIC:
            status.close()
            raise ValueError(f"{path} is not a loop status block (bad magic number)")
        status._last_text = [status._read_text(i) for i in range(len(_TEXT_SLOTS))]
        status._lateness_count = int(status._cells[_CELL_LATENESS_COUNT])
        return status

    def _bind(self, block: mmap.mmap, path: str, owner: bool) -> None:
        self._block: mmap.mmap | None = block  # None once closed
        self._path = path
        self._owner = owner
        self._use_views(_Views(block))
        #: The text last written to each text field (None: not yet), to skip rewriting the same.
        self._last_text: list[str | None] = [None] * len(_TEXT_SLOTS)
        self._lateness_count = 0
        self._finalizer = weakref.finalize(self, _release_block, block, path if owner else None)

    def _use_views(self, views: _Views) -> None:
        self._views = views
        self._cells = views.cells  # the hot paths' views, one attribute away
        self._ring_cells = views.ring_cells

    @property
    def path(self) -> str:
        """The block's file."""
        return self._path

    @property
    def closed(self) -> bool:
        """True once :meth:`close` ran."""
        return self._block is None

    def close(self) -> None:
        """Unmap the block (and remove its file if this object created it); idempotent.

        The owner sets :attr:`finished` first. The values stay readable here afterwards.
        """
        if self._block is None:
            return
        if self._owner:
            self.finished = True
        private = bytearray(self._views.raw)  # keep the last values
        old = self._views
        self._use_views(_Views(private))
        old.release()
        self._block = None
        self._finalizer()

    def __enter__(self) -> LoopStatus:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # -- state, finished and the lateness ring ---------------------------------------------

    @property
    def state(self) -> str:
        """The run state's name."""
        return STATE_NAMES[int(self._cells[_CELL_STATE])]

    @state.setter
    def state(self, value: str | int) -> None:
        code = value if isinstance(value, int) else _STATE_CODES.get(value, -1)  # a State (an int), or a name
        if not 0 <= code < _N_STATES:
            raise ValueError(f"unknown run state {value!r}; expected one of {', '.join(STATE_NAMES)}")
        self._cells[_CELL_STATE] = code

    @property
    def finished(self) -> bool:
        """True once the loop's side has finished the run."""
        return self._cells[_CELL_FINISHED] != 0.0

    @finished.setter
    def finished(self, value: bool) -> None:
        self._cells[_CELL_FINISHED] = 1.0 if value else 0.0

    def add_lateness(self, lateness_s: float) -> None:
        """Record one tick's wake-up lateness (s) in the ring (no allocation that outlives the call)."""
        count = self._lateness_count
        self._ring_cells[count & _RING_MASK] = lateness_s
        count += 1
        self._lateness_count = count
        self._cells[_CELL_LATENESS_COUNT] = count

    @property
    def lateness_count(self) -> int:
        """Lateness values recorded so far (the ring keeps the last 512)."""
        return int(self._cells[_CELL_LATENESS_COUNT])

    def recent_lateness_s(self) -> np.ndarray:
        """A copy of the lateness values in the ring (s), in no particular order."""
        n = min(self.lateness_count, LATENESS_RING_SIZE)
        ring = self._views.ring
        assert ring is not None, "only the views close() replaced are released"
        return ring[:n].copy()

    def lateness_percentiles(self) -> tuple[float, float]:
        """Lateness p50 and p99 over the ring (s); (0, 0) before the first tick."""
        recent = self.recent_lateness_s()
        if recent.size == 0:
            return 0.0, 0.0
        p50, p99 = np.percentile(recent, [50, 99])
        return float(p50), float(p99)

    # -- stories and events ------------------------------------------------------------------

    def set_story(self, index: int, drift_m: float, floor_acceleration_m_s2: float) -> None:
        """Publish story ``index + 1``'s interstory drift (m) and its floor's absolute acceleration (m/s^2).

        Two cell stores, no allocation: the tick calls it for every story, every tick.
        ``index`` counts from 0 (story 1) and must be below :data:`MAX_STORIES`.
        """
        cells = self._cells
        cells[_CELL_FIRST_DRIFT + index] = drift_m
        cells[_CELL_FIRST_ACCEL + index] = floor_acceleration_m_s2

    def stories(self) -> list[tuple[float, float]]:
        """``(drift_m, floor_acceleration_m_s2)`` of stories 1 .. :attr:`n_stories`, bottom up."""
        cells = self._cells
        count = min(max(self.n_stories, 0), MAX_STORIES)
        return [(cells[_CELL_FIRST_DRIFT + j], cells[_CELL_FIRST_ACCEL + j]) for j in range(count)]

    def add_event(self, line: str) -> None:
        """Append one line to the ring of recent events (the oldest of :data:`EVENT_LINES` is dropped; allocates)."""
        count = int(self._cells[_CELL_EVENT_COUNT])
        self._write_text(_FIRST_EVENT_SLOT + count % EVENT_LINES, line)
        self._cells[_CELL_EVENT_COUNT] = count + 1

    @property
    def event_count(self) -> int:
        """Event lines added so far (the ring keeps the last :data:`EVENT_LINES`)."""
        return int(self._cells[_CELL_EVENT_COUNT])

    def recent_events(self) -> list[str]:
        """The most recent event lines, oldest first."""
        count = self.event_count
        first = max(0, count - EVENT_LINES)
        return [self._read_text(_FIRST_EVENT_SLOT + k % EVENT_LINES) for k in range(first, count)]

    # -- text fields -------------------------------------------------------------------------

    def _write_text(self, index: int, value: str | None) -> None:
        """Encode, truncate and store text slot ``index`` under its sequence number (allocates)."""
        text = "" if value is None else str(value)
        _, capacity, _ = _TEXT_SLOTS[index]
        encoded = truncate_utf8(text.encode("utf-8", "replace"), capacity)
        offset, sequence = _TEXT_OFFSETS[index], _CELL_FIRST_TEXT + 2 * index
        cells = self._cells
        cells[sequence] += 1.0  # odd: being written
        self._views.raw[offset : offset + len(encoded)] = encoded
        cells[sequence + 1] = len(encoded)
        cells[sequence] += 1.0  # even: consistent
        self._last_text[index] = text

    def _read_text(self, index: int) -> str:
        """Text slot ``index`` as stored (retries while the writer is half-way through)."""
        _, capacity, _ = _TEXT_SLOTS[index]
        offset, sequence = _TEXT_OFFSETS[index], _CELL_FIRST_TEXT + 2 * index
        cells, raw = self._cells, self._views.raw
        data = b""
        for _ in range(_READ_ATTEMPTS):
            before = cells[sequence]
            if before % 2.0:
                continue
            length = min(int(cells[sequence + 1]), capacity)
            data = bytes(raw[offset : offset + length])
            if cells[sequence] == before:
                break
        return data.decode("utf-8", "replace")

    # -- snapshots ---------------------------------------------------------------------------

    def as_dict(self) -> dict:
        """Every field's current value, by name (for tests and summaries)."""
        return {name: getattr(self, name) for name in _FIELD_NAMES} | {"finished": self.finished}

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={value!r}" for name, value in self.as_dict().items())
        return f"LoopStatus({fields})"


def _number_property(cell: int, is_integer: bool, doc: str) -> property:
    """A property storing a number in float64 cell ``cell`` (integers read back as int)."""
    def read_int(self: LoopStatus) -> int:
        return int(self._cells[cell])

    def read_float(self: LoopStatus) -> float:
        return self._cells[cell]

    def write(self: LoopStatus, value: float) -> None:
        self._cells[cell] = value

    return property(read_int if is_integer else read_float, write, doc=doc)


def _text_property(index: int, name: str, capacity: int) -> property:
    """A property storing UTF-8 text; a write is one comparison unless the text changed."""
    def read(self: LoopStatus) -> str:
        return self._read_text(index)

    def write(self: LoopStatus, value: str) -> None:
        if value == self._last_text[index]:
            return
        self._write_text(index, value)

    return property(read, write, doc=f"{name} (at most {capacity} UTF-8 bytes are kept)")


for _i, (_name, _is_integer, _doc) in enumerate(NUMBER_FIELDS):
    setattr(LoopStatus, _name, _number_property(_CELL_FIRST_NUMBER + _i, _is_integer, _doc))
for _i, (_name, _capacity, _) in enumerate(TEXT_FIELDS):
    setattr(LoopStatus, _name, _text_property(_i, _name, _capacity))
del _i, _name, _is_integer, _doc, _capacity

_FIELD_NAMES = ("state", *(name for name, _, _ in NUMBER_FIELDS), *(name for name, _, _ in TEXT_FIELDS))
