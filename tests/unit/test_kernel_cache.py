"""The "compiling the kernels" spinner shows only when numba's cache lacks a kernel."""

from __future__ import annotations

from types import SimpleNamespace

from harness.kernel_cache import kernels_cached
from harness.model.warmup import warm_up


def _dispatcher(index: dict) -> SimpleNamespace:
    return SimpleNamespace(_cache=SimpleNamespace(_cache_file=SimpleNamespace(_load_index=lambda: index)), py_func=None)


def test_every_kernel_in_the_index_means_cached_and_one_missing_means_not() -> None:
    assert kernels_cached([_dispatcher({"sig": 1}), _dispatcher({"sig": 2})]) is True
    assert kernels_cached([_dispatcher({"sig": 1}), _dispatcher({})]) is False


def test_a_cache_that_works_differently_is_not_known() -> None:
    assert kernels_cached([SimpleNamespace(_cache=None)]) is None


def test_after_a_warm_up_the_real_kernels_are_cached() -> None:
    warm_up()
    assert kernels_cached() is True
