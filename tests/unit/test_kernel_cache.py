"""The "compiling the kernels" spinner shows only when numba's cache lacks a kernel."""

from __future__ import annotations

from types import SimpleNamespace

from harness.model.kernel_cache import kernels_cached
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


def test_cached_kernels_are_dropped_when_any_kernel_source_changes(tmp_path) -> None:
    from harness.model.kernel_cache import FINGERPRINT_NAME, drop_stale_kernels

    files = ("callee.py", "caller.py")
    for name in files:
        (tmp_path / name).write_text(f"# {name}\nCONSTANT = 1\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()

    def cached() -> list[str]:
        for stem in ("callee.f-1", "caller.g-2"):
            (cache / f"{stem}.py311.nbi").touch()
            (cache / f"{stem}.py311.1.nbc").touch()
        (cache / "other.h-3.py311.nbi").touch()  # another module's cache is not ours to drop
        return sorted(p.name for p in cache.glob("*.nb[ic]"))

    cached()
    assert drop_stale_kernels(tmp_path, files)  # no fingerprint yet: whatever is cached may be stale
    assert sorted(p.name for p in cache.glob("*.nb[ic]")) == ["other.h-3.py311.nbi"]
    before = cached()
    assert not drop_stale_kernels(tmp_path, files)  # nothing changed: the cache stays
    assert sorted(p.name for p in cache.glob("*.nb[ic]")) == before
    (tmp_path / "callee.py").write_text("# callee.py\nCONSTANT = 2\n")  # the callee changed, not the caller
    assert drop_stale_kernels(tmp_path, files)
    assert not list(cache.glob("caller.*.nb[ic]")) and not list(cache.glob("callee.*.nb[ic]"))
    assert (cache / FINGERPRINT_NAME).is_file()
