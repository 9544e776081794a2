"""harness.simulation.sampled: the per-sample arrays and loop the simulator and the rig twin share."""

from __future__ import annotations

import numpy as np
import pytest

from harness.simulation.sampled import CaseResult, CaseSamples, case_result


class Counter:
    """A plant whose state is the number of samples it advanced."""

    def __init__(self) -> None:
        self.y = np.zeros(2)

    def advance(self) -> None:
        self.y = self.y + 1.0


def run(n_samples: int, stop_at: int | None = None, progress=None) -> tuple[CaseSamples, Counter]:
    plant, samples = Counter(), CaseSamples(n_samples, 2, ("a_N", "b_m"))

    def sample(k: int) -> bool:
        samples.values["a_N"][k] = 10.0 * k
        samples.values["b_m"][k] = -k
        if k == stop_at:
            return False
        plant.advance()
        return True

    samples.run(plant, sample, progress)
    return samples, plant


def test_each_row_holds_the_state_at_its_sample():
    samples, plant = run(4)
    rows = samples.close(plant.y, ending={"a_N": 99.0}, held=("b_m",))
    assert rows == samples.rows == 5 and samples.taken == 4
    np.testing.assert_array_equal(samples.states[:, 0], [0, 1, 2, 3, 4])
    columns = samples.columns(("b_m", "a_N"))
    assert list(columns) == ["b_m", "a_N"]
    np.testing.assert_array_equal(columns["b_m"], [0, -1, -2, -3, -3])  # held from the last sample
    np.testing.assert_array_equal(columns["a_N"], [0, 10, 20, 30, 99])  # the value at the end


def test_a_sample_that_returns_false_ends_the_case_after_it():
    samples, plant = run(10, stop_at=3)
    assert samples.taken == 4
    samples.close(plant.y, held=("a_N",))
    np.testing.assert_array_equal(samples.states[:5, 0], [0, 1, 2, 3, 3])  # no advance after the last sample
    np.testing.assert_array_equal(samples.columns(("a_N", "b_m"))["a_N"], [0, 10, 20, 30, 30])
    np.testing.assert_array_equal(samples.columns(("b_m",))["b_m"], [0, -1, -2, -3, 0])  # neither held nor ending: 0


def test_progress_is_reported_about_every_five_percent_and_at_the_end():
    reports: list[float] = []
    run(100, progress=reports.append)
    assert reports == [k / 100 for k in range(0, 100, 5)] + [1.0]


def test_case_result_adds_peaks_and_wall_time():
    t = np.linspace(0.0, 1.0, 11)
    columns = {"t_s": t, "sliding_displacement_m": -0.02 * t, "base_acceleration_m_s2": np.sin(t),
               "drift_1_m": 0.001 * t, "floor_acceleration_1_m_s2": t, "force_command_N": 50.0 * t}
    result = case_result("controlled", columns, 1_000.0, 7, started_s=0.0, extra={"outcome": "completed"})
    assert isinstance(result, CaseResult)
    assert result.columns is columns and result.integrator_steps == 7 and result.wall_time_s > 0.0
    assert result.peaks.sliding_displacement_m == pytest.approx(0.02)
    assert result.peaks.peak_force_pct_weight == pytest.approx(5.0)
    assert result.extra == {"outcome": "completed"}
