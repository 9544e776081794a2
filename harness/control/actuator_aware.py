"""Sliding-mode control designed on the building augmented with its actuator's force state.

The paper designs its surfaces on Eq. 6-7, where the controller's force ``u`` acts on the
base mat the moment it is computed. On a rig the force comes from a cylinder under a force
loop (:mod:`harness.hydraulics.cylinder`); below the loop's bandwidth ``w_f`` its force obeys

    udot = w_f (u_c - u) - k_h xdot_b,        xdot_b = ydot_b - xdot_0              (A1)

with ``u_c`` the command, ``k_h`` the hydraulic stiffness and the last term the natural
velocity feedback. A controller that commands ``u_c`` as if it were ``u`` gets
``u = lag(u_c - (k_h / w_f) xdot_b)``: a ``k_h / w_f`` damper between table and base mat
(94 kN s/m on the shipped rig). Here the force is a state and the surface is designed for it,
by the regular form and LQR of SPEC 3 on the augmented system.

Augmented plant
---------------
Eq. 6-7 read ``Zdot = A Z + B (u - f + k_b x_0)``. Collect what enters through ``B`` in the
net base force

    v = u - f + k_b x_0                                                               (A2)

Then ``X = (Z, v)`` obeys, with ``c'`` picking ``ydot_b`` out of ``Z``,

    Xdot = Ah X + Bh u_c + D(t)                                                       (A3)
    Ah = [[A, B], [-k_h c', -w_f]],   Bh = (0, ..., 0, w_f),
    D  = (0, ..., 0, -w_f (f - k_b x_0) + (k_h + k_b) xdot_0 - fdot).

The command enters only through the force state, and the disturbance ``D`` only there too
(matched, as ``E`` is in Eq. 7).

Regular form and LQR (Eq. 8-9)
------------------------------
``Bh`` has a single non-zero entry, so the regular form's coordinates are ``w1 = Z`` (up to
an orthogonal rotation) and ``w2 = v``: the net force is the "control" of the building,

    Zdot = A Z + B v.                                                                 (A4)

LQR on ``J = integral (Z' Q Z + q_v v^2) dt`` gives ``v = -K Z``, ``K = B' X_r / q_v`` from
``A' X_r + X_r A - X_r B B' X_r / q_v + Q = 0``, and the surface (Eq. 8)

    S = Ph X = (v + K Z) / (m_b w_f) = (u - u_d) / (m_b w_f),   u_d = f - k_b x_0 - K Z,   (A5)

normalised ``Ph Bh = 1/m_b`` as :mod:`harness.control.surfaces` does (S in m/s). On ``S = 0``
the building moves as ``Zdot = (A - B K) Z``: the LQR-regulated building, free of friction
and table (both are in ``v``). :func:`actuator_lqr_surface` builds ``Ph`` with
:func:`harness.control.surfaces.lqr_surface` on :class:`AugmentedModel`.

Equivalent control (Eq. 11-13)
------------------------------
``V = S^2 / 2`` gives ``Vdot = lambda (u_c - G)`` with

    lambda = S (Ph Bh) = S / m_b                                                      (A6)
    G = -(Ph Bh)^-1 Ph (Ah X + D)
      = u + [k_h xdot_b - k_b xdot_0 - K (A Z + B v) + fdot] / w_f.                   (A7)

``G`` holds the measured force ``u`` (the load cell), the cancellation of the velocity
feedback ``(k_h / w_f) xdot_b``, and the desired force's rate over ``w_f`` (the inverse of the
lag). ``fdot`` is not known (the friction reverses within ``D_y`` of travel): it is left out,
a matched disturbance of S. The command (Eq. 13) is

    u_c = G - delta lambda,   delta = eta m_b^2,                                      (A8)

so ``Sdot = -eta S`` (plus what was left out): ``eta`` (1/s) is the rate at which the force
reaches its target. With ``eta = w_f`` (the default) the measured ``u`` cancels out of
``u_c``, which becomes the design model's inverse ``u_d + (k_h / w_f) xdot_b + udot_d / w_f``.

Output variant (Eq. 16-23)
--------------------------
A rig measures ``y_b, ydot_b, x_0, xdot_0`` and, with a load cell, ``u``. Take the output
design model of Eq. 18-23: the base mat alone, the story shear ``V_1`` unmeasured, a share
``phi`` of the springs cancelled,

    m_b yddot_b = u - f - k_b x_b + V_1,     x_b = y_b - x_0,                          (A9)

and the net force ``v_o = u - f - phi k_b x_b``. The regular form of ``(y_b, ydot_b, v_o)``
under (A1) has ``w1 = (y_b, ydot_b)`` and ``w2 = v_o``; placing the two sliding poles at
``-p1`` and ``-p2`` gives

    S = [v_o + m_b (p1 + p2) ydot_b + m_b p1 p2 y_b] / (m_b w_f) = (u - u_phi) / (m_b w_f),   (A10)

where ``u_phi = G* - delta s_1 / m_b`` is the phi controller's force (Eq. 22-23, with
``s_1 = p1 y_b + ydot_b`` of Eq. 18) and ``p2 = delta / m_b^2``. The output design keeps the
table controller's surface (``p1``, ``phi``, ``delta``) and makes the actuator's force follow
the phi force as a state. From (A1) and (A9), with ``V_1`` dropped (unmeasured, as Eq. 16-17
drop unmeasured states) and ``fdot`` dropped:

    ah_b = (u - f - k_b x_b) / m_b                                                    (A11)
    G_o = u + [k_h xdot_b + phi k_b xdot_b - (m_b p1 + delta / m_b) ah_b - (delta p1 / m_b) ydot_b] / w_f
    u_c = G_o - eta m_b S = G_o - (eta / w_f) (u - u_phi).                              (A12)

Robustness margin
-----------------
``G`` cancels the velocity feedback with the model's ``k_h / w_f``. A plant whose ratio is
smaller is over-cancelled: the tracking error ``e = u - u_phi`` obeys
``edot = -w_f' e + (w_f'/w_f k_h - k_h') xdot_b`` (for ``eta = w_f``), a negative damper of up
to ``eps k_h / w_f`` between table and base mat. With ``k_h`` and ``w_f`` each off by up to a
share ``a``, the true ratio is at least ``(1 - a)/(1 + a)`` of the model's, so
``eps = 2 a / (1 + a)``. The output design adds that damping to the sliding motion,

    delta += m_b eps k_h / w_f,     i.e.  p2 += eps k_h / (w_f m_b),                     (A13)

so that in the worst case the base mat keeps the phi surface's own damping ``m_b p1``.
(0.46 x 94 kN s/m = 43 kN s/m, ``p2`` = 38 1/s for the shipped actuator and ``a = 0.3``.)

Command range
-------------
The command is not the force: it exceeds the force by the flow the valve must pass,
``(k_h / w_f) xdot_b`` (15 kN at the 0.16 m/s of El Centro's table at 0.34 g, time scale 2).
The supervisor's force limit clamps the command, so where ``|u| + (k_h / w_f) |xdot_b|`` exceeds
it the cylinder cannot stroke as fast as the table and drags the base mat along, whatever the
design; the force the cylinder applies stays far below the limit.

The design's actuator numbers (``k_h``, ``w_f``) come from the profile's actuator model
(:class:`ActuatorModel`), never from a run's outcome.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from drivers.measurements import Measurements
from harness.control.controllers import PhiSMC, _SlidingModeInternals
from harness.control.surfaces import lqr_surface, sliding_poles
from harness.errors import ModelError
from harness.hydraulics import linear
from harness.model.building import StateSpace


@dataclass(frozen=True)
class ActuatorModel:
    """The first-order design model of the force-controlled actuator (A1).

    Attributes
    ----------
    stiffness_N_per_m : float
        ``k_h``, the oil column's stiffness (N/m): the gain of the natural velocity feedback.
        0 for a force source.
    bandwidth_rad_s : float
        ``w_f``, the force loop's bandwidth on a blocked piston (rad/s).
    """

    stiffness_N_per_m: float
    bandwidth_rad_s: float

    def __post_init__(self) -> None:
        if not self.bandwidth_rad_s > 0.0 or not math.isfinite(self.bandwidth_rad_s):
            raise ModelError(f"actuator bandwidth w_f must be > 0 rad/s, found {self.bandwidth_rad_s}")
        if not self.stiffness_N_per_m >= 0.0 or not math.isfinite(self.stiffness_N_per_m):
            raise ModelError(f"actuator stiffness k_h must be >= 0 N/m, found {self.stiffness_N_per_m}")

    @property
    def loop_damping_Ns_per_m(self) -> float:
        """``k_h / w_f`` (N s/m): the damper the force loop leaves between table and base mat."""
        return linear.loop_damping_Ns_per_m(self.stiffness_N_per_m, self.bandwidth_rad_s)

    def scaled(self, stiffness: float = 1.0, bandwidth: float = 1.0) -> ActuatorModel:
        """The model with ``k_h`` and ``w_f`` multiplied (model-error studies)."""
        return ActuatorModel(self.stiffness_N_per_m * stiffness, self.bandwidth_rad_s * bandwidth)

    @classmethod
    def from_rig_actuator(cls, actuator) -> ActuatorModel:
        """From a profile's ``rig.actuator`` (:class:`harness.rig.config.ActuatorConfig`).

        ``servo_hydraulic``: ``w_f = 2 pi force_loop_bandwidth_hz`` and the velocity feedback
        the servo controller leaves (``rig.actuator.hydraulics``,
        :meth:`~harness.hydraulics.config.HydraulicActuatorConfig.feedback_stiffness_N_per_m`,
        from :mod:`harness.hydraulics.linear`): with velocity feed-forward at gain ``alpha`` the
        term ``k_h xdot_b`` of (A1) becomes ``(1 - alpha) k_h xdot_b`` (SPEC 7a'), so ``k_h`` here
        is ``(1 - alpha) k_h``.
        ``first_order``: a force source, ``k_h = 0`` and ``w_f = 1 / time_constant_s``.

        Raises
        ------
        ModelError
            For the ``ideal`` and ``second_order`` models, which (A1) does not describe.
        """
        if actuator.model == "servo_hydraulic":
            hydraulics = actuator.hydraulics
            return cls(hydraulics.feedback_stiffness_N_per_m(), hydraulics.bandwidth_rad_s())
        if actuator.model == "first_order":
            return cls(0.0, 1.0 / actuator.time_constant_s)
        raise ModelError(
            f"an actuator-aware design needs a servo_hydraulic or first_order rig.actuator.model, found {actuator.model!r}"
        )


@dataclass(frozen=True)
class AugmentedModel:
    """The building with the actuator's net force as a state, ``X = (Z, v)`` (A3).

    Attributes
    ----------
    A : ndarray (N+1, N+1)
        ``Ah``.
    B : ndarray (N+1,)
        ``Bh = (0, ..., 0, w_f)``.
    base_mass_kg : float
    building : StateSpace
        The building's Eq. 6-7.
    actuator : ActuatorModel
    """

    A: np.ndarray
    B: np.ndarray
    base_mass_kg: float
    building: StateSpace
    actuator: ActuatorModel

    @property
    def size(self) -> int:
        """N + 1."""
        return self.building.size + 1


def augmented_model(building: StateSpace, actuator: ActuatorModel) -> AugmentedModel:
    """``Ah`` and ``Bh`` of (A3) for ``building`` driven through ``actuator``."""
    n = building.size
    a_matrix = np.zeros((n + 1, n + 1))
    a_matrix[:n, :n] = building.A
    a_matrix[:n, n] = building.B
    a_matrix[n, building.i_base_velocity] = -actuator.stiffness_N_per_m
    a_matrix[n, n] = -actuator.bandwidth_rad_s
    b_vector = np.zeros(n + 1)
    b_vector[n] = actuator.bandwidth_rad_s
    return AugmentedModel(a_matrix, b_vector, building.base_mass_kg, building, actuator)


def actuator_lqr_surface(model: AugmentedModel, q_state: np.ndarray, force_weight: float) -> np.ndarray:
    """``Ph`` of (A5): LQR on the regular form of the augmented model.

    Parameters
    ----------
    model : AugmentedModel
    q_state : ndarray (N,)
        Diagonal of Q on Z (:func:`harness.control.surfaces.q_diagonal_from_groups`).
    force_weight : float
        ``q_v`` (1/N^2 on the scale of Q), > 0.

    Returns
    -------
    ndarray (N+1,)
        ``Ph``, with ``Ph Bh = 1 / m_b``.

    Raises
    ------
    ModelError
        If the weights are negative or the sliding motion is not stable.
    """
    if not force_weight > 0.0:
        raise ModelError(f"the LQR weight on the actuator force must be > 0, found {force_weight}")
    return lqr_surface(model, np.append(np.asarray(q_state, dtype=float), force_weight))


def augmented_sliding_poles(model: AugmentedModel, p_row: np.ndarray) -> np.ndarray:
    """The N eigenvalues (1/s) of the motion on ``S = Ph X = 0``: ``A - B K`` of (A5)."""
    return sliding_poles(model, p_row)


def robust_sliding_margin(base_mass_kg: float, actuator: ActuatorModel, uncertainty: float) -> float:
    """The sliding margin (N kg s/m) of (A13) for ``k_h`` and ``w_f`` each off by up to ``uncertainty`` (0..1)."""
    if not 0.0 <= uncertainty < 1.0:
        raise ModelError(f"the actuator's model uncertainty must be in [0, 1), found {uncertainty}")
    over_cancelled = 2.0 * uncertainty / (1.0 + uncertainty)
    return base_mass_kg * over_cancelled * actuator.loop_damping_Ns_per_m


class ActuatorStateFeedbackSMC(_SlidingModeInternals):
    """Full-state sliding-mode control on the augmented plant, (A5)-(A8).

    Reads Z from ``state`` and the actuator's force from ``meas.actuator_force_N``; offline
    only (a rig does not measure the drifts): ``harness simulate --rig-effects`` hands it the
    twin's true plant state.

    Parameters
    ----------
    name : str
    model : AugmentedModel
        The design model: building (possibly mis-scaled) and actuator.
    p_row : ndarray (N+1,)
        ``Ph`` of (A5).
    reaching_rate_per_s : float
        ``eta`` of (A8), > 0.
    """

    needs_full_state: ClassVar[bool] = True

    def __init__(self, name: str, model: AugmentedModel, p_row: np.ndarray, reaching_rate_per_s: float):
        if not reaching_rate_per_s > 0.0:
            raise ModelError(f"the reaching rate eta must be > 0 1/s, found {reaching_rate_per_s}")
        self.name = name
        self.model = model
        self.p_row = np.asarray(p_row, dtype=float)
        self._pb = float(self.p_row @ model.B)
        self._pa = self.p_row @ model.A
        self._n = model.building.size
        self._kb = model.building.restoring_stiffness_N_per_m
        self._kh = model.actuator.stiffness_N_per_m
        self._wf = model.actuator.bandwidth_rad_s
        self.reaching_rate_per_s = float(reaching_rate_per_s)
        self.delta = self.reaching_rate_per_s * model.base_mass_kg**2
        self._x = np.zeros(self._n + 1)
        self.reset()

    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None) -> float:
        """The force command (N) from Z (``state``), the load cell, the table and the friction estimate."""
        if state is None:
            raise ModelError(f"controller {self.name!r} needs the full state Z (offline only)")
        x = self._x
        x[: self._n] = state[: self._n]
        x[self._n] = meas.actuator_force_N - friction_N + self._kb * meas.table_displacement_m  # v, (A2)
        s = float(self.p_row @ x)
        # D of (A3) without fdot; G = -(Ph Bh)^-1 Ph (Ah X + D)               (A7)
        disturbance = (-self._wf * (friction_N - self._kb * meas.table_displacement_m)
                       + (self._kh + self._kb) * meas.table_velocity_m_s)
        g = -(float(self._pa @ x) + self.p_row[self._n] * disturbance) / self._pb
        lam = s * self._pb  # (A6)
        self.sliding_variable = s
        self.equivalent_force_N = g
        self.gain_lambda = lam
        self.force_N = g - self.delta * lam  # (A8)
        return self.force_N


class ActuatorOutputSMC(PhiSMC):
    """Output sliding-mode control on the base mat augmented with the actuator, (A9)-(A12).

    Measures ``y_b, ydot_b, x_0, xdot_0`` and the load cell's ``u`` (``meas.actuator_force_N``):
    runs on a rig.

    Parameters
    ----------
    name : str
    base_mass_kg, restoring_stiffness_N_per_m : float
        Design values of m_b and k_b.
    p1_per_s, phi, delta : float
        The phi controller's surface (Eq. 22-23): pole (1/s), share of the springs
        cancelled, sliding margin (N kg s/m; ``p2 = delta / m_b^2``).
    actuator : ActuatorModel
    reaching_rate_per_s : float
        ``eta`` of (A12), > 0.
    """

    needs_full_state: ClassVar[bool] = False

    def __init__(
        self, name: str, base_mass_kg: float, restoring_stiffness_N_per_m: float, p1_per_s: float, phi: float, delta: float,
        actuator: ActuatorModel, reaching_rate_per_s: float,
    ):
        if not reaching_rate_per_s > 0.0:
            raise ModelError(f"the reaching rate eta must be > 0 1/s, found {reaching_rate_per_s}")
        self.actuator = actuator
        self.reaching_rate_per_s = float(reaching_rate_per_s)
        #: Force the phi surface asks for (N), u_phi of (A10).
        self.target_force_N = 0.0
        super().__init__(name, base_mass_kg, restoring_stiffness_N_per_m, p1_per_s, phi, delta)

    def reset(self) -> None:
        """Clear the internals."""
        super().reset()
        self.target_force_N = 0.0

    def update(self, t: float, dt: float, meas: Measurements, friction_N: float, state: np.ndarray | None = None) -> float:
        """The force command (N) from the measured base mat, table, load cell and the friction estimate."""
        m_b, k_b, p1, delta = self.base_mass_kg, self.restoring_stiffness_N_per_m, self.p1_per_s, self.delta
        w_f, k_h = self.actuator.bandwidth_rad_s, self.actuator.stiffness_N_per_m
        ydot_b, u = meas.base_velocity_m_s, meas.actuator_force_N
        x_b, xdot_b = meas.sliding_displacement_m, meas.sliding_velocity_m_s
        u_phi = super().update(t, dt, meas, friction_N, state)  # the phi controller's force, Eq. 18-23
        s = (u - u_phi) / (m_b * w_f)  # (A10)
        base_acceleration = (u - friction_N - k_b * x_b) / m_b  # (A11), V_1 unmeasured
        target_rate = (self.phi * k_b * xdot_b - (m_b * p1 + delta / m_b) * base_acceleration
                       - delta * p1 / m_b * ydot_b)
        g = u + (k_h * xdot_b + target_rate) / w_f  # (A11)
        lam = s / m_b  # (A6)
        self.sliding_variable = s
        self.equivalent_force_N = g
        self.gain_lambda = lam
        self.target_force_N = u_phi
        self.force_N = g - self.reaching_rate_per_s * m_b * s  # (A12)
        return self.force_N
