"""The force loop's linearised relations are written once, in ``harness/hydraulics/linear.py``.

The design side (the actuator-aware designs and through them the compensators, the
identification's fit and its bulk modulus) and the plant's own parameters
(:class:`~harness.hydraulics.config.HydraulicActuatorConfig`) take ``k_h``, ``w_f``, ``K_p``
and ``(1 - alpha) k_h / w_f`` from there (SPEC 7a, 7a'). These tests fail when a module
restates one of them: by what it imports, by what its code (docstrings and comments left out)
computes, and by the numbers it gives on the shipped profiles.
"""

from __future__ import annotations

import ast
import dataclasses
import math
import re
from pathlib import Path

import pytest

from harness.control.actuator_aware import ActuatorModel
from harness.hydraulics import linear
from harness.hydraulics.config import HydraulicActuatorConfig, TableConfig
from harness.hydraulics.cylinder import ACTUATOR_GAIN, pack_rig
from harness.identification.actuator_fit import ActuatorParameters, bulk_modulus_Pa
from harness.profile import load_profile
from tests.unit.test_architecture import REPO, imported_names

#: The modules that use the force loop's linearised relations, and must import them.
USERS = {
    "harness/control/actuator_aware.py": "harness.control.actuator_aware",
    "harness/identification/actuator_fit.py": "harness.identification.actuator_fit",
    "harness/hydraulics/cylinder.py": "harness.hydraulics.cylinder",
}
#: The shipped profiles.
PROFILES = sorted((REPO / "profiles").glob("*.yaml"))
#: Code that restates a relation of ``harness/hydraulics/linear.py`` (in ``ast.unparse``'s spelling).
RESTATEMENTS = {
    "4 beta_e ... (k_h or the pressure gain)": re.compile(r"4\.0 \* [\w.]*(bulk_modulus|beta)"),
    "A^2 (k_h, beta_e from k_h, the leakage pole)": re.compile(r"piston_area_m2 \*\* 2"),
    "2 pi of the force loop's bandwidth (w_f)": re.compile(r"2\.0 \* (math|np)\.pi \* [\w.]*force_loop_bandwidth_hz"),
    "k_h / w_f": re.compile(r"stiffness_N_per_m / [^,\n]*(bandwidth|omega|w_f)"),
    "(1 - alpha) k_h": re.compile(r"1\.0 - [\w.]*feedforward(_gain|\.gain)\) \* [\w.]*stiffness"),
    "A / q_nl": re.compile(r"piston_area_m2 / [\w.]*valve_flow"),
}
#: Where the relations may be written: their home (and its tests).
HOME = REPO / "harness" / "hydraulics" / "linear.py"


def code_without_docs(path: Path) -> str:
    """The module's code as ``ast.unparse`` spells it, docstrings left out (comments are gone already)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    for node in ast.walk(tree):
        body = getattr(node, "body", None)
        if isinstance(body, list) and body and isinstance(body[0], ast.Expr) \
                and isinstance(body[0].value, ast.Constant) and isinstance(body[0].value.value, str):
            body[0] = ast.Pass()
    return ast.unparse(tree)


@pytest.mark.parametrize("path, module", sorted(USERS.items()))
def test_the_design_side_and_the_plant_import_the_linear_relations_from_their_home(path: str, module: str) -> None:
    names = imported_names(REPO / path, module)
    assert "harness.hydraulics.linear" in names, f"{path} does not take the force loop's relations from harness.hydraulics.linear"


def test_no_module_restates_a_linear_relation() -> None:
    found = []
    for path in sorted((REPO / "harness").rglob("*.py")):
        if path == HOME:
            continue
        code = code_without_docs(path)
        found += [f"{path.relative_to(REPO)}: {what}" for what, pattern in RESTATEMENTS.items() if pattern.search(code)]
    assert not found, f"restated instead of calling harness/hydraulics/linear.py: {found}"


def test_the_restatement_finder_sees_code_and_not_docs(tmp_path: Path) -> None:
    module = tmp_path / "m.py"
    module.write_text('"""k_h = 4.0 * bulk_modulus_Pa * A ** 2"""\n\ndef k(c):\n    """4.0 * beta"""\n    return 1.0\n')
    assert not any(p.search(code_without_docs(module)) for p in RESTATEMENTS.values())
    module.write_text("def k(c):\n    return 4.0 * c.bulk_modulus_Pa * c.piston_area_m2**2 / c.oil_volume_m3\n")
    assert RESTATEMENTS["4 beta_e ... (k_h or the pressure gain)"].search(code_without_docs(module))
    module.write_text("def c(h):\n    return h.stiffness_N_per_m / (2.0 * math.pi * h.force_loop_bandwidth_hz)\n")
    assert RESTATEMENTS["k_h / w_f"].search(code_without_docs(module))


def _servo_hydraulic(path: Path, feedforward_gain: float | None = None):
    """The profile's ``rig.actuator`` as a servo-hydraulic actuator (with ``alpha`` replaced if given)."""
    actuator = load_profile(path).rig.actuator
    hydraulics = actuator.hydraulics
    if feedforward_gain is not None:
        feedforward = dataclasses.replace(hydraulics.feedforward, gain=feedforward_gain)
        hydraulics = dataclasses.replace(hydraulics, feedforward=feedforward)
    return dataclasses.replace(actuator, model="servo_hydraulic", hydraulics=hydraulics)


@pytest.mark.parametrize("alpha", [None, 0.0, 0.5], ids=["shipped_alpha", "plain_loop", "half_feedforward"])
@pytest.mark.parametrize("path", PROFILES, ids=[p.stem for p in PROFILES])
def test_the_design_model_is_the_linear_relations_on_the_shipped_profiles(path: Path, alpha: float | None) -> None:
    actuator = _servo_hydraulic(path, alpha)
    h = actuator.hydraulics
    c = h.cylinder
    k_h = linear.hydraulic_stiffness_N_per_m(c.bulk_modulus_Pa, c.piston_area_m2, c.oil_volume_m3)
    w_f = linear.angular_frequency_rad_s(h.force_loop_bandwidth_hz)
    c_eff = linear.velocity_feedback_Ns_per_m(k_h, w_f, h.feedforward.gain)
    model = ActuatorModel.from_rig_actuator(actuator)
    assert model.bandwidth_rad_s == w_f
    assert model.stiffness_N_per_m == linear.velocity_feedback_stiffness_N_per_m(c_eff, w_f)
    assert model.stiffness_N_per_m == pytest.approx((1.0 - h.feedforward.gain) * k_h, rel=1e-12)
    assert model.loop_damping_Ns_per_m == pytest.approx(c_eff, rel=1e-12)
    # the plant's configuration and the identification's model: the same numbers, bit for bit
    assert c.hydraulic_stiffness_N_per_m == k_h
    assert h.velocity_feedback_Ns_per_m() == c_eff
    assert h.loop_damping_Ns_per_m() == linear.loop_damping_Ns_per_m(k_h, w_f)
    assert ActuatorParameters.from_config(h, 0.0).velocity_feedback_Ns_per_m() == c_eff
    assert bulk_modulus_Pa(k_h, h) == pytest.approx(c.bulk_modulus_Pa, rel=1e-12)


@pytest.mark.parametrize("path", PROFILES, ids=[p.stem for p in PROFILES])
def test_the_packed_force_gain_gives_the_loop_its_bandwidth(path: Path) -> None:
    h = _servo_hydraulic(path).hydraulics
    c = h.cylinder
    rig = pack_rig(h, TableConfig(), 1000.0, False, 0.02)
    pressure_gain = linear.pressure_gain_Pa_per_m3(c.bulk_modulus_Pa, c.oil_volume_m3)
    assert rig[ACTUATOR_GAIN] == linear.force_gain_per_N(h.bandwidth_rad_s(), pressure_gain, c.piston_area_m2,
                                                         c.valve_flow_m3_per_s)
    w_f = linear.force_loop_bandwidth_rad_s(rig[ACTUATOR_GAIN], pressure_gain, c.piston_area_m2, c.valve_flow_m3_per_s)
    assert w_f == pytest.approx(2.0 * math.pi * h.force_loop_bandwidth_hz, rel=1e-12)


def test_the_relations_hold_their_closed_forms() -> None:
    beta, area, volume = 1.0e9, 7.25e-4, 1.78e-4
    k_h = linear.hydraulic_stiffness_N_per_m(beta, area, volume)
    assert k_h == pytest.approx(4.0 * beta * area * area / volume, rel=1e-15)
    assert linear.bulk_modulus_Pa(k_h, area, volume) == pytest.approx(beta, rel=1e-14)
    assert linear.pressure_gain_Pa_per_m3(beta, volume) * area * area == pytest.approx(k_h, rel=1e-14)
    assert linear.leakage_pole_per_s(k_h, 4.0e-14, area) == pytest.approx(4.0 * beta / volume * 4.0e-14, rel=1e-14)
    assert linear.velocity_feedback_Ns_per_m(k_h, 125.0, 0.0) == linear.loop_damping_Ns_per_m(k_h, 125.0)
    assert linear.velocity_feedback_Ns_per_m(k_h, 125.0, 1.0) == 0.0
    assert linear.feedforward_current_per_m_s(area, 9.5e-4) == area / 9.5e-4
    default = HydraulicActuatorConfig()
    assert default.feedforward_current_per_m_s() == linear.feedforward_current_per_m_s(
        default.cylinder.piston_area_m2, default.cylinder.valve_flow_m3_per_s)
