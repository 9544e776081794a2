"""Whether numba's on-disk cache already holds the integration kernels, so a command can say "compiling" only when it will.

:func:`harness.model.warmup.warm_up` calls every numba kernel once; from a warm cache that
loads them in about half a second, after an edit of their source (or on a fresh checkout)
it compiles them, which takes up to a minute. :func:`kernels_cached` asks numba's cache
index of each kernel, before anything is loaded, whether it holds an entry for the
kernel's current source (numba keys its index by the source file's time stamp and size).
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable
from typing import Any

#: The module whose numba dispatchers :func:`harness.model.warmup.warm_up` calls.
WARMUP_MODULE = "harness.model.warmup"


def _dispatchers(module_name: str = WARMUP_MODULE) -> list[Any]:
    """The numba dispatchers the warm-up module imports (objects with a ``_cache``)."""
    module = importlib.import_module(module_name)
    return [value for value in vars(module).values() if hasattr(value, "_cache") and hasattr(value, "py_func")]


def _cached(dispatcher: Any) -> bool:
    """True if the dispatcher's cache index lists a compiled overload for its current source."""
    index = dispatcher._cache._cache_file._load_index()  # {} when missing or written for another version of the source
    return bool(index)


def kernels_cached(dispatchers: Iterable[Any] | None = None) -> bool | None:
    """True if every warm-up kernel is in numba's cache for its current source, False if one is not.

    Returns None when it cannot be told (a numba whose cache works differently): a caller then
    treats it as "may compile".
    """
    try:
        found = list(dispatchers) if dispatchers is not None else _dispatchers()
        return bool(found) and all(_cached(dispatcher) for dispatcher in found)
    except (AttributeError, OSError, EOFError, ValueError, TypeError):
        return None
