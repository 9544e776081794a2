"""An n-story shear building on a sliding base mat: configuration and state-space matrices (SPEC 1).

State order used everywhere in this package (the paper orders drifts top-down; any
documented order is allowed, SPEC 1)::

    Z = (x_1, ..., x_n, y_b, xdot_1, ..., xdot_n, ydot_b)        length N = 2 n + 2

``x_j`` is the drift of story j (floor j minus floor j-1, floor 0 is the base mat),
``y_b`` the base-mat absolute displacement. The equations of motion (Eq. 1-2) give

    Zdot = A Z - B f + B u + E(t),      E = B k_b x_0(t)                (Eq. 6-7)

where ``B`` has ``+1/m_b`` on ``ydot_b``'s row and ``-1/m_b`` on ``xdot_1``'s row.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from harness.config.schema import quantity

GRAVITY_M_S2 = 9.80665


@dataclass(frozen=True)
class BuildingConfig:
    """Masses, story stiffness and damping of the superstructure and base mat (SI).

    Story damping is given either as ``story_damping_Ns_per_m`` (one value per
    story) or as ``first_mode_damping_ratio`` (stiffness-proportional damping that
    gives this ratio in the first fixed-base mode), not both.
    """

    floor_masses_kg: tuple[float, ...] = quantity(unit="kg", gt=0, min_len=1, doc="masses of floors 1..n, bottom up")
    base_mass_kg: float = quantity(unit="kg", gt=0, doc="base mat mass m_b")
    story_stiffness_N_per_m: tuple[float, ...] = quantity(unit="N/m", gt=0, min_len=1, doc="story stiffness k_1..k_n")
    story_damping_Ns_per_m: tuple[float, ...] | None = quantity(None, unit="N*s/m", ge=0, doc="story damping c_1..c_n")
    first_mode_damping_ratio: float | None = quantity(None, ge=0, lt=1, doc="stiffness-proportional damping ratio in mode 1")
    restoring_stiffness_N_per_m: float = quantity(0.0, unit="N/m", ge=0, doc="restraining springs k_b, base mat to table")
    assumptions: str = field(default="", metadata={"doc": "which values are assumed rather than identified"})

    def __post_init__(self) -> None:
        n = len(self.floor_masses_kg)
        if len(self.story_stiffness_N_per_m) != n:
            raise ValueError(
                f"story_stiffness_N_per_m has {len(self.story_stiffness_N_per_m)} values, expected {n} (one per floor mass)"
            )
        if (self.story_damping_Ns_per_m is None) == (self.first_mode_damping_ratio is None):
            raise ValueError("give exactly one of story_damping_Ns_per_m and first_mode_damping_ratio")
        if self.story_damping_Ns_per_m is not None and len(self.story_damping_Ns_per_m) != n:
            raise ValueError(f"story_damping_Ns_per_m has {len(self.story_damping_Ns_per_m)} values, expected {n}")

    @property
    def n_stories(self) -> int:
        """Number of stories n."""
        return len(self.floor_masses_kg)

    @property
    def total_mass_kg(self) -> float:
        """``mbar``: base mat plus all floors, the mass the bearings carry (kg)."""
        return self.base_mass_kg + float(sum(self.floor_masses_kg))

    @property
    def total_weight_N(self) -> float:
        """``mbar * g`` (N)."""
        return self.total_mass_kg * GRAVITY_M_S2

    def story_damping(self) -> np.ndarray:
        """Story damping c_1..c_n (N s/m), resolving ``first_mode_damping_ratio`` if used."""
        if self.story_damping_Ns_per_m is not None:
            return np.asarray(self.story_damping_Ns_per_m, dtype=float)
        ratio = self.first_mode_damping_ratio
        assert ratio is not None, "__post_init__: exactly one of the two is given"
        omega_1 = fixed_base_modes(self, np.zeros(self.n_stories))[0][0]
        return 2.0 * ratio / omega_1 * np.asarray(self.story_stiffness_N_per_m, dtype=float)

    def with_stiffness_scale(self, scale: float) -> BuildingConfig:
        """A copy with every story stiffness multiplied by ``scale`` (design-model mismatch studies)."""
        from dataclasses import replace

        return replace(
            self,
            story_stiffness_N_per_m=tuple(k * scale for k in self.story_stiffness_N_per_m),
            story_damping_Ns_per_m=tuple(self.story_damping()),
            first_mode_damping_ratio=None,
        )


def _shear_matrices(masses: np.ndarray, stiffness: np.ndarray, damping: np.ndarray):
    """Fixed-base mass, stiffness and damping matrices in floor displacements relative to the base."""
    n = len(masses)
    k_matrix = np.zeros((n, n))
    c_matrix = np.zeros((n, n))
    for j in range(n):
        k_matrix[j, j] += stiffness[j]
        c_matrix[j, j] += damping[j]
        if j + 1 < n:
            k_matrix[j, j] += stiffness[j + 1]
            c_matrix[j, j] += damping[j + 1]
            k_matrix[j, j + 1] = k_matrix[j + 1, j] = -stiffness[j + 1]
            c_matrix[j, j + 1] = c_matrix[j + 1, j] = -damping[j + 1]
    return np.diag(masses), k_matrix, c_matrix


def fixed_base_modes(config: BuildingConfig, damping: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Natural frequencies and damping ratios of the superstructure on a fixed base.

    Parameters
    ----------
    config : BuildingConfig
    damping : ndarray, optional
        Story damping (N s/m); defaults to ``config.story_damping()``.

    Returns
    -------
    omega : ndarray
        Undamped natural frequencies (rad/s), ascending.
    zeta : ndarray
        Damping ratios of the same modes (1 = critical), from the complex eigenvalues.
    """
    masses = np.asarray(config.floor_masses_kg, dtype=float)
    stiffness = np.asarray(config.story_stiffness_N_per_m, dtype=float)
    c = config.story_damping() if damping is None else np.asarray(damping, dtype=float)
    m_matrix, k_matrix, c_matrix = _shear_matrices(masses, stiffness, c)
    n = len(masses)
    m_inv = np.linalg.inv(m_matrix)
    system = np.block([[np.zeros((n, n)), np.eye(n)], [-m_inv @ k_matrix, -m_inv @ c_matrix]])
    eigenvalues = np.linalg.eigvals(system)
    eigenvalues = eigenvalues[eigenvalues.imag > 0] if np.any(c) else eigenvalues[eigenvalues.imag >= 0]
    if len(eigenvalues) != n:  # overdamped modes or zero damping duplicates: fall back to undamped
        omega = np.sqrt(np.sort(np.linalg.eigvals(m_inv @ k_matrix).real))
        return omega, np.zeros(n)
    magnitude = np.abs(eigenvalues)
    order = np.argsort(magnitude)
    return magnitude[order], (-eigenvalues.real / magnitude)[order]


@dataclass(frozen=True)
class StateSpace:
    """Matrices of Eq. 6-7 for the chosen state order (see module docstring).

    Attributes
    ----------
    A : ndarray (N, N)
    B : ndarray (N,)
        Input vector of the actuator force u (and, with minus sign, of the friction f).
    n_stories : int
    base_mass_kg, restoring_stiffness_N_per_m, total_weight_N : float
    """

    A: np.ndarray
    B: np.ndarray
    n_stories: int
    base_mass_kg: float
    restoring_stiffness_N_per_m: float
    total_weight_N: float

    @property
    def size(self) -> int:
        """N = 2 n + 2."""
        return 2 * self.n_stories + 2

    @property
    def i_base_displacement(self) -> int:
        """Index of ``y_b`` in Z."""
        return self.n_stories

    @property
    def i_base_velocity(self) -> int:
        """Index of ``ydot_b`` in Z."""
        return 2 * self.n_stories + 1

    def E(self, table_displacement_m: float) -> np.ndarray:
        """``E = B k_b x_0`` (Eq. 7)."""
        return self.B * (self.restoring_stiffness_N_per_m * table_displacement_m)


def acceleration_maps(config: BuildingConfig, damping: np.ndarray | None = None):
    """Linear maps from (Z, base force) to absolute accelerations.

    Returns
    -------
    floor_map : ndarray (n, N)
        ``a_j = floor_map[j-1] @ Z`` (absolute floor accelerations do not depend on f or u).
    base_map : ndarray (N,)
        ``yddot_b = base_map @ Z + (k_b x_0 - f + u) / m_b``.
    """
    n = config.n_stories
    size = 2 * n + 2
    masses = np.asarray(config.floor_masses_kg, dtype=float)
    stiffness = np.asarray(config.story_stiffness_N_per_m, dtype=float)
    c = config.story_damping() if damping is None else np.asarray(damping, dtype=float)
    shear = np.zeros((n + 1, size))  # V_1..V_n, V_{n+1} = 0
    for j in range(n):
        shear[j, j] = stiffness[j]
        shear[j, n + 1 + j] = c[j]
    floor_map = np.zeros((n, size))
    for j in range(n):
        floor_map[j] = (shear[j + 1] - shear[j]) / masses[j]  # m_j a_j = V_{j+1} - V_j  (Eq. 1)
    base_map = shear[0].copy() / config.base_mass_kg
    base_map[n] -= config.restoring_stiffness_N_per_m / config.base_mass_kg
    return floor_map, base_map


def state_space(config: BuildingConfig) -> StateSpace:
    """Build A and B of Eq. 6-7 for ``config``."""
    n = config.n_stories
    size = 2 * n + 2
    floor_map, base_map = acceleration_maps(config)
    a_matrix = np.zeros((size, size))
    a_matrix[: n + 1, n + 1 :] = np.eye(n + 1)  # displacement rates are the velocities
    a_matrix[2 * n + 1] = base_map  # yddot_b
    a_matrix[n + 1] = floor_map[0] - base_map  # xddot_1 = a_1 - yddot_b
    for j in range(1, n):
        a_matrix[n + 1 + j] = floor_map[j] - floor_map[j - 1]  # xddot_j = a_j - a_{j-1}
    b_vector = np.zeros(size)
    b_vector[2 * n + 1] = 1.0 / config.base_mass_kg
    b_vector[n + 1] = -1.0 / config.base_mass_kg
    return StateSpace(
        A=a_matrix,
        B=b_vector,
        n_stories=n,
        base_mass_kg=config.base_mass_kg,
        restoring_stiffness_N_per_m=config.restoring_stiffness_N_per_m,
        total_weight_N=config.total_weight_N,
    )
