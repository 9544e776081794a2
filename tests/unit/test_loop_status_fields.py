"""The loop status block's layout is the documented one, and every field has a place of its own.

:class:`harness.loop.status.LoopStatus` declares each field once, in its class body; the
block (:mod:`harness.loop.status_block`) places them when the class is made. These tests
hold that placement to the byte table in the block's docstring, check that no two fields
share a cell or a byte, and read every field back, through a second mapping as the
console's child does, as the type it is declared with.
"""

from __future__ import annotations

import re

import pytest

from harness.loop import status_block
from harness.loop.status import STATE_NAMES, LoopStatus
from harness.loop.status_block import (
    CELL_MAGIC,
    EVENT_LINE_BYTES,
    EVENT_LINES,
    LATENESS_RING_SIZE,
    MAX_STORIES,
    N_CELLS,
    FloatField,
    IntField,
    StateField,
    StatusBlock,
    TextField,
)

LAYOUT = LoopStatus.layout


def _documented_ranges() -> list[tuple[int, int]]:
    """The ``start .. end`` byte ranges of the docstring's table, top to bottom."""
    doc = status_block.__doc__ or ""
    return [(int(a), int(b)) for a, b in re.findall(r"^(\d+) \.\. (\d+) ", doc, re.M)]


def test_the_block_is_laid_out_as_its_docstring_says() -> None:
    assert _documented_ranges() == [
        (0, LAYOUT.ring_offset), (LAYOUT.ring_offset, LAYOUT.text_offset), (LAYOUT.text_offset, LAYOUT.block_bytes),
    ]
    doc = status_block.__doc__ or ""
    assert f"{N_CELLS} float64 cells" in doc and f"up to {MAX_STORIES} stories" in doc
    assert LAYOUT.ring_offset == 8 * N_CELLS and f"most recent {LATENESS_RING_SIZE} lateness values" in doc
    texts = [field for field in LoopStatus.fields if isinstance(field, TextField)]
    for field in texts:
        assert f"{field.name} {field.capacity}" in doc, field.name
    assert f"{EVENT_LINES} most recent event" in doc and f"({EVENT_LINE_BYTES} each)" in doc


def test_every_field_has_a_cell_or_a_slot_of_its_own() -> None:
    numbers = [field for field in LoopStatus.fields if isinstance(field, (FloatField, IntField))]
    texts = [field for field in LoopStatus.fields if isinstance(field, TextField)]
    states = [field for field in LoopStatus.fields if isinstance(field, StateField)]
    assert len(states) == 1 and states[0].cell == LAYOUT.state
    structure = [CELL_MAGIC, LAYOUT.state, LAYOUT.finished, LAYOUT.lateness_count, LAYOUT.event_count]
    structure += [LAYOUT.first_text + k for k in range(2 * len(LAYOUT.text_capacities))]
    structure += [LAYOUT.first_drift + j for j in range(MAX_STORIES)] + [LAYOUT.first_accel + j for j in range(MAX_STORIES)]
    cells = [field.cell for field in numbers] + structure
    assert len(set(cells)) == len(cells), "two things share a cell"
    assert all(0 <= cell < N_CELLS for cell in cells)
    assert [field.slot for field in texts] == list(range(len(texts)))
    assert LAYOUT.text_capacities == (*(field.capacity for field in texts), *(EVENT_LINE_BYTES,) * EVENT_LINES)
    ends = [offset + capacity for offset, capacity in zip(LAYOUT.text_offsets, LAYOUT.text_capacities, strict=True)]
    assert LAYOUT.text_offsets[0] == LAYOUT.text_offset and list(LAYOUT.text_offsets[1:]) == ends[:-1], "slots tile"
    assert ends[-1] == LAYOUT.block_bytes


def _distinct_value(field: object, k: int) -> object:
    if isinstance(field, StateField):
        return STATE_NAMES[-1]
    if isinstance(field, IntField):
        return 1000 + k
    if isinstance(field, FloatField):
        return 0.5 + k
    assert isinstance(field, TextField)
    return f"{field.name} é {k}"


def test_each_field_reads_back_in_another_mapping_as_the_type_it_is_declared_with() -> None:
    values = {field.name: _distinct_value(field, k) for k, field in enumerate(LoopStatus.fields)}
    kinds = {FloatField: float, IntField: int, TextField: str, StateField: str}
    with LoopStatus(**values) as status:
        reader = LoopStatus.attach(status.path)
        try:
            read = reader.as_dict()
            assert read == {**values, "finished": False}, "a field changed another's cell or slot"
            for field in LoopStatus.fields:
                assert type(getattr(reader, field.name)) is kinds[type(field)], field.name
        finally:
            reader.close()


def test_a_block_whose_cells_do_not_fit_is_refused_when_its_class_is_made() -> None:
    too_many = {f"x{k}": FloatField(f"number {k}") for k in range(N_CELLS)}
    with pytest.raises(ValueError, match="cells"):
        type("Crowded", (StatusBlock,), {"__slots__": (), **too_many})
    with pytest.raises(TypeError, match="state fields"):
        type("TwoStates", (StatusBlock,), {"__slots__": (), "a": StateField(("X",), "x"), "b": StateField(("Y",), "y")})
