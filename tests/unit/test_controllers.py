"""Sliding surfaces and controllers (SPEC 3, Eq. 8-23)."""

from __future__ import annotations

import numpy as np
import pytest

from drivers.measurements import Measurements
from harness.control.controllers import PhiSMC, StateFeedbackSMC
from harness.control.designs import (
    FullStateDesign,
    LqrWeights,
    PhiDesign,
    SimpleOutputDesign,
    StaticOutputDesign,
    SurfaceConfig,
)
from harness.control.factory import build_controller, state_names
from harness.control.surfaces import (
    lqr_surface,
    pole_surface,
    q_diagonal_from_groups,
    regular_form,
    sliding_poles,
)
from harness.errors import ModelError
from harness.model.building import state_space


def test_regular_form_isolates_the_force():
    b = np.array([0.0, -2.0, 0.0, 2.0])
    t = regular_form(b)
    assert np.allclose(t @ t.T, np.eye(4))
    assert np.allclose((t @ b)[:-1], 0.0)
    assert (t @ b)[-1] == pytest.approx(np.linalg.norm(b))


@pytest.mark.parametrize("weights", [(1000, 10, 0.1), (1e4, 50, 0.1)])
def test_lqr_surface_is_stable_and_normalised(eight, weights):
    model = state_space(eight)
    p = lqr_surface(model, q_diagonal_from_groups(8, *weights))
    assert p @ model.B == pytest.approx(1 / eight.base_mass_kg)
    poles = sliding_poles(model, p)
    assert len(poles) == model.size - 1
    assert np.all(poles.real < 0)


def test_lqr_surface_solves_the_reduced_riccati_optimum(rig):
    """Perturbing the optimal gain K increases the LQR cost of the reduced problem."""
    from scipy.linalg import solve_continuous_lyapunov

    model = state_space(rig)
    q = np.diag(q_diagonal_from_groups(3, 100.0, 10.0, 1.0))
    p = lqr_surface(model, np.diag(q))
    t = regular_form(model.B)
    reduced = t @ model.A @ t.T
    a11, a12 = reduced[:-1, :-1], reduced[:-1, -1:]
    qr = t @ q @ t.T
    w = p @ t.T
    gain = (w[:-1] / w[-1]).reshape(1, -1)

    def cost(k):
        closed = a11 - a12 @ k
        weight = np.block([[np.eye(len(k.ravel())), -k.T]]) @ qr @ np.block([[np.eye(len(k.ravel()))], [-k]])
        return np.trace(solve_continuous_lyapunov(closed.T, -weight))

    best = cost(gain)
    rng = np.random.default_rng(0)
    for _ in range(5):
        assert cost(gain + 1e-3 * np.abs(gain).max() * rng.normal(size=gain.shape)) > best


def test_pole_surface_places_the_sliding_poles(rig):
    model = state_space(rig)
    wanted = np.array([-1.0, -2.0, -3.0, -4.0, -5.0, -6.0, -7.0])
    p = pole_surface(model, wanted)
    assert np.sort(sliding_poles(model, p).real) == pytest.approx(np.sort(wanted), rel=1e-4)


def test_pole_surface_needs_n_minus_one_poles(rig):
    with pytest.raises(ModelError, match="needs 7 poles"):
        pole_surface(state_space(rig), np.array([-1.0, -2.0]))


def _meas(x0=0.0, xd0=0.0, yb=0.0, ydb=0.0) -> Measurements:
    m = Measurements()
    m.set(x0, xd0, yb, ydb)
    return m


def test_phi_controller_follows_eq_22_23():
    c = PhiSMC("phi", base_mass_kg=1000.0, restoring_stiffness_N_per_m=5e4, p1_per_s=0.5, phi=0.8, delta=200.0)
    meas = _meas(x0=0.01, yb=0.03, ydb=-0.2)
    u = c.update(0.0, 0.002, meas, friction_N=150.0)
    s = 0.5 * 0.03 - 0.2
    g = -1000 * 0.5 * (-0.2) + 0.8 * 5e4 * (0.03 - 0.01) + 150.0
    assert c.sliding_variable == pytest.approx(s)
    assert c.equivalent_force_N == pytest.approx(g)
    assert c.gain_lambda == pytest.approx(s / 1000.0)
    assert u == pytest.approx(g - 200.0 * s / 1000.0)


def test_simple_output_design_is_phi_equal_one(rig):
    simple = build_controller("OF", SimpleOutputDesign(kind="simple_output", p1_per_s=2.0, delta=0.0), rig)
    phi_one = build_controller("phi", PhiDesign(kind="phi", p1_per_s=2.0, phi=1.0, delta=0.0), rig)
    meas = _meas(0.01, 0.1, 0.02, -0.05)
    assert simple.update(0, 0.002, meas, 10.0) == pytest.approx(phi_one.update(0, 0.002, meas, 10.0))


def test_full_state_equivalent_control_keeps_s_constant(rig):
    """Applied continuously, u = G makes Sdot = 0 exactly (Eq. 11-13)."""
    model = state_space(rig)
    design = FullStateDesign(kind="full_state", surface=SurfaceConfig(q=LqrWeights(100.0, 10.0, 1.0)), delta=0.0)
    c = build_controller("FSF", design, rig)
    rng = np.random.default_rng(3)
    z = rng.normal(size=model.size) * 1e-2
    friction, x0 = 300.0, 0.004
    u = c.update(0.0, 0.002, _meas(x0=x0), friction, z)
    zdot = model.A @ z + model.B * (u - friction + rig.restoring_stiffness_N_per_m * x0)
    assert c.p_row @ zdot == pytest.approx(0.0, abs=1e-9 * np.abs(c.p_row) @ np.abs(zdot))


def test_delta_drives_s_toward_zero(rig):
    model = state_space(rig)
    design = FullStateDesign(kind="full_state", surface=SurfaceConfig(q=LqrWeights(100.0, 10.0, 1.0)), delta=5e6)
    c = build_controller("FSF", design, rig)
    z = np.zeros(model.size)
    z[model.i_base_velocity] = 0.1
    u = c.update(0.0, 0.002, _meas(), 0.0, z)
    zdot = model.A @ z + model.B * u
    s = c.p_row @ z
    assert s * (c.p_row @ zdot) < 0  # Vdot = S Sdot < 0


def test_static_output_ignores_unmeasured_states(rig):
    surface = SurfaceConfig(q=LqrWeights(100.0, 10.0, 1.0))
    design = StaticOutputDesign(kind="static_output", surface=surface, measured=("y_b", "ydot_b"), delta=0.0)
    c = build_controller("SOF", design, rig)
    z = np.zeros(8)
    z[3], z[7] = 0.01, -0.02
    u_only_base = c.update(0.0, 0.002, _meas(), 0.0, z.copy())
    z_drifts = z.copy()
    z_drifts[:3] = [0.001, 0.002, 0.003]
    assert c.update(0.0, 0.002, _meas(), 0.0, z_drifts) == pytest.approx(u_only_base)
    full = build_controller("FSF", FullStateDesign(kind="full_state", surface=surface), rig)
    assert full.update(0.0, 0.002, _meas(), 0.0, z_drifts) != pytest.approx(u_only_base)


def test_static_output_rejects_unknown_state_names(rig):
    design = StaticOutputDesign(
        kind="static_output", surface=SurfaceConfig(q=LqrWeights(1, 1, 1)), measured=("y_b", "x_9"), delta=0.0
    )
    with pytest.raises(ModelError, match="x_9"):
        build_controller("SOF", design, rig)


def test_state_names_follow_the_documented_order():
    assert state_names(2) == ["x_1", "x_2", "y_b", "xdot_1", "xdot_2", "ydot_b"]


def test_controllers_reset_clears_internals():
    c = PhiSMC("phi", 1000.0, 0.0, 1.0, 1.0, 0.0)
    c.update(0.0, 0.002, _meas(yb=0.1, ydb=0.1), 5.0)
    c.reset()
    assert (c.sliding_variable, c.equivalent_force_N, c.force_N) == (0.0, 0.0, 0.0)
    assert isinstance(c, PhiSMC) and not c.needs_full_state and StateFeedbackSMC.needs_full_state


def test_every_design_builds_a_controller_of_the_protocol():
    """Every shipped design is a Controller (the loop, the simulator and the twin rely on it)."""
    from harness.control.controllers import Controller
    from harness.control.factory import make_controller
    from harness.profile import load_profile
    from tests.conftest import PROFILES

    for name in ("eight_story.yaml", "nceer_4dof.yaml"):
        profile = load_profile(PROFILES / name)
        for design in profile.control.designs:
            assert isinstance(make_controller(profile, design), Controller), design
