"""The actuator-aware designs (harness/control/actuator_aware.py): surfaces, equivalent control, stability.

The closed loops are built from the controllers' own ``update`` (probed with unit inputs: with
no table motion and no friction each controller is linear in Z and the actuator force), so a
wrong sign or a dropped term in the code shows up here, not only in the derivation.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.linalg import expm

from drivers.measurements import Measurements
from harness.control.actuator_aware import (
    ActuatorModel,
    ActuatorOutputSMC,
    ActuatorStateFeedbackSMC,
    augmented_model,
    augmented_sliding_poles,
)
from harness.control.factory import build_controller_for_rig, make_controller
from harness.errors import ModelError, ProfileError
from harness.model.building import state_space
from harness.profile import load_profile

#: The controller's sample period on the rig (s).
PERIOD_S = 0.002
#: Actuator model errors the designs must survive: k_h and w_f each off by -30 %, 0, +30 %.
MODEL_ERRORS = list(itertools.product((0.7, 1.0, 1.3), (0.7, 1.0, 1.3)))
#: The actuator-aware designs are for a servo controller without velocity feed-forward, whose force
#: loop leaves the whole natural velocity feedback (SPEC 7a'); the shipped profile's cancels it.
PLAIN_LOOP = ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0"]


@pytest.fixture(scope="module")
def profile():
    return load_profile(None, overrides=PLAIN_LOOP)


@pytest.fixture(scope="module")
def actuator(profile) -> ActuatorModel:
    return ActuatorModel.from_rig_actuator(profile.rig.actuator)


def _meas(z: np.ndarray, n: int, force_N: float, x0: float = 0.0, xd0: float = 0.0) -> Measurements:
    meas = Measurements()
    meas.set(x0, xd0, float(z[n]), float(z[2 * n + 1]))
    meas.actuator_force_N = force_N
    return meas


def _linear_law(controller, size: int, n: int) -> tuple[np.ndarray, float]:
    """``u_c = L_z Z + L_u u`` of a controller with the table at rest and no friction."""
    controller.reset()
    zero = np.zeros(size)
    assert controller.update(0.0, PERIOD_S, _meas(zero, n, 0.0), 0.0, zero) == pytest.approx(0.0, abs=1e-9)
    l_z = np.empty(size)
    for i in range(size):
        z = np.zeros(size)
        z[i] = 1.0
        l_z[i] = controller.update(0.0, PERIOD_S, _meas(z, n, 0.0), 0.0, z)
    l_u = controller.update(0.0, PERIOD_S, _meas(zero, n, 1.0), 0.0, zero)
    return l_z, l_u


def _plant(building, true_actuator: ActuatorModel) -> tuple[np.ndarray, np.ndarray]:
    """The building with the true first-order actuator (A1): state (Z, u), input u_c; no friction, table at rest."""
    model = state_space(building)
    size = model.size
    a = np.zeros((size + 1, size + 1))
    a[:size, :size] = model.A
    a[:size, size] = model.B
    a[size, model.i_base_velocity] = -true_actuator.stiffness_N_per_m
    a[size, size] = -true_actuator.bandwidth_rad_s
    b = np.zeros(size + 1)
    b[size] = true_actuator.bandwidth_rad_s
    return a, b


def _closed_loop(building, controller, true_actuator: ActuatorModel) -> np.ndarray:
    a, b = _plant(building, true_actuator)
    size = a.shape[0] - 1
    l_z, l_u = _linear_law(controller, size, building.n_stories)
    return a + np.outer(b, np.append(l_z, l_u))


def _sampled_loop_radius(building, controller, true_actuator: ActuatorModel) -> float:
    """Spectral radius of the loop sampled at 500 Hz, the command held and applied one period late."""
    a, b = _plant(building, true_actuator)
    size = a.shape[0]
    l_z, l_u = _linear_law(controller, size - 1, building.n_stories)
    block = np.zeros((size + 1, size + 1))
    block[:size, :size], block[:size, size] = a, b
    held = expm(block * PERIOD_S)
    phi, gamma = held[:size, :size], held[:size, size]
    loop = np.zeros((size + 1, size + 1))
    loop[:size, :size], loop[:size, size] = phi, gamma  # x_{k+1} = Phi x_k + Gamma c_{k-1}
    loop[size, :size] = np.append(l_z, l_u)  # c_k = L x_k
    return float(np.max(np.abs(np.linalg.eigvals(loop))))


# ------------------------------------------------------------------ the model and the surfaces
def test_the_actuator_model_comes_from_the_profiles_rig(profile, actuator):
    hydraulics = profile.rig.actuator.hydraulics
    assert actuator.stiffness_N_per_m == pytest.approx(hydraulics.cylinder.hydraulic_stiffness_N_per_m)
    assert actuator.loop_damping_Ns_per_m == pytest.approx(hydraulics.loop_damping_Ns_per_m())
    stiffer = load_profile(None, overrides=[*PLAIN_LOOP, "rig.actuator.hydraulics.cylinder.bulk_modulus_Pa=1.3e9"])
    controller = make_controller(stiffer, "phi-A")
    assert isinstance(controller, ActuatorOutputSMC)
    assert controller.actuator.stiffness_N_per_m == pytest.approx(1.3 * actuator.stiffness_N_per_m)
    force_source = load_profile(None, variant="force_source")
    assert ActuatorModel.from_rig_actuator(force_source.rig.actuator) == ActuatorModel(0.0, 100.0)  # 1 / 10 ms
    # The servo controller's velocity feed-forward at alpha leaves (1 - alpha) of the velocity feedback.
    shipped = ActuatorModel.from_rig_actuator(load_profile(None).rig.actuator)
    assert shipped.stiffness_N_per_m == 0.0 and shipped.bandwidth_rad_s == actuator.bandwidth_rad_s
    half = load_profile(None, overrides=["rig.actuator.hydraulics.feedforward.gain=0.5"])
    assert ActuatorModel.from_rig_actuator(half.rig.actuator).loop_damping_Ns_per_m == pytest.approx(
        0.5 * actuator.loop_damping_Ns_per_m)


def test_an_actuator_model_the_first_order_form_does_not_describe_is_refused():
    ideal = load_profile(None, overrides=["rig.actuator.model=ideal"])
    with pytest.raises(ProfileError, match="servo_hydraulic or first_order"):
        make_controller(ideal, "phi-A")
    with pytest.raises(ModelError, match="w_f"):
        ActuatorModel(1e6, 0.0)


def test_the_command_enters_only_through_the_force_state(profile, actuator):
    model = augmented_model(state_space(profile.structure), actuator)
    n = model.size - 1
    assert np.count_nonzero(model.B) == 1 and model.B[n] == pytest.approx(actuator.bandwidth_rad_s)
    np.testing.assert_allclose(model.A[:n, n], state_space(profile.structure).B)  # v drives Z as u does in Eq. 6-7
    assert model.A[n, model.building.i_base_velocity] == pytest.approx(-actuator.stiffness_N_per_m)


def test_the_shipped_full_state_surface_is_stable_and_normalised(profile):
    controller = make_controller(profile, "FSF-A")
    assert isinstance(controller, ActuatorStateFeedbackSMC)
    model = controller.model
    assert controller.p_row @ model.B == pytest.approx(1.0 / profile.structure.base_mass_kg)
    poles = augmented_sliding_poles(model, controller.p_row)
    assert poles.size == model.size - 1 and np.max(poles.real) < -1.0


def test_the_output_design_adds_the_margin_for_the_actuator_uncertainty(profile, actuator):
    controller = make_controller(profile, "phi-A")
    assert isinstance(controller, ActuatorOutputSMC)
    m_b = profile.structure.base_mass_kg
    p2 = controller.delta / m_b**2
    # k_h and w_f each off by 30 %: the ratio may be 0.7 / 1.3 of the model's, over-cancelled by 46 %.
    assert p2 == pytest.approx((1.0 - 0.7 / 1.3) * actuator.loop_damping_Ns_per_m / m_b)
    assert 30.0 < p2 < 45.0


def test_a_force_weight_of_zero_is_refused(profile):
    with pytest.raises(ProfileError, match="force"):
        load_profile(None, overrides=["control.designs.FSF-A.q.force=0"])


# --------------------------------------------------------------- equivalent control (A7), (A11)
def test_the_full_state_equivalent_control_keeps_s_constant(profile):
    controller = make_controller(profile, "FSF-A", design_stiffness_scale=0.8)
    assert isinstance(controller, ActuatorStateFeedbackSMC)
    model = controller.model
    building, act = model.building, model.actuator
    n, k_b = building.n_stories, building.restoring_stiffness_N_per_m
    rng = np.random.default_rng(5)
    z = rng.normal(size=building.size) * 1e-2
    u, friction, x0, xd0 = 800.0, 350.0, 0.004, -0.12
    command = controller.update(0.0, PERIOD_S, _meas(z, n, u, x0, xd0), friction, z)
    # The design model, (A1) and Eq. 6-7, with friction constant: the rates of Z and u.
    zdot = building.A @ z + building.B * (u - friction + k_b * x0)
    udot = act.bandwidth_rad_s * (command - u) - act.stiffness_N_per_m * (z[2 * n + 1] - xd0)
    vdot = udot + k_b * xd0
    sdot = controller.p_row[:-1] @ zdot + controller.p_row[-1] * vdot
    assert sdot == pytest.approx(-controller.reaching_rate_per_s * controller.sliding_variable, rel=1e-6, abs=1e-9)
    # (A7) in closed form gives the same G.
    k_gain = controller.p_row[:-1] / controller.p_row[-1]
    v = u - friction + k_b * x0
    g = u + (act.stiffness_N_per_m * (z[2 * n + 1] - xd0) - k_b * xd0
             - k_gain @ (building.A @ z + building.B * v)) / act.bandwidth_rad_s
    s = controller.sliding_variable
    assert command == pytest.approx(g - controller.delta * s / building.base_mass_kg)


def test_the_output_equivalent_control_keeps_s_constant_on_its_design_model(profile):
    controller = make_controller(profile, "phi-A")
    assert isinstance(controller, ActuatorOutputSMC)
    m_b, k_b = profile.structure.base_mass_kg, profile.structure.restoring_stiffness_N_per_m
    act = controller.actuator
    y_b, ydot_b, x0, xd0, u, friction = 0.003, 0.05, -0.01, 0.15, 1200.0, 400.0
    meas = Measurements()
    meas.set(x0, xd0, y_b, ydot_b)
    meas.actuator_force_N = u
    command = controller.update(0.0, PERIOD_S, meas, friction)
    s = controller.sliding_variable
    # The design model (A1), (A9) with V_1 = 0, table at constant velocity, friction constant.
    yddot_b = (u - friction - k_b * (y_b - x0)) / m_b
    udot = act.bandwidth_rad_s * (command - u) - act.stiffness_N_per_m * (ydot_b - xd0)
    h = 1e-7
    ahead = Measurements()
    ahead.set(x0 + h * xd0, xd0, y_b + h * ydot_b, ydot_b + h * yddot_b)
    ahead.actuator_force_N = u + h * udot
    probe = ActuatorOutputSMC("probe", m_b, k_b, controller.p1_per_s, controller.phi, controller.delta, act,
                              controller.reaching_rate_per_s)
    probe.update(0.0, PERIOD_S, ahead, friction)
    sdot = (probe.sliding_variable - s) / h
    assert sdot == pytest.approx(-controller.reaching_rate_per_s * s, rel=1e-4)


def test_the_output_command_cancels_the_velocity_feedback(profile, actuator):
    # Base mat still in space on a table moving at xdot_0, force already at the phi target:
    # the command exceeds the target by the force loop's (k_h + phi k_b) / w_f times the stroke velocity.
    controller = make_controller(profile, "phi-A")
    assert isinstance(controller, ActuatorOutputSMC)
    for table_velocity in (0.1, -0.05):
        meas = Measurements()
        meas.set(0.0, table_velocity, 0.0, 0.0)
        meas.actuator_force_N = 0.0
        command = controller.update(0.0, PERIOD_S, meas, 0.0)
        assert controller.target_force_N == pytest.approx(0.0)
        k_b, phi = profile.structure.restoring_stiffness_N_per_m, controller.phi
        expected = -(actuator.stiffness_N_per_m + phi * k_b) * table_velocity / actuator.bandwidth_rad_s
        assert command == pytest.approx(expected)


def test_the_phi_design_is_the_output_design_without_the_actuator():
    # Without the robustness margin (A13), and with the force on target, the output design's
    # surface is 0 and its target is the phi force.
    profile = load_profile(None, overrides=["control.designs.phi-A.actuator_uncertainty=0"])
    phi = build_controller_for_rig(profile, "phi")
    output = build_controller_for_rig(profile, "phi-A")
    meas = Measurements()
    meas.set(0.01, 0.0, 0.012, 0.03)
    target = phi.update(0.0, PERIOD_S, meas, 250.0, None)
    meas.actuator_force_N = target
    output.update(0.0, PERIOD_S, meas, 250.0, None)
    assert isinstance(output, ActuatorOutputSMC)
    assert output.target_force_N == pytest.approx(target) and output.sliding_variable == pytest.approx(0.0, abs=1e-12)


# ----------------------------------------------------------------------------- stability
@pytest.mark.parametrize("design", ["FSF-A", "phi-A"])
@pytest.mark.parametrize(("stiffness_error", "bandwidth_error"), MODEL_ERRORS)
def test_the_closed_loop_is_stable_with_the_actuator_off_by_30_percent(profile, actuator, design, stiffness_error,
                                                                       bandwidth_error):
    controller = make_controller(profile, design)
    true_actuator = actuator.scaled(stiffness_error, bandwidth_error)
    eigenvalues = np.linalg.eigvals(_closed_loop(profile.structure, controller, true_actuator))
    assert np.max(eigenvalues.real) < 0.0, eigenvalues
    # Sampled at 500 Hz with the command held and applied one period late, as on the rig.
    assert _sampled_loop_radius(profile.structure, controller, true_actuator) < 1.0


def test_the_closed_loop_check_sees_an_unstable_design(profile, actuator):
    # The check above is not vacuous: a design that over-cancels the velocity feedback (its k_h
    # three times the plant's) leaves a negative damper between table and base mat.
    wrong = ActuatorOutputSMC("wrong", profile.structure.base_mass_kg, profile.structure.restoring_stiffness_N_per_m,
                              8.0, 0.8, 0.0, actuator.scaled(3.0, 1.0), actuator.bandwidth_rad_s)
    eigenvalues = np.linalg.eigvals(_closed_loop(profile.structure, wrong, actuator))
    assert np.max(eigenvalues.real) > 0.0


# -------------------------------------------------------------------------- on a rig or not
def test_the_output_design_runs_on_a_rig_and_the_full_state_one_does_not(profile):
    assert not build_controller_for_rig(profile, "phi-A").needs_full_state
    with pytest.raises(ProfileError, match="full state"):
        build_controller_for_rig(profile, "FSF-A")


def test_the_full_state_design_needs_the_state(profile):
    controller = make_controller(profile, "FSF-A")
    with pytest.raises(ModelError, match="full state"):
        controller.update(0.0, PERIOD_S, Measurements(), 0.0, None)


def test_the_ideal_simulation_refuses_an_actuator_aware_design(profile):
    from harness.runs.options import StudyOptions
    from harness.runs.simulate import run_study

    with pytest.raises(ProfileError, match="--rig-effects"):
        run_study(profile, StudyOptions(controller="phi-A", duration_s=1.0))
