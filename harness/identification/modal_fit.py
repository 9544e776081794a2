"""Fixed-base modal frequencies and damping ratios from base-mat and floor accelerations (time domain).

With classical damping each floor's absolute acceleration is the base's plus the modes'
relative accelerations (Eq. 1 in modal coordinates):

    a_j(t) = a_b(t) + sum_r R_jr qddot_r(t),   qddot_r + 2 zeta_r w_r qdot_r + w_r^2 q_r = -a_b(t)

with ``R_jr = phi_jr Gamma_r`` the modal participation of mode r at floor j (``sum_r R_jr = 1``).
Each mode's ``qddot_r`` is simulated from the measured ``a_b`` (:mod:`harness.identification.lti`),
the ``R_jr`` follow by linear least squares for given frequencies and damping (variable
projection: only ``w_r``, ``zeta_r`` and a time delay are searched, by
:func:`scipy.optimize.least_squares`), and the residual is the floors' measured minus modelled
acceleration, over every floor and every run. The delay ``tau`` (``a_j`` measured at ``t``
belongs to ``a_b`` at ``t - tau``) absorbs the sensors' different timing (the story sensors are
read at half the loop's rate on the rig). Nothing here uses the masses: this is what the data
say of the modes alone.

Fitting in the time domain, not on an averaged frequency response, keeps the lightly damped
first mode's damping unbiased: its half-power bandwidth (0.05 Hz at 1 % and 2.3 Hz) is far
below the resolution a Welch average of a 30-60 s record allows, whose window would widen
the peak and overstate the damping several times.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from harness.identification import lti
from harness.identification.fit_statistics import honest_standard_errors, time_blocks
from harness.identification.structure_records import StructureRecord

#: Damping ratio the search starts from.
START_DAMPING = 0.02


@dataclass(frozen=True)
class ModalFit:
    """The identified modes.

    Attributes
    ----------
    frequency_hz, frequency_se_hz : ndarray (m,)
        Undamped natural frequencies ``w_r / 2 pi`` (Hz), ascending, and their standard errors.
    damping_ratio, damping_se : ndarray (m,)
        Damping ratios and their standard errors.
    participation : ndarray (m, n)
        ``R_jr`` as ``[r, j]``.
    delay_s : float
        The floors' timing against the base mat's (s).
    rms_error_m_s2, rms_signal_m_s2 : float
        RMS of measured minus modelled floor acceleration, and of the measured floor acceleration (band-passed).
    evaluations : int
    """

    frequency_hz: np.ndarray
    frequency_se_hz: np.ndarray
    damping_ratio: np.ndarray
    damping_se: np.ndarray
    participation: np.ndarray
    delay_s: float
    rms_error_m_s2: float
    rms_signal_m_s2: float
    evaluations: int

    @property
    def relative_rms_error(self) -> float:
        return self.rms_error_m_s2 / self.rms_signal_m_s2 if self.rms_signal_m_s2 > 0 else float("inf")


def mode_response(omega_rad_s: float, damping: float, base: np.ndarray, dt_s: float) -> np.ndarray:
    """``qddot`` of one mode driven by ``-a_b``: ``qddot = -a_b - 2 zeta w qdot - w^2 q`` (m/s^2 per unit participation)."""
    a_matrix = np.array([[0.0, 1.0], [-omega_rad_s**2, -2.0 * damping * omega_rad_s]])
    c_matrix = np.array([[-omega_rad_s**2, -2.0 * damping * omega_rad_s]])
    return lti.simulate(a_matrix, np.array([0.0, -1.0]), c_matrix, np.array([-1.0]), base, dt_s)[0]


class _Problem:
    """Variable projection over the records, in ``theta = (ln w_r, ln zeta_r, tau in ms)``."""

    def __init__(self, records: Sequence[StructureRecord], start_hz: Sequence[float]):
        self.records = tuple(records)
        self.omega0 = 2.0 * np.pi * np.asarray(start_hz, dtype=float)
        self.modes = len(start_hz)
        self.evaluations = 0

    def parts(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Basis (m, N_total), targets (n, N_total) and the participation that fits them best (m, n)."""
        self.evaluations += 1
        m = self.modes
        omega, damping, delay_s = self.omega0 * np.exp(theta[:m]), np.exp(theta[m:2 * m]), theta[2 * m] * 1e-3
        bases, targets = [], []
        for record in self.records:
            base = lti.delayed(record.base_acceleration, delay_s, record.dt_s)
            bases.append(np.array([mode_response(w, z, base, record.dt_s) for w, z in zip(omega, damping, strict=True)]))
            targets.append(record.floor_accelerations - base)
        basis, target = np.hstack(bases), np.hstack(targets)
        participation = np.linalg.lstsq(basis.T, target.T, rcond=None)[0]
        return basis, target, participation

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        basis, target, participation = self.parts(theta)
        return (target - participation.T @ basis).ravel()


def fit_modes(records: Sequence[StructureRecord], start_hz: Sequence[float]) -> ModalFit:
    """Fit ``len(start_hz)`` modes to the records, starting at those frequencies; see the module docstring."""
    problem = _Problem(records, start_hz)
    m = problem.modes
    start = np.concatenate([np.zeros(m), np.full(m, np.log(START_DAMPING)), [0.0]])
    lower = np.concatenate([np.full(m, -0.5), np.full(m, np.log(1e-4)), [-20.0]])
    upper = np.concatenate([np.full(m, 0.5), np.full(m, np.log(0.5)), [20.0]])
    solution = optimize.least_squares(problem.residuals, start, bounds=(lower, upper),
                                      x_scale=np.concatenate([np.full(m, 0.01), np.full(m, 0.3), [0.5]]))
    theta = solution.x
    samples = np.concatenate([time_blocks(len(r.base_acceleration)) for r in records])
    se = honest_standard_errors(solution.jac, solution.fun, np.tile(samples, records[0].floor_accelerations.shape[0]))
    omega = problem.omega0 * np.exp(theta[:m])
    damping = np.exp(theta[m:2 * m])
    order = np.argsort(omega)
    _, target, participation = problem.parts(theta)
    return ModalFit(
        frequency_hz=omega[order] / (2.0 * np.pi), frequency_se_hz=(omega * se[:m])[order] / (2.0 * np.pi),
        damping_ratio=damping[order], damping_se=(damping * se[m:2 * m])[order], participation=participation[order],
        delay_s=float(theta[2 * m] * 1e-3), rms_error_m_s2=float(np.sqrt(np.mean(solution.fun**2))),
        rms_signal_m_s2=float(np.sqrt(np.mean(np.hstack([r.floor_accelerations for r in records]) ** 2))),
        evaluations=problem.evaluations,
    )


def modal_response(fit: ModalFit, freq_hz: np.ndarray) -> np.ndarray:
    """The fitted modes' response ``a_j / a_b`` at ``freq_hz`` (n, F), the delay included."""
    s = 2j * np.pi * np.asarray(freq_hz)
    omega = 2.0 * np.pi * fit.frequency_hz
    relative = np.zeros((fit.participation.shape[1], len(s)), dtype=complex)
    for r, (w, z) in enumerate(zip(omega, fit.damping_ratio, strict=True)):
        mode = -(s**2) / (s**2 + 2.0 * z * w * s + w**2)  # qddot per unit a_b
        relative += fit.participation[r][:, None] * mode[None, :]
    return (1.0 + relative) * np.exp(-s * fit.delay_s)[None, :]
