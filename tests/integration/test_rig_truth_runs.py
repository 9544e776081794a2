"""``rig.truth`` reaches the rig and nothing else: the twin, ``harness simulate`` and a dry run.

Each test would fail if the truth stopped reaching the rig's plant (the behaviour would not
change), or if it leaked into the controller, the friction estimator or the ideal simulation
(they would see the true values).
"""

from __future__ import annotations

import io
import json

import numpy as np
import pytest
from rich.console import Console

from harness.control import factory
from harness.control.estimator import FrictionEstimator
from harness.control.factory import build_controller_for_rig
from harness.motions import load_motion
from harness.profile import load_profile
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study
from harness.simulation.twin import run_rig_twin
from tests.conftest import PROFILES

RATE_HZ = 500.0
#: A rig whose bearings grip twice as hard and whose springs are half as stiff as the design says.
TRUTH = ("rig.truth.bearing.mu_max=0.12", "rig.truth.bearing.mu_delta=0.06",
         "rig.truth.structure.restoring_stiffness_N_per_m=35000")


class _Recorded(FrictionEstimator):
    """The estimator, remembering the parameters it was built with."""

    built: list[tuple[float, float]] = []
    yields_m: list[float] = []

    def __init__(self, bearing, total_weight_N: float):
        super().__init__(bearing, total_weight_N)
        _Recorded.built.append((bearing.mu_max, total_weight_N))
        _Recorded.yields_m.append(bearing.yield_displacement_m)


@pytest.fixture
def recorded(monkeypatch):
    _Recorded.built, _Recorded.yields_m = [], []
    # every run builds its estimator in the one factory (simulate, the twin and a session alike)
    monkeypatch.setattr(factory, "FrictionEstimator", _Recorded)
    return _Recorded


def _twin(monkeypatch, recorded, overrides: tuple[str, ...]):
    # The force-source rig: the servo-hydraulic actuator's velocity feedback would dominate the force.
    profile = load_profile(PROFILES / "nceer_4dof.yaml", variant="force_source", overrides=overrides)
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=3.0)
    controller = build_controller_for_rig(profile, "phi")
    return controller, run_rig_twin(profile, motion, RATE_HZ, controller)


def test_the_twin_integrates_the_truth_while_its_controller_and_estimator_keep_the_design(monkeypatch, recorded):
    design_controller, design = _twin(monkeypatch, recorded, ())
    true_controller, true = _twin(monkeypatch, recorded, TRUTH)
    weight = load_profile(PROFILES / "nceer_4dof.yaml").structure.total_weight_N
    assert recorded.built == [(0.06, weight), (0.06, weight)]  # the estimator: the design's bearing, both times
    assert recorded.yields_m == pytest.approx([6.5e-5, 6.5e-5])  # with its own yield displacement (control.estimator)
    assert true_controller.restoring_stiffness_N_per_m == design_controller.restoring_stiffness_N_per_m == 71616.36
    # the plant is not the design's: a stiffer grip and softer springs change what the controller has to do
    design_force, true_force = design.peaks.peak_force_pct_weight, true.peaks.peak_force_pct_weight
    assert abs(true_force - design_force) > 0.05 * design_force, (design_force, true_force)


def test_simulate_applies_the_truth_with_rig_effects_only(monkeypatch):
    built: list = []
    original = factory.build_controller

    def recording(name, design, design_building):
        built.append(design_building)
        return original(name, design, design_building)

    monkeypatch.setattr("harness.control.factory.build_controller", recording)
    options = StudyOptions(duration_s=2.0)
    design_profile = load_profile(PROFILES / "nceer_4dof.yaml")
    true_profile = load_profile(PROFILES / "nceer_4dof.yaml", overrides=TRUTH)
    ideal_design, ideal_true = run_study(design_profile, options), run_study(true_profile, options)
    # the ideal simulation is the design's world: rig.truth changes nothing there
    for case in ("passive", "controlled"):
        np.testing.assert_equal(ideal_true.cases[case].peaks.flatten(), ideal_design.cases[case].peaks.flatten())
    assert "rig_truth" not in ideal_true.to_json()
    rig_options = StudyOptions(duration_s=2.0, rig_effects=True)
    twin_design, twin_true = run_study(design_profile, rig_options), run_study(true_profile, rig_options)
    # with rig effects the passive reference is the rig's: the same passive test on the true rig
    design_sliding = twin_design.cases["passive"].peaks.sliding_displacement_m
    true_sliding = twin_true.cases["passive"].peaks.sliding_displacement_m
    assert abs(true_sliding - design_sliding) > 0.05 * design_sliding, (design_sliding, true_sliding)
    assert "bearing.mu_max 0.12 (design 0.06)" in twin_true.to_json()["rig_truth"]["summary"]
    assert "rig_truth" not in twin_design.to_json()
    assert {b.restoring_stiffness_N_per_m for b in built} == {71616.36}  # every controller: the design's springs


def test_a_dry_run_serves_the_truth_and_says_so(tmp_path, monkeypatch, recorded):
    from harness.rig import virtual_rig
    from harness.runs import dry_run as dry_run_module

    rigs: list = []
    original_init = virtual_rig.VirtualRig.__init__

    def remember(self, *args, **kwargs):
        original_init(self, *args, **kwargs)
        rigs.append(self)

    passive_plants: list = []
    original_plant = dry_run_module.Plant

    def plant(building, bearing, *args, **kwargs):
        passive_plants.append(bearing)
        return original_plant(building, bearing, *args, **kwargs)

    monkeypatch.setattr(virtual_rig.VirtualRig, "__init__", remember)
    monkeypatch.setattr(dry_run_module, "Plant", plant)
    profile = load_profile(PROFILES / "nceer_4dof.yaml", overrides=["rig.truth.bearing.mu_max=0.075"])
    options = dry_run_module.DryRunOptions(
        study=StudyOptions(duration_s=1.0), interface="virtual", channel="truth-test", log_dir=str(tmp_path),
        lockstep=True, show_console=True,
    )
    console = Console(file=io.StringIO(), width=200, color_system=None)
    result = dry_run_module.dry_run(profile, options, console)
    assert result.session.outcome == "completed"
    (rig,) = rigs
    assert rig.table.record.bearing.mu_max == 0.075  # the rig's plant: the truth
    # the loop's estimator and its simulated twin's (harness.runs.dry_run.simulated_twins): the design's bearing ...
    assert [mu for mu, _ in recorded.built] == [0.06, 0.06]
    assert recorded.yields_m == pytest.approx([6.5e-5, 6.5e-5])  # ... with the estimator's own yield displacement
    assert [b.mu_max for b in passive_plants] == [0.075]  # the passive reference: a passive test on the same rig
    line = "rig truth differs from design: bearing.mu_max 0.075 (design 0.06)"
    metadata = json.loads((result.session.run_path / "metadata.json").read_text())
    assert metadata["rig_truth"]["summary"] == line
    panel = console.file.getvalue()  # type: ignore[attr-defined]
    assert "NOTE" in panel and line in panel
    assert result.truth_note == line


def test_a_dry_run_on_the_design_says_nothing_about_truth(tmp_path):
    from harness.runs.dry_run import DryRunOptions, dry_run

    options = DryRunOptions(study=StudyOptions(duration_s=0.5), interface="virtual", channel="truth-none",
                            log_dir=str(tmp_path), lockstep=True, show_console=True, compare=False)
    console = Console(file=io.StringIO(), width=200, color_system=None)
    result = dry_run(load_profile(PROFILES / "nceer_4dof.yaml"), options, console)
    metadata = json.loads((result.session.run_path / "metadata.json").read_text())
    assert "rig_truth" not in metadata
    panel = console.file.getvalue()  # type: ignore[attr-defined]
    assert "state" in panel and "NOTE" not in panel and "rig truth" not in panel
    assert result.truth_note == ""
