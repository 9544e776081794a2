"""The continuous sliding-mode controllers of SPEC 3 (no sign function, no chattering).

Each controller is a small callable object: ``update(t, dt, meas, friction_N, state)``
returns the raw actuator force (N) and leaves its internals visible for logging:
``sliding_variable`` (S, m/s), ``equivalent_force_N`` (G), ``gain_lambda`` (lambda)
and ``force_N``. They never read a clock.

- :class:`StateFeedbackSMC`: full-state feedback (Eq. 13), partial compensation
  ``alpha_star`` (Eq. 15), and static output feedback (Eq. 16-17) when given a mask of
  measured states (unmeasured entries of Z set to zero).
- :class:`PhiSMC`: partial restraint cancellation (Eq. 22-23); with ``phi = 1`` it is the
  simple output feedback controller (Eq. 18-21).
"""

from __future__ import annotations

from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from drivers.measurements import Measurements
from harness.model.building import StateSpace


@runtime_checkable
class Controller(Protocol):
    """What the loop, the simulator and the twin need of a controller (SPEC 3).

    Attributes
    ----------
    needs_full_state : bool
        True if ``update`` reads ``state`` (Z); a rig measures only x_0, xdot_0, y_b, ydot_b.
    sliding_variable : float
        S of the last update (m/s), for the record.
    equivalent_force_N : float
        G of the last update (N), for the record.
    """

    needs_full_state: ClassVar[bool]
    sliding_variable: float
    equivalent_force_N: float

    def reset(self) -> None:
        """Back to the state before the first update."""

    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None) -> float:
        """The raw actuator force (N) at time ``t`` (s), ``dt`` (s) after the previous update.

        ``friction_N`` is the friction force to compensate (the online estimate or the
        model's); ``state`` is Z for full-state designs, None on a rig. Never reads a clock.
        """
        ...


class _SlidingModeInternals:
    """The internals every controller shows: S (m/s), G (N), lambda, and the raw force (N)."""

    sliding_variable: float
    equivalent_force_N: float
    gain_lambda: float
    force_N: float

    def reset(self) -> None:
        """Clear the internals."""
        self.sliding_variable = 0.0
        self.equivalent_force_N = 0.0
        self.gain_lambda = 0.0
        self.force_N = 0.0


class StateFeedbackSMC(_SlidingModeInternals):
    """Full-state (Eq. 13, 15) or static-output (Eq. 16-17) sliding-mode control.

    Parameters
    ----------
    name : str
    model : StateSpace
        The controller's design model (A, B, m_b, k_b).
    p_row : ndarray (N,)
        Sliding surface S = P Z (Eq. 8).
    delta : float
        Sliding margin (>= 0), in N kg s/m with ``P B = 1/m_b``.
    alpha_star : float
        Partial compensation 0..1 (Eq. 15); 1 is Eq. 13.
    measured_mask : ndarray of bool, optional
        Entries of Z the controller measures; the others are set to zero (Eq. 16-17).
        ``None`` means full state.
    """

    needs_full_state: ClassVar[bool] = True

    def __init__(
        self,
        name: str,
        model: StateSpace,
        p_row: np.ndarray,
        delta: float,
        alpha_star: float = 1.0,
        measured_mask: np.ndarray | None = None,
    ):
        self.name = name
        self.p_row = np.asarray(p_row, dtype=float)
        self._pb = float(self.p_row @ model.B)
        self._pa = self.p_row @ model.A
        self._kb = model.restoring_stiffness_N_per_m
        self._mask = None if measured_mask is None else np.asarray(measured_mask, dtype=float)
        self.delta = float(delta)
        self.alpha_star = float(alpha_star)
        self.reset()


    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None) -> float:
        """Return the raw force (N) for time ``t``; ``state`` is Z (full or estimated)."""
        z = state if self._mask is None else state * self._mask
        s = float(self.p_row @ z)
        # G = -(PB)^-1 P (A Z - B f + E), E = B k_b x_0           (Eq. 12, 17)
        pe = self._pb * self._kb * meas.table_displacement_m
        g = -(float(self._pa @ z) - self._pb * friction_N + pe) / self._pb
        lam = s * self._pb  # Eq. 12 (Eq. 17: Z_m' P' P B)
        self.sliding_variable = s
        self.equivalent_force_N = g
        self.gain_lambda = lam
        self.force_N = self.alpha_star * g - self.delta * lam  # Eq. 13, 15
        return self.force_N


class PhiSMC(_SlidingModeInternals):
    """Partial restraint cancellation, the controller used on the shaking table (Eq. 22-23).

    ``S = p1 y_b + ydot_b``, ``lambda = S / m_b``,
    ``G* = -m_b p1 ydot_b + phi k_b (y_b - x_0) + f_hat``, ``u = G* - delta lambda``.
    With ``phi = 1`` this is the simple output feedback controller (Eq. 18-21).

    Parameters
    ----------
    name : str
    base_mass_kg, restoring_stiffness_N_per_m : float
        Design values of m_b and k_b.
    p1_per_s : float
        Pole of the sliding surface (1/s), > 0.
    phi : float
        Share of the restraining springs cancelled, 0..1.
    delta : float
        Sliding margin (>= 0), N kg s/m.
    """

    needs_full_state: ClassVar[bool] = False

    def __init__(
        self, name: str, base_mass_kg: float, restoring_stiffness_N_per_m: float, p1_per_s: float, phi: float, delta: float
    ):
        self.name = name
        self.base_mass_kg = float(base_mass_kg)
        self.restoring_stiffness_N_per_m = float(restoring_stiffness_N_per_m)
        self.p1_per_s = float(p1_per_s)
        self.phi = float(phi)
        self.delta = float(delta)
        self.reset()


    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None = None) -> float:
        """Return the raw force (N) from the measured y_b, ydot_b, x_0 and the friction estimate."""
        y_b = meas.base_displacement_m
        ydot_b = meas.base_velocity_m_s
        s = self.p1_per_s * y_b + ydot_b  # Eq. 18
        lam = s / self.base_mass_kg  # Eq. 21a
        g = (
            -self.base_mass_kg * self.p1_per_s * ydot_b
            + self.phi * self.restoring_stiffness_N_per_m * (y_b - meas.table_displacement_m)
            + friction_N
        )  # Eq. 23b (Eq. 21b with phi = 1)
        self.sliding_variable = s
        self.equivalent_force_N = g
        self.gain_lambda = lam
        self.force_N = g - self.delta * lam  # Eq. 23a
        return self.force_N
