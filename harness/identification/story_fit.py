"""Story stiffness and damping that reproduce the measured floor accelerations with the profile's masses.

The fixed-base shear building of Eq. 1 (floor masses ``m_j`` from the profile, story stiffness
``k_j`` and damping ``c_j`` searched) driven by the measured base-mat acceleration:

    M uddot + C udot + K u = -M 1 a_b,      a_j = -(M^-1 (K u + C udot))_j

``u`` the floors' displacements relative to the base mat. Its floor accelerations are simulated
from the measured ``a_b`` (:mod:`harness.identification.lti`) and compared with the measured
ones, over every floor and run, by :func:`scipy.optimize.least_squares`, with a time delay as
in :mod:`harness.identification.modal_fit`. The search starts from stiffnesses whose undamped
frequencies are the identified modes' (:func:`matching_stiffness`), so it begins in the right
valley: the time-domain error of lightly damped modes has many.

:func:`fit_frequency_response` fits the same building to the measured frequency response
instead: coarser (the Welch average widens the peaks), but its error has one broad valley, so
it finds the modes from a start 20-30 % off. It gives the modal fit its starting frequencies.

Damping comes in two forms, as the profile gives it: ``per_story`` fits ``c_1..c_n``
(``structure.story_damping_Ns_per_m``); ``proportional`` fits one ratio, the first mode's, with
``C`` proportional to ``K`` (``structure.first_mode_damping_ratio``).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from harness.identification import lti
from harness.identification.choices import DampingModel
from harness.identification.fit_statistics import honest_standard_errors, time_blocks
from harness.identification.structure_records import StructureRecord
from harness.model.building import BuildingConfig, fixed_base_modes


@dataclass(frozen=True)
class StoryFit:
    """The identified stories.

    Attributes
    ----------
    building : BuildingConfig
        The profile's building with the identified stiffness and damping.
    damping_model : {"per_story", "proportional"}
    stiffness_N_per_m, stiffness_se : ndarray (n,)
    damping_Ns_per_m, damping_se : ndarray (n,)
        Per story (with ``proportional`` derived from the ratio; its standard errors too).
    first_mode_damping_ratio, first_mode_damping_se : float or None
        With ``proportional`` only.
    delay_s : float
    rms_error_m_s2 : float
        RMS of measured minus modelled floor acceleration (band-passed).
    evaluations : int
    """

    building: BuildingConfig
    damping_model: DampingModel
    stiffness_N_per_m: np.ndarray
    stiffness_se: np.ndarray
    damping_Ns_per_m: np.ndarray
    damping_se: np.ndarray
    first_mode_damping_ratio: float | None
    first_mode_damping_se: float | None
    delay_s: float
    rms_error_m_s2: float
    evaluations: int

    def modes(self) -> tuple[np.ndarray, np.ndarray]:
        """The fitted building's fixed-base frequencies (Hz) and damping ratios."""
        omega, zeta = fixed_base_modes(self.building)
        return omega / (2.0 * np.pi), zeta


def with_model_error(stories: StoryFit, modal_frequency_hz: np.ndarray, modal_first_damping: float | None = None) -> StoryFit:
    """``stories`` with each stiffness's (and the first-mode damping ratio's) standard error widened by the model's miss.

    The shear building with the profile's masses is a model: where its modes miss the modal
    fit's (which uses no masses) by a relative ``gap`` in frequency, its stiffnesses are no surer
    than ``2 gap`` (``k`` goes with ``f^2``), however small the residuals' scatter. That term is
    added to each stiffness's standard error in quadrature. On the virtual rig the third mode is
    reproduced 0.02-0.44 % low and the story stiffnesses miss by up to 1 %, several times the
    scatter alone (``benchmarks/README.md``). Likewise the first-mode damping ratio of the
    ``proportional`` form: it ties every mode's damping to the stiffness, and where it differs
    from the modal fit's own first-mode damping (``modal_first_damping``) by ``d``, ``d`` is added
    to its standard error in quadrature (on the virtual rig the scatter alone covered the truth in
    14 of 20 seeds of 60 s).
    """
    frequency_hz, _ = stories.modes()
    gap = float(np.max(np.abs(frequency_hz / np.asarray(modal_frequency_hz) - 1.0)))
    widened = np.hypot(stories.stiffness_se, 2.0 * gap * stories.stiffness_N_per_m)
    ratio_se = stories.first_mode_damping_se
    if stories.first_mode_damping_ratio is not None and ratio_se is not None and modal_first_damping is not None:
        ratio_se = float(np.hypot(ratio_se, stories.first_mode_damping_ratio - modal_first_damping))
    return dataclasses.replace(stories, stiffness_se=widened, first_mode_damping_se=ratio_se)


def shear_matrices(stiffness: np.ndarray, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fixed-base stiffness and damping matrices of a shear building (stories bottom up)."""
    n = len(stiffness)

    def assembled(values: np.ndarray) -> np.ndarray:
        matrix = np.diag(values.astype(float))
        matrix[:-1, :-1] += np.diag(values[1:])
        for j in range(1, n):
            matrix[j - 1, j] = matrix[j, j - 1] = -values[j]
        return matrix

    return assembled(stiffness), assembled(damping)


def floor_response(masses: np.ndarray, stiffness: np.ndarray, damping: np.ndarray, base: np.ndarray, dt_s: float) -> np.ndarray:
    """Absolute floor accelerations (n, N) of the fixed-base building driven by the base acceleration ``base``."""
    n = len(masses)
    k_matrix, c_matrix = shear_matrices(stiffness, damping)
    k_over_m, c_over_m = k_matrix / masses[:, None], c_matrix / masses[:, None]
    a_matrix = np.block([[np.zeros((n, n)), np.eye(n)], [-k_over_m, -c_over_m]])
    b_vector = np.concatenate([np.zeros(n), -np.ones(n)])
    return lti.simulate(a_matrix, b_vector, np.hstack([-k_over_m, -c_over_m]), np.zeros(n), base, dt_s)


def floor_frequency_response(masses: np.ndarray, stiffness: np.ndarray, damping: np.ndarray, freq_hz: np.ndarray,
                             delay_s: float = 0.0) -> np.ndarray:
    """``a_j / a_b`` of the fixed-base building at ``freq_hz`` (n, F): ``1 + s^2 U`` with ``(M s^2 + C s + K) U = -M 1``."""
    k_matrix, c_matrix = shear_matrices(stiffness, damping)
    m_matrix = np.diag(masses)
    out = np.empty((len(masses), len(freq_hz)), dtype=complex)
    for i, f in enumerate(freq_hz):
        s = 2j * np.pi * f
        relative = np.linalg.solve(m_matrix * s**2 + c_matrix * s + k_matrix, -masses.astype(complex))
        out[:, i] = (1.0 + s**2 * relative) * np.exp(-s * delay_s)
    return out


def undamped_frequencies_hz(masses: np.ndarray, stiffness: np.ndarray) -> np.ndarray:
    """Undamped fixed-base frequencies (Hz), ascending."""
    k_matrix, _ = shear_matrices(stiffness, np.zeros_like(stiffness))
    scaled = k_matrix / np.sqrt(np.outer(masses, masses))  # M^-1/2 K M^-1/2: symmetric
    return np.sqrt(np.maximum(np.linalg.eigvalsh(scaled), 0.0)) / (2.0 * np.pi)


def matching_stiffness(masses: np.ndarray, start: np.ndarray, target_hz: np.ndarray) -> np.ndarray:
    """Story stiffnesses near ``start`` whose undamped frequencies are ``target_hz`` (as many as there are stories)."""
    solution = optimize.least_squares(
        lambda log_scale: np.log(undamped_frequencies_hz(masses, start * np.exp(log_scale))[: len(target_hz)] / target_hz),
        np.zeros(len(start)), bounds=(np.full(len(start), -3.0), np.full(len(start), 3.0)),
    )
    return start * np.exp(solution.x)


def fit_frequency_response(freq_hz: np.ndarray, response: np.ndarray, coherence: np.ndarray, masses: np.ndarray,
                           stiffness: np.ndarray, damping: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Story stiffness and damping whose ``a_j / a_b`` fits the measured one, each bin weighted by its precision.

    The error of each bin is relative to the measured value and to the H1 estimate's own
    scatter, ``sqrt((1 - coherence) / coherence)``, so low-coherence bins (noise, the base mat's
    antiresonances) weigh little. Starts from ``stiffness`` and ``damping``; a delay is fitted too.
    """
    gamma = np.clip(coherence, 1e-3, 1.0 - 1e-6)
    weight = 1.0 / (np.abs(response) * np.sqrt((1.0 - gamma) / gamma) + 1e-9)
    n = len(masses)

    def residuals(theta: np.ndarray) -> np.ndarray:
        model = floor_frequency_response(masses, stiffness * np.exp(theta[:n]), damping * np.exp(theta[n:2 * n]), freq_hz,
                                         theta[-1] * 1e-3)
        error = (model - response) * weight
        return np.concatenate([error.real.ravel(), error.imag.ravel()])

    bounds = (np.concatenate([np.full(n, -1.5), np.full(2 * n - n, -4.0), [-20.0]]),
              np.concatenate([np.full(n, 1.5), np.full(n, 4.0), [20.0]]))
    solution = optimize.least_squares(residuals, np.zeros(2 * n + 1), bounds=bounds,
                                      x_scale=np.concatenate([np.full(n, 0.1), np.full(n, 0.5), [0.5]]))
    return stiffness * np.exp(solution.x[:n]), damping * np.exp(solution.x[n:2 * n])


class _Problem:
    """The building over the records, in ``theta = (ln k_j, damping, tau in ms)``; damping ``ln c_j`` or ``ln zeta_1``."""

    def __init__(self, records: Sequence[StructureRecord], masses: np.ndarray, model: DampingModel):
        self.records = tuple(records)
        self.masses = masses
        self.model = model
        self.n = len(masses)
        self.evaluations = 0

    def stories(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Stiffness and damping per story of ``theta``."""
        stiffness = np.exp(theta[: self.n])
        if self.model == "per_story":
            return stiffness, np.exp(theta[self.n: 2 * self.n])
        first_hz = undamped_frequencies_hz(self.masses, stiffness)[0]
        return stiffness, 2.0 * np.exp(theta[self.n]) / (2.0 * np.pi * first_hz) * stiffness

    def residuals(self, theta: np.ndarray) -> np.ndarray:
        self.evaluations += 1
        stiffness, damping = self.stories(theta)
        delay_s = theta[-1] * 1e-3
        parts = []
        for record in self.records:
            base = lti.delayed(record.base_acceleration, delay_s, record.dt_s)
            modelled = floor_response(self.masses, stiffness, damping, base, record.dt_s)
            parts.append((modelled - record.floor_accelerations).ravel())
        return np.concatenate(parts)


def fit_stories(records: Sequence[StructureRecord], design: BuildingConfig, mode_hz: np.ndarray, first_damping: float,
                model: DampingModel) -> StoryFit:
    """Fit story stiffness and damping to the records with ``design``'s masses; see the module docstring.

    Parameters
    ----------
    records : sequence of StructureRecord
    design : BuildingConfig
        The masses, and the stiffnesses the search starts near.
    mode_hz : ndarray
        Identified undamped frequencies (Hz), one per story: the start matches them.
    first_damping : float
        The identified first mode's damping ratio: the start's damping.
    model : {"per_story", "proportional"}
    """
    masses = np.asarray(design.floor_masses_kg, dtype=float)
    n = len(masses)
    stiffness0 = matching_stiffness(masses, np.asarray(design.story_stiffness_N_per_m, dtype=float), np.asarray(mode_hz))
    first_omega = 2.0 * np.pi * undamped_frequencies_hz(masses, stiffness0)[0]
    if model == "per_story":
        damping0 = np.log(2.0 * first_damping / first_omega * stiffness0)
    else:
        damping0 = np.array([np.log(first_damping)])
    start = np.concatenate([np.log(stiffness0), damping0, [0.0]])
    problem = _Problem(records, masses, model)
    spread = np.concatenate([np.full(n, 0.7), np.full(len(damping0), 4.0), [20.0]])
    upper = start + spread
    upper[-1] = 20.0
    solution = optimize.least_squares(problem.residuals, start, bounds=(start - spread, upper),
                                      x_scale=np.concatenate([np.full(n, 0.05), np.full(len(damping0), 0.3), [0.5]]))
    theta = solution.x
    blocks = np.concatenate([np.tile(time_blocks(len(r.base_acceleration)), n) for r in records])
    se = honest_standard_errors(solution.jac, solution.fun, blocks)
    stiffness, damping = problem.stories(theta)
    stiffness_se = stiffness * se[:n]
    ratio = ratio_se = None
    if model == "per_story":
        damping_se = damping * se[n: 2 * n]
        building = dataclasses.replace(design, story_stiffness_N_per_m=tuple(float(k) for k in stiffness),
                                       story_damping_Ns_per_m=tuple(float(c) for c in damping), first_mode_damping_ratio=None)
    else:
        ratio, ratio_se = float(np.exp(theta[n])), float(np.exp(theta[n]) * se[n])
        damping_se = damping * se[n]
        building = dataclasses.replace(design, story_stiffness_N_per_m=tuple(float(k) for k in stiffness),
                                       story_damping_Ns_per_m=None, first_mode_damping_ratio=ratio)
    return StoryFit(building, model, stiffness, stiffness_se, damping, damping_se, ratio, ratio_se, float(theta[-1] * 1e-3),
                    float(np.sqrt(np.mean(solution.fun**2))), problem.evaluations)
