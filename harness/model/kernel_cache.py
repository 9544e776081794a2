"""Whether numba's on-disk cache already holds the integration kernels, so a command can say "compiling" only when it will.

:func:`harness.model.warmup.warm_up` calls every numba kernel once; from a warm cache that
loads them in about half a second, after an edit of their source (or on a fresh checkout)
it compiles them, which takes up to a minute. :func:`kernels_cached` asks numba's cache
index of each kernel, before anything is loaded, whether it holds an entry for the
kernel's current source (numba keys its index by the source file's time stamp and size).

Numba keys each kernel's cache on its own source file alone, and freezes the globals it
reads (constants such as :mod:`harness.hydraulics.cylinder`' parameter offsets) and the
kernels it calls into the compiled code. A change to a callee's file would leave a caller
compiled against the old one. :func:`drop_stale_kernels` therefore fingerprints every file
that holds kernels (in :mod:`harness.model` and :mod:`harness.hydraulics`) and, when the
fingerprint changed, removes their cached code from each file's ``__pycache__``, so every
kernel compiles again. :mod:`harness.model` calls it when first imported, before the
integrator, the one caller across the two folders, is loaded.
"""

from __future__ import annotations

import hashlib
import importlib
from collections.abc import Iterable
from pathlib import Path
from typing import Any

#: The folder the kernel files are named from: the ``harness`` package.
KERNEL_DIR = Path(__file__).resolve().parent.parent
#: The files that hold numba kernels which call one another, relative to :data:`KERNEL_DIR`.
KERNEL_FILES = ("model/bearing.py", "hydraulics/cylinder.py", "model/integrator.py")
#: Where the fingerprint of the kernels' sources is kept (``KERNEL_DIR/__pycache__``).
FINGERPRINT_NAME = "kernel_sources.sha256"

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


def kernel_fingerprint(directory: Path = KERNEL_DIR, files: Iterable[str] = KERNEL_FILES) -> str:
    """SHA-256 over the kernels' source files (their names and contents)."""
    digest = hashlib.sha256()
    for name in files:
        digest.update(name.encode())
        digest.update((directory / name).read_bytes())
    return digest.hexdigest()


def _cached_code(directory: Path, files: tuple[str, ...]) -> list[Path]:
    """numba's cache files (index and code) of the kernels in ``files``, each in its own folder's ``__pycache__``."""
    found: list[Path] = []
    for name in files:
        source = directory / name
        cache = source.parent / "__pycache__"
        if cache.is_dir():
            found.extend(path for path in cache.glob("*.nb[ic]") if path.name.startswith(source.stem + "."))
    return found


def drop_stale_kernels(directory: Path = KERNEL_DIR, files: Iterable[str] = KERNEL_FILES) -> bool:
    """Remove numba's cached kernels of ``files`` (relative to ``directory``) when any of their sources changed.

    Returns True if cached code was removed. Does nothing, quietly, where a cache folder
    cannot be written (numba then uses its own cache folder, keyed the same way).
    """
    files = tuple(files)
    cache = directory / "__pycache__"
    stamp = cache / FINGERPRINT_NAME
    try:
        fingerprint = kernel_fingerprint(directory, files)
        if stamp.is_file() and stamp.read_text().strip() == fingerprint:
            return False
        stale = _cached_code(directory, files)
        for path in stale:
            path.unlink(missing_ok=True)
        cache.mkdir(exist_ok=True)
        stamp.write_text(fingerprint + "\n")
        return bool(stale)
    except OSError:
        return False
