"""The one peaks model (harness.signals.peaks) against the columns it comes from."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from harness.recording import load_run, write_simulation_case
from harness.recording.peaks import run_peaks
from harness.signals.peaks import (
    Peaks,
    force_column,
    peak_abs,
    peak_responses,
    reduction_pct,
)

WEIGHT_N = 1000.0


def _columns(n_stories: int = 2) -> dict[str, np.ndarray]:
    t = np.linspace(0.0, 1.0, 11)
    columns = {"t_s": t, "sliding_displacement_m": -0.02 * t, "base_acceleration_m_s2": 3.0 * np.sin(4 * t),
               "table_acceleration_m_s2": -2.5 * t, "table_velocity_m_s": 0.1 * t, "table_displacement_m": 0.03 * t}
    for j in range(1, n_stories + 1):
        columns[f"drift_{j}_m"] = 0.001 * j * t
        columns[f"floor_acceleration_{j}_m_s2"] = -(1.0 + j) * t
    return columns


def test_peaks_are_the_largest_finite_magnitudes_bottom_up() -> None:
    columns = _columns() | {"force_command_N": 50.0 * np.linspace(-1, 0.5, 11)}
    columns["drift_2_m"][3] = np.nan
    peaks = peak_responses(columns, WEIGHT_N)
    assert peaks.sliding_displacement_m == pytest.approx(0.02)
    assert peaks.drift_m == pytest.approx((0.001, 0.002)) and peaks.floor_acceleration_m_s2 == pytest.approx((2.0, 3.0))
    assert peaks.peak_force_pct_weight == pytest.approx(5.0)
    assert (peaks.table_acceleration_m_s2, peaks.table_displacement_m) == pytest.approx((2.5, 0.03))
    assert peaks.n_stories == 2


def test_as_json_is_the_layout_of_simulate_json() -> None:
    peaks = peak_responses(_columns(3) | {"force_command_N": np.zeros(11)}, WEIGHT_N)
    doc = json.loads(json.dumps(peaks.as_json()))
    assert list(doc) == ["sliding_displacement_m", "base_acceleration_m_s2", "drift_m", "floor_acceleration_m_s2",
                         "peak_force_pct_weight"]
    assert len(doc["drift_m"]) == 3 and doc["peak_force_pct_weight"] == 0.0


def test_flatten_names_every_peak_by_its_column() -> None:
    flat = peak_responses(_columns(2), WEIGHT_N).flatten()
    assert list(flat) == ["sliding_displacement_m", "base_acceleration_m_s2", "drift_1_m", "drift_2_m",
                          "floor_acceleration_1_m_s2", "floor_acceleration_2_m_s2", "peak_force_pct_weight"]
    assert flat["drift_2_m"] == pytest.approx(0.002)


def test_no_force_column_is_a_passive_case_and_an_unrecorded_force_is_nan() -> None:
    assert peak_responses(_columns(), WEIGHT_N).peak_force_pct_weight == 0.0
    unrecorded = _columns() | {"force_command_N": np.full(11, np.nan)}
    assert math.isnan(peak_responses(unrecorded, WEIGHT_N).peak_force_pct_weight)
    assert peak_responses(unrecorded, WEIGHT_N, passive=True).peak_force_pct_weight == 0.0
    assert math.isnan(peak_responses(_columns(), WEIGHT_N, passive=False).peak_force_pct_weight)


def test_the_raw_force_stands_in_for_an_unrecorded_command() -> None:
    columns = _columns() | {"force_command_N": np.full(11, np.nan), "force_raw_N": np.full(11, -30.0)}
    assert force_column(columns) == "force_raw_N"
    assert peak_responses(columns, WEIGHT_N).peak_force_pct_weight == pytest.approx(3.0)


def test_absent_columns_and_weight_give_nan() -> None:
    peaks = peak_responses({"t_s": np.arange(3.0), "force_command_N": np.array([1.0, -4.0, 2.0])}, None)
    assert peaks.drift_m == () and math.isnan(peaks.sliding_displacement_m)
    assert math.isnan(peaks.peak_force_pct_weight) and math.isnan(peaks.measured_force_pct_weight)
    assert peak_abs(np.array([np.nan])) is None


def test_run_peaks_take_weight_and_passive_from_the_metadata(tmp_path: Path) -> None:
    columns = ("t_s", "force_command_N", "force_measured_N")
    t = np.arange(4.0)
    folder = write_simulation_case(
        tmp_path, "a", columns,
        {"t_s": t, "force_command_N": np.array([0, 100.0, -300, 0]), "force_measured_N": np.array([0, 90.0, -280, 5])},
        {"total_weight_N": WEIGHT_N},
    )
    peaks = run_peaks(load_run(folder))
    assert peaks.peak_force_pct_weight == pytest.approx(30.0)
    assert peaks.measured_force_pct_weight == pytest.approx(28.0)
    unrecorded = write_simulation_case(tmp_path, "passive", ("t_s", "force_command_N"),
                                       {"t_s": t, "force_command_N": np.full(4, np.nan)}, {"total_weight_N": WEIGHT_N})
    assert run_peaks(load_run(unrecorded)).peak_force_pct_weight == 0.0  # the passive case of a simulation


def test_run_peaks_equal_the_peaks_of_the_columns_written(tmp_path: Path) -> None:
    columns = _columns(3) | {"force_command_N": 70.0 * np.sin(np.arange(11.0))}
    folder = write_simulation_case(tmp_path, "controlled", tuple(columns), columns, {"total_weight_N": WEIGHT_N})
    assert run_peaks(load_run(folder)).flatten() == pytest.approx(peak_responses(columns, WEIGHT_N).flatten(), rel=1e-9)


@pytest.mark.parametrize(
    ("passive", "hybrid", "expected"),
    [(10.0, 4.0, 60.0), (10.0, 12.0, -20.0), (0.0, 1.0, None), (None, 1.0, None), (float("nan"), 1.0, None)],
)
def test_reduction_pct_follows_the_spec_definition(passive, hybrid, expected) -> None:
    assert reduction_pct(passive, hybrid) == (pytest.approx(expected) if expected is not None else None)


@pytest.mark.parametrize(
    ("passive", "hybrid"),
    [
        (1.9e-15, 1.0e-5),  # a drift reference of a run that tripped before its record started (-5e11 %)
        (2.7e-8, 0.040),  # its base acceleration: -1.5e8 %
        (1e-7, 1e-7),  # numerically zero, however the controlled case compares
        (1e-4, 0.2),  # a reference 2000 times below the response: below -99 900 %
    ],
)
def test_no_reduction_against_a_reference_that_is_zero_or_off_the_response_scale(passive, hybrid) -> None:
    assert reduction_pct(passive, hybrid) is None


def test_a_large_growth_against_a_real_reference_is_still_shown() -> None:
    assert reduction_pct(0.0149, 0.0317) == pytest.approx(-112.75, abs=0.01)  # Pacoima's sliding displacement under phi
    assert reduction_pct(1e-3, 0.9) == pytest.approx(-89_900.0)  # 900 times the reference: at the floor, shown


def test_peaks_are_frozen() -> None:
    peaks = Peaks(0.1, 1.0, (0.01,), (2.0,), 0.0)
    with pytest.raises(AttributeError):
        peaks.sliding_displacement_m = 0.2  # type: ignore[misc]
