"""The bearings' friction force from the base mat's force balance (Eq. 1-2).

The base mat's equation of motion, ``m_b a_b = V_1 - k_b x_b - f + u``, solved for the friction
force ``f``; the story-1 shear ``V_1`` is what the floors' inertia puts on the base mat: summing
the floors' equations ``m_j a_j = V_{j+1} - V_j`` (``V_{n+1} = 0``) gives ``V_1 = -sum_j m_j a_j``.
So

    f = u - k_b x_b - m_b a_b - sum_j m_j a_j

with ``u`` the actuator's force (its load cell), ``x_b`` the sliding displacement, ``a_b`` and
``a_j`` the absolute accelerations of the base mat and the floors (all measured), and the
masses and springs of the profile. Nothing here depends on the superstructure's stiffness or
damping, nor on the bearing's own model.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from harness.model.building import BuildingConfig


def friction_from_balance(
    building: BuildingConfig,
    actuator_force_N: np.ndarray,
    sliding_displacement_m: np.ndarray,
    base_acceleration_m_s2: np.ndarray,
    floor_accelerations_m_s2: Sequence[np.ndarray],
) -> np.ndarray:
    """The friction force ``f`` (N) at every sample, from the measured signals.

    Parameters
    ----------
    building : BuildingConfig
        Masses ``m_b``, ``m_1..m_n`` (kg) and restraining springs ``k_b`` (N/m).
    actuator_force_N : ndarray
        ``u``, the force the actuator puts on the base mat (N).
    sliding_displacement_m : ndarray
        ``x_b = y_b - x_0`` (m).
    base_acceleration_m_s2 : ndarray
        ``a_b`` (m/s^2).
    floor_accelerations_m_s2 : sequence of ndarray
        ``a_1 .. a_n``, floor 1 first (m/s^2).
    """
    if len(floor_accelerations_m_s2) != building.n_stories:
        raise ValueError(f"found {len(floor_accelerations_m_s2)} floor accelerations, expected {building.n_stories}")
    springs_N = building.restoring_stiffness_N_per_m * np.asarray(sliding_displacement_m)
    friction = np.asarray(actuator_force_N, dtype=float) - springs_N - building.base_mass_kg * np.asarray(base_acceleration_m_s2)
    for mass_kg, accel in zip(building.floor_masses_kg, floor_accelerations_m_s2, strict=True):
        friction = friction - mass_kg * np.asarray(accel)
    return friction
