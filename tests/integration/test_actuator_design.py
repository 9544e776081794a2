"""The actuator-aware designs on the servo-hydraulic twin (harness simulate --rig-effects).

El Centro at 0.34 g, time scale 2, the first 12 s (the strong motion): the phi controller
commanding the cylinder through a plain force loop (a servo controller without velocity
feed-forward) amplifies the drifts (the loop's 94 kN s/m damper drags the base mat along with the
table); the actuator-aware designs reduce them, and so does the shipped servo controller's
velocity feed-forward (SPEC 7a') under the unchanged phi controller.
"""

from __future__ import annotations

import numpy as np
import pytest

from harness.control.controllers import PhiSMC
from harness.motions import load_motion
from harness.profile import load_profile
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study
from harness.simulation.twin import run_rig_twin
from tests.conftest import PROFILES

DESIGNS = ("phi", "phi-A", "FSF-A")
#: A servo controller without velocity feed-forward, what the actuator-aware designs are built for.
PLAIN_LOOP = ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0"]


def _el_centro(records_dir, name: str = "phi") -> StudyOptions:
    return StudyOptions(record="el_centro", records_dir=str(records_dir), pga_g=0.34, time_scale=2.0,
                        duration_s=12.0, controller=name, rig_effects=True)


@pytest.fixture(scope="module")
def studies(records_dir):
    profile = load_profile(PROFILES / "nceer_4dof.yaml", overrides=PLAIN_LOOP)
    results = {}
    for name in DESIGNS:
        options = StudyOptions(record="el_centro", records_dir=str(records_dir), pga_g=0.34, time_scale=2.0,
                               duration_s=12.0, controller=name, rig_effects=True)
        results[name] = run_study(profile, options)
    return results


def _drift_reductions(study) -> list[float]:
    passive = study.cases["passive"].peaks.flatten()
    controlled = study.cases["controlled"].peaks.flatten()
    return [100.0 * (1.0 - controlled[f"drift_{j}_m"] / passive[f"drift_{j}_m"]) for j in (1, 2, 3)]


def test_the_phi_controller_through_the_force_loop_amplifies_the_drifts(studies):
    assert max(_drift_reductions(studies["phi"])) < 0.0


def test_the_phi_controller_through_the_shipped_feedforward_reduces_every_drift(records_dir):
    study = run_study(load_profile(PROFILES / "nceer_4dof.yaml"), _el_centro(records_dir))
    assert study.cases["controlled"].extra["outcome"] == "completed"
    assert min(_drift_reductions(study)) > 0.0, _drift_reductions(study)


@pytest.mark.parametrize("name", ["phi-A", "FSF-A"])
def test_an_actuator_aware_design_reduces_every_story_drift_where_phi_amplifies_it(studies, name):
    study = studies[name]
    assert study.cases["controlled"].extra["outcome"] == "completed"
    assert min(_drift_reductions(study)) > 25.0, _drift_reductions(study)


def test_the_output_design_reads_the_rig_the_full_state_one_the_twin_state(studies):
    assert studies["phi-A"].cases["controlled"].extra["state_source"] == "measured"
    offline = studies["FSF-A"].to_json()["sampling"]["controller_state"]
    assert offline == "true plant state (offline design study)"


class _LoadCellSpy(PhiSMC):
    """The phi controller, keeping the load-cell force it was handed at each sample."""

    def __init__(self, samples: int):
        super().__init__("spy", 1148.62, 71616.36, 8.0, 0.8, 0.0)
        self.seen = np.full(samples, np.nan)
        self._k = 0

    def update(self, t, dt, meas, friction_N, state=None):
        self.seen[self._k] = meas.actuator_force_N
        self._k += 1
        return super().update(t, dt, meas, friction_N, state)


def test_the_twin_hands_the_controller_the_actuator_force():
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=2.0)
    spy = _LoadCellSpy(1000)
    result = run_rig_twin(profile, motion, 500.0, spy)
    measured = result.columns["force_measured_N"][:-1]
    np.testing.assert_array_equal(spy.seen, measured)
    assert np.max(np.abs(measured)) > 100.0  # the cylinder pushed: the values are not the default 0
