"""JSON that every parser reads: a value that is not a finite number is written ``null``.

Python's :mod:`json` writes a NaN or an infinity as the bare words ``NaN`` and ``Infinity``,
which are not JSON: parsers of other languages (and ``jq``) reject the whole file. Every
file of run data (``metadata.json``, ``events.jsonl``, ``sweep.json``, ``harness simulate
--json``) is written through :func:`dumps`: :func:`plain` first turns the data into plain
JSON values, with ``None`` for every non-finite float, then :func:`json.dumps` runs with
``allow_nan=False``, so a non-finite number that slipped past is an error, never a file
that is not JSON.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import Any

Default = Callable[[Any], Any]


def _no_default(value: Any) -> Any:
    raise TypeError(f"found {type(value).__name__}, expected JSON data (numbers, strings, lists, mappings)")


def plain(value: Any, default: Default = _no_default) -> Any:
    """``value`` as plain JSON data: dicts with text keys, lists, text, bools, ints, finite floats and None.

    Parameters
    ----------
    value : any
        Mappings, sequences (lists, tuples, sets), numbers (numpy scalars and arrays
        included: anything with ``tolist``), text, None.
    default : callable, optional
        Turns any other value (a path, a time) into JSON data, which is made plain in turn;
        it raises TypeError for a value it does not know.

    Returns
    -------
    any
        The same data, with ``None`` where a float was NaN or infinite.
    """
    if value is None or isinstance(value, (str, bool, int)):
        return value
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, Mapping):
        return {str(key): plain(item, default) for key, item in value.items()}
    if isinstance(value, (list, tuple, set, frozenset)):
        return [plain(item, default) for item in value]
    if hasattr(value, "tolist"):  # numpy scalars and arrays
        return plain(value.tolist(), default)
    return plain(default(value), default)


def dumps(value: Any, default: Default = _no_default, **options: Any) -> str:
    """:func:`json.dumps` of :func:`plain` ``(value, default)``, refusing any non-finite number.

    ``options`` go to :func:`json.dumps` (``indent``, ``sort_keys``...).
    """
    return json.dumps(plain(value, default), allow_nan=False, **options)


def loads(text: str) -> Any:
    """Parse ``text`` as strict JSON: ``NaN``, ``Infinity`` and ``-Infinity`` are refused (ValueError).

    What a parser of another language does; tests read the harness's files with it.
    """
    return json.loads(text, parse_constant=_refuse_constant)


def _refuse_constant(name: str) -> Any:
    raise ValueError(f"{name} is not JSON (expected a number or null)")
