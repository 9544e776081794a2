"""Memory for real-time buffers: allocated once and touched at once.

``numpy.zeros`` gets its pages from the operating system lazily: each page is committed
on first write. In a real-time buffer that first write happens inside a tick, as a page
fault (a latency spike), and the process's resident memory keeps creeping up while the
buffer fills, which looks like a leak. Every page of a buffer made here is written
before it is returned.
"""

from __future__ import annotations

from typing import cast

import numpy as np


def prefaulted_zeros(shape: int | tuple[int, ...], dtype: np.dtype | type = np.float64) -> np.ndarray:
    """An array of zeros whose every page is already resident.

    Parameters
    ----------
    shape : int or tuple of int
    dtype : numpy dtype
    """
    array = np.empty(shape, dtype=dtype)
    array.fill(0)
    return array


def float_view(array: np.ndarray) -> memoryview[float]:
    """A memoryview of the float64 ``array``: what a tick stores through (a third of a numpy item store).

    The same view as ``memoryview(array)``, typed: numpy's stubs give ``ndarray.data`` int items
    (and, for Python before 3.12, give an ndarray no buffer protocol at all).

    Raises
    ------
    TypeError
        ``array`` is not float64.
    """
    if array.dtype != np.float64:
        raise TypeError(f"found a {array.dtype} array, expected float64")
    return cast("memoryview[float]", array.data)
