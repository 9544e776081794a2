"""``harness simulate`` (ideal and with rig effects, the twin) builds its friction estimator with ``control.estimator``.

A dry run's session is covered in tests/integration/test_rig_truth_runs.py. Each test fails if a
run built its estimator on the bearing's yield displacement instead of the estimator's own.
"""

from __future__ import annotations

import pytest

from harness.control import factory
from harness.control.estimator import FrictionEstimator
from harness.profile import load_profile
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study
from tests.conftest import PROFILES

SOURCE_D_Y = ["control.estimator.yield_displacement_m=null"]


@pytest.fixture
def built_yields_m(monkeypatch) -> list[float]:
    yields: list[float] = []

    class Recorded(FrictionEstimator):
        def __init__(self, bearing, total_weight_N: float):
            super().__init__(bearing, total_weight_N)
            yields.append(bearing.yield_displacement_m)

    monkeypatch.setattr(factory, "FrictionEstimator", Recorded)
    return yields


@pytest.mark.parametrize("rig_effects", [False, True], ids=["ideal", "twin"])
def test_simulate_builds_the_estimator_with_its_own_yield_displacement(built_yields_m, rig_effects: bool) -> None:
    options = StudyOptions(duration_s=0.5, rig_effects=rig_effects)
    run_study(load_profile(PROFILES / "nceer_4dof.yaml"), options)
    run_study(load_profile(PROFILES / "nceer_4dof.yaml", overrides=SOURCE_D_Y), options)
    assert built_yields_m == pytest.approx([6.5e-5, 2.54e-5])  # the setting, then (null) the bearing's D_y
