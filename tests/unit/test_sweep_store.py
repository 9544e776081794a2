"""The results folder: rows written in parts as they come, merged, read back, resumable; CSV without pyarrow."""

from __future__ import annotations

import math

import pytest

from harness.sweep.store import ResultStore, have_pyarrow


def _row(i: int, outcome: str = "ok", **extra) -> dict:
    row = {"case_id": f"{i:020d}", "case_index": i, "record": "synthetic:1", "pga_g": 0.1 * i, "controller": "OF-I",
           "outcome": outcome, "error": "" if outcome == "ok" else "ValueError: no", "wall_time_s": 0.1}
    if outcome == "ok":
        row["passive.sliding_displacement_m"] = 0.01 * i
    return {**row, **extra}


FORMATS = [pytest.param(True, id="parquet", marks=pytest.mark.skipif(not have_pyarrow(), reason="pyarrow not installed")),
           pytest.param(False, id="csv")]


@pytest.mark.parametrize("parquet", FORMATS)
def test_rows_are_written_as_parts_and_merged(tmp_path, parquet):
    store = ResultStore(tmp_path, parquet=parquet)
    for i in range(3):
        store.append(_row(i))
    store.append(_row(3, "failed"))
    store.flush()
    assert len(list((tmp_path / "parts").iterdir())) == 1
    again = ResultStore(tmp_path, parquet=parquet)  # a second process reads what the first wrote
    assert again.outcomes() == {f"{i:020d}": "ok" for i in range(3)} | {f"{3:020d}": "failed"}
    main = store.compact()
    assert main.is_file() and not list((tmp_path / "parts").iterdir())
    assert (tmp_path / "cases.csv").is_file()
    rows = ResultStore(tmp_path, parquet=parquet).rows()
    assert [row["case_index"] for row in rows] == [0, 1, 2, 3]
    assert rows[0]["case_id"] == "0" * 20, "a key of digits stays text"
    assert rows[3]["error"] == "ValueError: no"
    failed_peak = rows[3]["passive.sliding_displacement_m"]
    assert failed_peak is None or math.isnan(failed_peak)
    columns = ResultStore(tmp_path, parquet=parquet).columns()
    assert columns["passive.sliding_displacement_m"][1] == pytest.approx(0.01)


@pytest.mark.parametrize("parquet", FORMATS)
def test_a_case_run_again_keeps_its_latest_row(tmp_path, parquet):
    store = ResultStore(tmp_path, parquet=parquet)
    store.append(_row(0, "failed"))
    store.append(_row(1))
    store.compact()
    store.append(_row(0))
    store.flush()
    assert ResultStore(tmp_path, parquet=parquet).outcomes()[f"{0:020d}"] == "ok"
    assert len(ResultStore(tmp_path, parquet=parquet).rows()) == 2


def test_parts_are_flushed_every_so_many_rows(tmp_path):
    from harness.sweep import store as store_module

    store = ResultStore(tmp_path)
    for i in range(store_module.FLUSH_ROWS + 1):
        store.append(_row(i))
    assert len(list((tmp_path / "parts").iterdir())) == 1, "a part as soon as FLUSH_ROWS rows are buffered"
