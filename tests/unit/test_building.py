"""The building model: matrices of Eq. 6-7 and the fixed-base modal self-checks of SPEC 6."""

from __future__ import annotations

import numpy as np
import pytest

from harness.model.building import (
    BuildingConfig,
    acceleration_maps,
    fixed_base_modes,
    state_space,
)


def test_eight_story_first_mode_matches_spec(eight):
    omega, zeta = fixed_base_modes(eight)
    assert omega[0] == pytest.approx(5.24, abs=0.005)
    assert zeta[0] * 100 == pytest.approx(0.38, abs=0.005)


def test_rig_assumed_superstructure_gives_spec_frequencies(rig):
    omega, zeta = fixed_base_modes(rig)
    assert omega / (2 * np.pi) == pytest.approx([2.3, 7.3, 12.2], abs=0.1)
    assert zeta[0] == pytest.approx(0.01, rel=1e-9)


def test_b_vector_has_the_two_entries_of_spec(eight):
    model = state_space(eight)
    nonzero = np.flatnonzero(model.B)
    assert list(nonzero) == [eight.n_stories + 1, 2 * eight.n_stories + 1]
    assert model.B[model.i_base_velocity] == pytest.approx(1 / eight.base_mass_kg)
    assert model.B[eight.n_stories + 1] == pytest.approx(-1 / eight.base_mass_kg)


def test_static_equilibrium_under_a_constant_base_force(rig):
    """With k_b, a constant force u holds the building at y_b = u / k_b and zero drift."""
    model = state_space(rig)
    u = 1000.0
    z = np.zeros(model.size)
    z[model.i_base_displacement] = u / rig.restoring_stiffness_N_per_m
    assert np.allclose(model.A @ z + model.B * u, 0.0, atol=1e-12)


def test_rigid_body_motion_has_no_story_forces(eight):
    """Translating the whole building (drifts zero) with k_b = 0 produces no acceleration."""
    model = state_space(eight)
    z = np.zeros(model.size)
    z[model.i_base_displacement] = 0.3
    z[model.i_base_velocity] = 0.1
    derivative = model.A @ z
    assert np.allclose(derivative[: model.size // 2], z[model.size // 2 :])
    assert np.allclose(derivative[model.size // 2 :], 0.0)


def test_accelerations_balance_newton_for_the_whole_building(rig):
    """Sum of m a over floors and base equals the external force on the base (Eq. 2)."""
    rng = np.random.default_rng(1)
    model = state_space(rig)
    floor_map, base_map = acceleration_maps(rig)
    z = rng.normal(size=model.size) * 1e-3
    u, f, x0 = 350.0, -120.0, 0.004
    base_acc = base_map @ z + (rig.restoring_stiffness_N_per_m * x0 - f + u) / rig.base_mass_kg
    floor_acc = floor_map @ z
    total = rig.base_mass_kg * base_acc + np.dot(rig.floor_masses_kg, floor_acc)
    external = u - f - rig.restoring_stiffness_N_per_m * (z[model.i_base_displacement] - x0)
    assert total == pytest.approx(external, rel=1e-9)


def test_state_space_drift_accelerations_match_floor_accelerations(rig):
    model = state_space(rig)
    floor_map, base_map = acceleration_maps(rig)
    rng = np.random.default_rng(2)
    z = rng.normal(size=model.size)
    n = rig.n_stories
    zdot = model.A @ z
    absolute = np.cumsum(zdot[n + 1 : 2 * n + 1]) + zdot[-1]
    assert np.allclose(absolute, floor_map @ z)


def test_stiffness_scale_changes_stiffness_and_keeps_damping(eight):
    scaled = eight.with_stiffness_scale(0.7)
    assert np.allclose(scaled.story_stiffness_N_per_m, np.array(eight.story_stiffness_N_per_m) * 0.7)
    assert np.allclose(scaled.story_damping(), eight.story_damping())


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"story_stiffness_N_per_m": (1.0, 2.0)}, "expected 3"),
        ({"story_damping_Ns_per_m": (1.0, 1.0, 1.0)}, "exactly one"),
        ({"first_mode_damping_ratio": None}, "exactly one"),
    ],
)
def test_inconsistent_building_is_refused(changes, message):
    base = dict(
        floor_masses_kg=(1.0, 1.0, 1.0), base_mass_kg=1.0, story_stiffness_N_per_m=(1.0, 1.0, 1.0),
        first_mode_damping_ratio=0.01,
    )
    base.update(changes)
    with pytest.raises(ValueError, match=message):
        BuildingConfig(**base)
