"""A fixed-size block of shared memory that one process writes every tick and another reads.

:class:`StatusBlock` is the mechanism under :class:`harness.loop.status.LoopStatus`: the
block's file, its byte layout, the typed fields a subclass declares in its class body
(:class:`FloatField`, :class:`IntField`, :class:`TextField`, :class:`StateField`) and the
sequence lock that keeps a reader from showing a half-written text.

The block is a small temporary file (in ``/dev/shm`` where it exists), mapped with
:mod:`mmap` by both processes and removed by :meth:`StatusBlock.close`. Its layout, for
the fields :class:`~harness.loop.status.LoopStatus` declares:

==============  ======================================================================
bytes           contents
==============  ======================================================================
0 .. 512        64 float64 cells: a magic number, the numeric fields, the state code,
                the finished flag, the lateness count, for each text slot a sequence
                number and a length, the event count, and each story's drift (m)
                and floor acceleration (m/s^2), up to 8 stories
512 .. 4608     ring of the most recent 512 lateness values (float64, s)
4608 .. 6016    UTF-8 text slots: the text fields in the order declared (phase 64 bytes,
                last_event 256, trip_reason 128), then a ring of the 6 most recent event
                lines (160 each)
==============  ======================================================================

The cells are placed in the order the fields are declared (:class:`BlockLayout`), when
the subclass is created; ``tests/unit/test_loop_status_fields.py`` holds the table above
to that layout.

Writes allocate nothing: numeric fields go straight into the float64 cells; a text field
is encoded and copied only when it differs from the last string written (one string
comparison otherwise). A text slot is guarded by a sequence number (odd while it is being
written) so a reader never shows a half-written string. The story values
(:meth:`StatusBlock.set_story`) are two cell stores per story; an event line
(:meth:`StatusBlock.add_event`) is encoded when the event happens, which is rare.
"""

from __future__ import annotations

import mmap
import os
import tempfile
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Self, overload

import numpy as np

#: Float64 cells at the start of the block.
N_CELLS = 64
#: Lateness values kept for the console's percentiles (a power of two: the index is ``count & mask``).
LATENESS_RING_SIZE = 512
_RING_MASK = LATENESS_RING_SIZE - 1
#: Event lines kept for the console's scrolling list, and the UTF-8 bytes kept of each.
EVENT_LINES = 6
EVENT_LINE_BYTES = 160
#: Stories whose drift and floor acceleration the block holds.
MAX_STORIES = 8

MAGIC = float(0x53_5441_5403)  # "STAT" v3 (v3: the table check's cells); exact in a float64 (40 bits)
CELL_MAGIC = 0
_READ_ATTEMPTS = 1000


@dataclass(frozen=True)
class BlockLayout:
    """Where everything lies in a block: cell indices, then byte offsets.

    Attributes
    ----------
    first_number : int
        Cell of the first numeric field; the others follow in the order declared.
    state, finished, lateness_count : int
        Cells of the state code, the finished flag and the count of lateness values.
    first_text : int
        Cell of text slot 0's sequence number; each slot has two cells (sequence, length).
    event_count : int
        Cell of the count of event lines added.
    first_drift, first_accel : int
        Cells of story 1's drift and floor 1's acceleration; story ``j`` at ``first + j - 1``.
    ring_offset, text_offset : int
        Bytes where the lateness ring and the text slots begin.
    text_capacities : tuple of int
        UTF-8 bytes of each text slot: the text fields, then the event lines.
    text_offsets : tuple of int
        Byte where each text slot begins.
    block_bytes : int
        Size of the block.
    """

    first_number: int
    state: int
    finished: int
    lateness_count: int
    first_text: int
    event_count: int
    first_drift: int
    first_accel: int
    ring_offset: int
    text_offset: int
    text_capacities: tuple[int, ...]
    text_offsets: tuple[int, ...]
    block_bytes: int

    @classmethod
    def of(cls, number_fields: int, text_capacities: Sequence[int]) -> BlockLayout:
        """The layout of a block with ``number_fields`` numeric fields and text fields of these capacities (bytes).

        Raises
        ------
        ValueError
            The cells do not fit :data:`N_CELLS`.
        """
        capacities = (*text_capacities, *(EVENT_LINE_BYTES,) * EVENT_LINES)
        first_number = CELL_MAGIC + 1
        state = first_number + number_fields
        first_text = state + 3  # then the finished flag and the lateness count
        event_count = first_text + 2 * len(capacities)
        first_accel = event_count + 1 + MAX_STORIES
        if first_accel + MAX_STORIES > N_CELLS:
            raise ValueError(f"{number_fields} numeric and {len(text_capacities)} text fields need "
                             f"{first_accel + MAX_STORIES} cells; a block has {N_CELLS}")
        ring_offset = 8 * N_CELLS
        text_offset = ring_offset + 8 * LATENESS_RING_SIZE
        offsets = tuple(text_offset + sum(capacities[:i]) for i in range(len(capacities)))
        return cls(first_number=first_number, state=state, finished=state + 1, lateness_count=state + 2,
                   first_text=first_text, event_count=event_count, first_drift=event_count + 1, first_accel=first_accel,
                   ring_offset=ring_offset, text_offset=text_offset, text_capacities=capacities, text_offsets=offsets,
                   block_bytes=text_offset + sum(capacities))

    @property
    def first_event_slot(self) -> int:
        """Text slot of the first event line (after the text fields)."""
        return len(self.text_capacities) - EVENT_LINES


# --- the fields a block declares --------------------------------------------------------------


class _Field:
    """A named value of a block, declared in a :class:`StatusBlock` subclass's body; placed when the class is made."""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name


class _CellField(_Field):
    """A number kept in one float64 cell.

    Parameters
    ----------
    doc : str
        What it holds, with its unit.
    """

    def __init__(self, doc: str):
        self.__doc__ = doc
        self.cell = -1  # placed by StatusBlock.__init_subclass__


class FloatField(_CellField):
    """A number kept in one float64 cell, read back as a float."""

    @overload
    def __get__(self, block: None, owner: type | None = None) -> Self: ...

    @overload
    def __get__(self, block: StatusBlock, owner: type | None = None) -> float: ...

    def __get__(self, block: StatusBlock | None, owner: type | None = None) -> float | Self:
        if block is None:
            return self
        return block._cells[self.cell]

    def __set__(self, block: StatusBlock, value: float) -> None:
        block._cells[self.cell] = value


class IntField(_CellField):
    """A count kept in one float64 cell (exact up to 2**53), read back as an int."""

    @overload
    def __get__(self, block: None, owner: type | None = None) -> Self: ...

    @overload
    def __get__(self, block: StatusBlock, owner: type | None = None) -> int: ...

    def __get__(self, block: StatusBlock | None, owner: type | None = None) -> int | Self:
        if block is None:
            return self
        return int(block._cells[self.cell])

    def __set__(self, block: StatusBlock, value: int) -> None:
        block._cells[self.cell] = value


class TextField(_Field):
    """UTF-8 text in a slot of its own, cut to ``capacity`` bytes at a character boundary.

    Parameters
    ----------
    capacity : int
        Most UTF-8 bytes kept.
    default : str
        What a new block holds.
    """

    def __init__(self, capacity: int, default: str = ""):
        self.capacity = capacity
        self.default = default
        self.slot = -1  # placed by StatusBlock.__init_subclass__

    def __set_name__(self, owner: type, name: str) -> None:
        super().__set_name__(owner, name)
        self.__doc__ = f"{name} (at most {self.capacity} UTF-8 bytes are kept)"

    @overload
    def __get__(self, block: None, owner: type | None = None) -> Self: ...

    @overload
    def __get__(self, block: StatusBlock, owner: type | None = None) -> str: ...

    def __get__(self, block: StatusBlock | None, owner: type | None = None) -> str | Self:
        if block is None:
            return self
        return block._read_text(self.slot)

    def __set__(self, block: StatusBlock, value: str) -> None:
        """One comparison unless the text changed (then encoded and stored under the slot's sequence number)."""
        if value == block._last_text[self.slot]:
            return
        block._write_text(self.slot, value)


class StateField(_Field):
    """A state kept as its code in the block's state cell; set from its name or its code, read back as its name.

    Parameters
    ----------
    names : sequence of str
        The states by code.
    what : str
        What the states are, for the error message.
    """

    def __init__(self, names: Sequence[str], what: str):
        self.names = tuple(names)
        self.codes = {name: code for code, name in enumerate(self.names)}
        self.what = what
        self.cell = -1  # placed by StatusBlock.__init_subclass__

    @overload
    def __get__(self, block: None, owner: type | None = None) -> Self: ...

    @overload
    def __get__(self, block: StatusBlock, owner: type | None = None) -> str: ...

    def __get__(self, block: StatusBlock | None, owner: type | None = None) -> str | Self:
        if block is None:
            return self
        return self.names[int(block._cells[self.cell])]

    def __set__(self, block: StatusBlock, value: str | int) -> None:
        code = value if isinstance(value, int) else self.codes.get(value, -1)  # an IntEnum member (an int), or a name
        if not 0 <= code < len(self.names):
            raise ValueError(f"unknown {self.what} {value!r}; expected one of {', '.join(self.names)}")
        block._cells[self.cell] = code


# --- the block's file --------------------------------------------------------------------------


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


def _create_block(size: int) -> tuple[mmap.mmap, str]:
    """A new zeroed block file of ``size`` bytes, mapped read-write with every page already resident; (map, path)."""
    fd, path = tempfile.mkstemp(prefix="harness-status-", suffix=".bin", dir=_shared_memory_dir())
    try:
        os.ftruncate(fd, size)
        block = mmap.mmap(fd, size)
    except BaseException:
        os.close(fd)
        os.unlink(path)
        raise
    os.close(fd)  # the map keeps its own reference to the file
    block[:] = bytes(size)  # touch every page now, not as a page fault inside a tick
    return block, path


def _open_block(path: str, size: int, writable: bool) -> mmap.mmap:
    """Map an existing block file of ``size`` bytes."""
    fd = os.open(path, os.O_RDWR if writable else os.O_RDONLY)
    try:
        if os.fstat(fd).st_size < size:
            raise ValueError(f"{path} is not a loop status block (too short)")
        return mmap.mmap(fd, size, access=mmap.ACCESS_WRITE if writable else mmap.ACCESS_READ)
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

    def __init__(self, buffer: mmap.mmap | bytearray, layout: BlockLayout):
        self.raw = memoryview(buffer)
        self.cells = self.raw[: layout.ring_offset].cast("d")
        self.numbers: np.ndarray | None = np.frombuffer(buffer, dtype=np.float64, count=N_CELLS)  # None once released
        self.ring_cells = self.raw[layout.ring_offset : layout.text_offset].cast("d")
        self.ring: np.ndarray | None = np.frombuffer(buffer, dtype=np.float64, count=LATENESS_RING_SIZE,
                                                    offset=layout.ring_offset)

    def release(self) -> None:
        """Drop every export of the underlying buffer held here."""
        self.cells.release()
        self.ring_cells.release()
        self.raw.release()
        self.numbers = self.ring = None


# --- the block ---------------------------------------------------------------------------------


class StatusBlock:
    """A status block in shared memory, with the fields a subclass declares in its class body.

    ``Subclass(**fields)`` creates a new block (this object owns it and removes it at
    :meth:`close`); :meth:`attach` maps an existing one (read-only by default) in another
    process. After :meth:`close` the object keeps its last values in private memory and
    stays readable and writable.

    A subclass declares its fields as class attributes (:class:`FloatField`,
    :class:`IntField`, :class:`TextField` and at most one :class:`StateField`); when the
    class is made they are placed in its :class:`BlockLayout` in the order declared.

    Parameters
    ----------
    **fields
        Initial values of any of the declared fields.

    Attributes
    ----------
    layout : BlockLayout
        Where each field and part lies (the subclass's).
    fields : tuple
        The declared fields, in the order declared.
    """

    __slots__ = ("_views", "_cells", "_ring_cells", "_block", "_path", "_owner", "_last_text", "_lateness_count",
                 "_finalizer", "__weakref__")

    layout: ClassVar[BlockLayout]
    fields: ClassVar[tuple[FloatField | IntField | TextField | StateField, ...]]

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        fields = tuple(value for value in vars(cls).values()
                       if isinstance(value, (FloatField, IntField, TextField, StateField)))
        numbers = [field for field in fields if isinstance(field, _CellField)]
        texts = [field for field in fields if isinstance(field, TextField)]
        states = [field for field in fields if isinstance(field, StateField)]
        if len(states) > 1:
            raise TypeError(f"{cls.__name__} declares {len(states)} state fields; a block has one state cell")
        layout = BlockLayout.of(len(numbers), [text.capacity for text in texts])
        for index, number in enumerate(numbers):
            number.cell = layout.first_number + index
        for index, text in enumerate(texts):
            text.slot = index
        for state in states:
            state.cell = layout.state
        cls.layout, cls.fields = layout, fields

    def __init__(self, **fields: object):
        block, path = _create_block(self.layout.block_bytes)
        self._bind(block, path, owner=True)
        try:
            self._cells[CELL_MAGIC] = MAGIC
            for field in self.fields:
                if isinstance(field, TextField):
                    setattr(self, field.name, field.default)
            names = {field.name for field in self.fields}
            for name, value in fields.items():
                if name not in names:
                    raise TypeError(f"{type(self).__name__}() got an unexpected keyword argument {name!r}")
                setattr(self, name, value)
        except BaseException:
            self.close()
            raise

    @classmethod
    def attach(cls, path: str | os.PathLike, writable: bool = False) -> Self:
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
        status._bind(_open_block(os.fspath(path), cls.layout.block_bytes, writable), os.fspath(path), owner=False)
        if status._cells[CELL_MAGIC] != MAGIC:
            status.close()
            raise ValueError(f"{path} is not a loop status block (bad magic number)")
        status._last_text = [status._read_text(i) for i in range(len(cls.layout.text_capacities))]
        status._lateness_count = int(status._cells[cls.layout.lateness_count])
        return status

    def _bind(self, block: mmap.mmap, path: str, owner: bool) -> None:
        self._block: mmap.mmap | None = block  # None once closed
        self._path = path
        self._owner = owner
        self._use_views(_Views(block, self.layout))
        #: The text last written to each text slot (None: not yet), to skip rewriting the same.
        self._last_text: list[str | None] = [None] * len(self.layout.text_capacities)
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
        self._use_views(_Views(private, self.layout))
        old.release()
        self._block = None
        self._finalizer()

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- finished and the lateness ring ------------------------------------------------------

    @property
    def finished(self) -> bool:
        """True once the writer's side has finished (the reader then draws its last frame)."""
        return self._cells[self.layout.finished] != 0.0

    @finished.setter
    def finished(self, value: bool) -> None:
        self._cells[self.layout.finished] = 1.0 if value else 0.0

    def add_lateness(self, lateness_s: float) -> None:
        """Record one tick's wake-up lateness (s) in the ring (no allocation that outlives the call)."""
        count = self._lateness_count
        self._ring_cells[count & _RING_MASK] = lateness_s
        count += 1
        self._lateness_count = count
        self._cells[self.layout.lateness_count] = count

    @property
    def lateness_count(self) -> int:
        """Lateness values recorded so far (the ring keeps the last 512)."""
        return int(self._cells[self.layout.lateness_count])

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
        cells, layout = self._cells, self.layout
        cells[layout.first_drift + index] = drift_m
        cells[layout.first_accel + index] = floor_acceleration_m_s2

    def story_values(self, count: int) -> list[tuple[float, float]]:
        """``(drift_m, floor_acceleration_m_s2)`` of stories 1 .. ``count`` (at most :data:`MAX_STORIES`), bottom up."""
        cells, layout = self._cells, self.layout
        count = min(max(count, 0), MAX_STORIES)
        return [(cells[layout.first_drift + j], cells[layout.first_accel + j]) for j in range(count)]

    def add_event(self, line: str) -> None:
        """Append one line to the ring of recent events (the oldest of :data:`EVENT_LINES` is dropped; allocates)."""
        count = int(self._cells[self.layout.event_count])
        self._write_text(self.layout.first_event_slot + count % EVENT_LINES, line)
        self._cells[self.layout.event_count] = count + 1

    @property
    def event_count(self) -> int:
        """Event lines added so far (the ring keeps the last :data:`EVENT_LINES`)."""
        return int(self._cells[self.layout.event_count])

    def recent_events(self) -> list[str]:
        """The most recent event lines, oldest first."""
        count = self.event_count
        first = max(0, count - EVENT_LINES)
        return [self._read_text(self.layout.first_event_slot + k % EVENT_LINES) for k in range(first, count)]

    # -- text slots under their sequence numbers ----------------------------------------------

    def _write_text(self, index: int, value: str | None) -> None:
        """Encode, truncate and store text slot ``index`` under its sequence number (allocates)."""
        text = "" if value is None else str(value)
        layout = self.layout
        encoded = truncate_utf8(text.encode("utf-8", "replace"), layout.text_capacities[index])
        offset, sequence = layout.text_offsets[index], layout.first_text + 2 * index
        cells = self._cells
        cells[sequence] += 1.0  # odd: being written
        self._views.raw[offset : offset + len(encoded)] = encoded
        cells[sequence + 1] = len(encoded)
        cells[sequence] += 1.0  # even: consistent
        self._last_text[index] = text

    def _read_text(self, index: int) -> str:
        """Text slot ``index`` as stored (retries while the writer is half-way through)."""
        layout = self.layout
        capacity = layout.text_capacities[index]
        offset, sequence = layout.text_offsets[index], layout.first_text + 2 * index
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
        """Every field's current value, by name, and ``finished`` (for tests and summaries)."""
        return {field.name: getattr(self, field.name) for field in self.fields} | {"finished": self.finished}

    def __repr__(self) -> str:
        fields = ", ".join(f"{name}={value!r}" for name, value in self.as_dict().items())
        return f"{type(self).__name__}({fields})"
