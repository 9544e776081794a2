"""The feed-forward study (profiles/studies/feedforward.yaml) and the ``set`` axis that sets several keys at once."""

from __future__ import annotations

import textwrap
from pathlib import Path

from harness.sweep.cases import case_count, expand
from harness.sweep.study import load_study
from tests.conftest import PROFILES

GAIN_KEYS = ("rig.actuator.hydraulics.feedforward.gain", "rig.truth.actuator.feedforward_gain",
             "safety.force.velocity_feedforward_gain")


def test_a_set_axis_of_several_keys_sets_each_of_them_to_the_same_value(tmp_path: Path) -> None:
    study = tmp_path / "paired.yaml"
    study.write_text(textwrap.dedent(f"""\
        name: paired
        profile: {PROFILES / "nceer_4dof.yaml"}
        options: {{duration_s: 2, rig_effects: true}}
        axes:
          records: ["synthetic:1"]
          controllers: [phi]
          set:
            {",".join(GAIN_KEYS)}: [0.0, 0.5]
            rig.truth.actuator.bulk_modulus_Pa: [0.7e9, 1.3e9]
        """))
    cases = expand(load_study(study))
    assert len(cases) == 4  # the three keys are one axis of two values, crossed with the other axis's two
    for case in cases:
        values = {key: value for key, value in case.inputs if key in GAIN_KEYS}
        assert set(values) == set(GAIN_KEYS) and len(set(values.values())) == 1  # every key, one value
        assert sum(item.startswith(GAIN_KEYS) for item in case.overrides) == 3
    assert sorted({dict(case.inputs)[GAIN_KEYS[0]] for case in cases}) == [0.0, 0.5]


def test_the_shipped_feedforward_study_expands_to_its_324_cases(records_dir: Path) -> None:
    study = load_study(PROFILES / "studies" / "feedforward.yaml")
    count = case_count(study)
    assert (count.records, count.pga_levels, count.controllers, count.grid_points, count.total) == (3, 3, 1, 36, 324)
    cases = expand(study)
    assert len(cases) == 324 and len({case.key for case in cases}) == 324
    gains = {tuple(dict(case.inputs)[key] for key in GAIN_KEYS) for case in cases}
    assert gains == {(g, g, g) for g in (0.0, 0.5, 0.8, 1.0)}  # the servo controller, the rig's truth and the check agree
    flows = sorted({dict(case.inputs)["rig.truth.actuator.valve_flow_m3_per_s"] for case in cases})
    assert flows == [6.65e-4, 9.5e-4, 1.235e-3]  # -30 %, the profile's 9.5e-4 m^3/s, +30 %
    assert all(case.options == cases[0].options for case in cases) and dict(cases[0].options)["rig_effects"] is True
