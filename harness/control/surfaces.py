"""Sliding surfaces S = P Z (Eq. 8) from the regular form: LQR (Eq. 9) or pole assignment.

The regular form is an orthogonal change of coordinates ``w = T Z`` whose last row is
``B / |B|``, so that ``T B = (0, ..., 0, |B|)``. The first N-1 coordinates ``w1`` then
obey ``w1dot = A11 w1 + A12 w2`` with no force term, and ``w2`` is treated as the
"control" of that subsystem. With the LQR weights of ``J = integral Z' Q Z`` expressed
in the new coordinates (``Qr = T Q T'``), the optimal ``w2 = -K w1`` follows from the
Riccati equation with a cross term (Utkin & Young):

    A11' X + X A11 - (X A12 + Q12) Q22^-1 (A12' X + Q12') + Q11 = 0,
    K = Q22^-1 (A12' X + Q12'),

and the surface is ``S = w2 + K w1 = [K, 1] T Z``. P is scaled so that ``P B = 1/m_b``,
the same normalisation as the simple-output surface ``S = p1 y_b + ydot_b`` (Eq. 18),
so that delta has one meaning across controllers.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from harness.errors import ModelError


class InputModel(Protocol):
    """What a surface design needs of a model: ``Xdot = A X + B u (+ disturbances)`` and m_b.

    The building's :class:`~harness.model.building.StateSpace` (Eq. 6-7), or the building
    augmented with the actuator's force state (:mod:`harness.control.actuator_aware`).
    """

    @property
    def A(self) -> np.ndarray:  # noqa: N802 - the paper's name
        """System matrix (N, N)."""

    @property
    def B(self) -> np.ndarray:  # noqa: N802 - the paper's name
        """Input vector (N,)."""

    @property
    def base_mass_kg(self) -> float:
        """m_b (kg), for the normalisation ``P B = 1/m_b``."""


def regular_form(b_vector: np.ndarray) -> np.ndarray:
    """Orthogonal T with ``T B = (0, ..., 0, |B|)``."""
    b = np.asarray(b_vector, dtype=float).reshape(-1, 1)
    import scipy.linalg  # imported where used: scipy costs about 0.5 s at start-up

    null_basis = scipy.linalg.null_space(b.T)  # N x (N-1), orthonormal
    return np.vstack([null_basis.T, (b / np.linalg.norm(b)).T])


def _partition(model: InputModel, matrix: np.ndarray):
    t_matrix = regular_form(model.B)
    reduced = t_matrix @ matrix @ t_matrix.T
    return t_matrix, reduced[:-1, :-1], reduced[:-1, -1:]


def _surface_from_gain(model: InputModel, t_matrix: np.ndarray, gain: np.ndarray, a11: np.ndarray, a12: np.ndarray) -> np.ndarray:
    closed = a11 - a12 @ gain.reshape(1, -1)
    eigenvalues = np.linalg.eigvals(closed)
    if np.max(eigenvalues.real) >= 0:
        raise ModelError(
            f"sliding-surface dynamics are not stable (largest real part {np.max(eigenvalues.real):.3g} 1/s); "
            "expected every eigenvalue in the left half-plane: check the weights or poles"
        )
    p_row = np.append(gain.ravel(), 1.0) @ t_matrix
    return p_row / (p_row @ model.B) / model.base_mass_kg


def lqr_surface(model: InputModel, q_diagonal: np.ndarray) -> np.ndarray:
    """Sliding surface P from LQR on the regular form (Eq. 9).

    Parameters
    ----------
    model : InputModel
        The design model (may differ from the plant, for robustness studies): the
        building's StateSpace, or the building augmented with the actuator.
    q_diagonal : ndarray (N,)
        Diagonal of Q in this package's state order.

    Returns
    -------
    ndarray (N,)
        P, normalised so that ``P B = 1 / m_b``.
    """
    q_matrix = np.diag(np.asarray(q_diagonal, dtype=float))
    if np.any(np.diag(q_matrix) < 0):
        raise ModelError("LQR weights must be >= 0")
    t_matrix, a11, a12 = _partition(model, model.A)
    q_reduced = t_matrix @ q_matrix @ t_matrix.T
    q11, q12, q22 = q_reduced[:-1, :-1], q_reduced[:-1, -1:], q_reduced[-1:, -1:]
    if q22[0, 0] <= 0:
        raise ModelError("the LQR weight on the regular-form force coordinate is zero; give the velocities a positive weight")
    import scipy.linalg

    try:
        riccati = scipy.linalg.solve_continuous_are(a11, a12, q11, q22, s=q12)
    except (np.linalg.LinAlgError, ValueError) as err:
        raise ModelError(f"the Riccati equation of the sliding surface has no stabilising solution: {err}") from err
    gain = np.linalg.solve(q22, a12.T @ riccati + q12.T)
    return _surface_from_gain(model, t_matrix, gain, a11, a12)


def pole_surface(model: InputModel, poles_per_s: np.ndarray) -> np.ndarray:
    """Sliding surface P placing the N-1 sliding-mode poles (1/s) by pole assignment."""
    poles = np.asarray(poles_per_s)
    t_matrix, a11, a12 = _partition(model, model.A)
    if len(poles) != a11.shape[0]:
        raise ModelError(f"pole assignment needs {a11.shape[0]} poles (N - 1), found {len(poles)}")
    import scipy.signal  # imported where used: about 1 s at start-up

    try:
        placed = scipy.signal.place_poles(a11, a12, poles)
    except ValueError as err:
        raise ModelError(f"pole assignment failed: {err}") from err
    return _surface_from_gain(model, t_matrix, placed.gain_matrix, a11, a12)


def q_diagonal_from_groups(n_stories: int, drifts: float, base_displacement: float, velocities: float) -> np.ndarray:
    """Diagonal LQR weights from the paper's named groups (SPEC 6a), in this package's state order."""
    return np.concatenate([np.full(n_stories, drifts), [base_displacement], np.full(n_stories + 1, velocities)])


def sliding_poles(model: InputModel, p_row: np.ndarray) -> np.ndarray:
    """Eigenvalues of the motion on S = 0 (1/s): N-1 values, for checks and reports."""
    t_matrix, a11, a12 = _partition(model, model.A)
    w = p_row @ t_matrix.T  # S = w . (T Z)
    gain = w[:-1] / w[-1]
    return np.linalg.eigvals(a11 - a12 @ gain.reshape(1, -1))
