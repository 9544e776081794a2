"""Gain margin of the friction estimator's loop on the stuck bearing, and the estimator's yield displacement it sets.

The loop (issue 31, item 6; benchmarks/limit_cycle.py measures it). When the bearing sticks
its Bouc-Wen friction (Eq. 3-5) is a spring of ``k0 = mu(0) W / D_y``. The friction estimator
runs the same Bouc-Wen on the measured sliding displacement and the controller adds its
estimate to the force: a spring fed back positively, cancelled by the bearing's only through
the loop's delay ``T``. With the actuator's command-to-force response (force loop, valve,
natural velocity feedback and the servo controller's velocity feed-forward, SPEC 7a') and the
base mat on the stuck bearing, the estimator's loop is

    L(s) = k0_est e^(-sT) x_b / u_c,   x_b / u_c = w_f V / [(m_b s^2 + k0)(s + w_f V) - k_h (alpha V H - 1) s]

with ``V`` the valve, ``H`` the feed-forward's LVDT delay and filter, ``k0`` the bearing's
pre-sliding stiffness (its ``D_y``) and ``k0_est`` the estimator's (its own yield
displacement). Positive feedback: a crossing of phase 0 with ``|L| > 1`` is unstable, and the
estimator's saturation (``|nu| <= 1``) turns it into a limit cycle. The controller's own terms
(``m_b p1 ydot_b``, ``phi k_b x_b``) are small at these frequencies and left out.

The design rule: a gain margin of 6 dB, ``|L| <= 0.5`` at the phase-0 crossing (the usual
minimum for a feedback loop, e.g. Ogata, *Modern Control Engineering*, 5th ed., Sec. 7-6;
Franklin, Powell & Emami-Naeini, *Feedback Control of Dynamic Systems*, Sec. 6.4), in real
time (:data:`REALTIME_DELAY_S`) and without the feed-forward (``alpha = 0``), the worst case a
lab may have. ``L`` is proportional to ``k0_est``, that is to ``1 / D_y_est``: hence
:func:`margin_yield_displacement_m`.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from harness.control.sections import ControlSections

#: Delay around the estimator's loop in lockstep (s): sensor 1 ms, half the 2 ms hold, command transport 1 ms ...
LOCKSTEP_DELAY_S = 0.003
#: ... and in real time one more period of asynchrony on average.
REALTIME_DELAY_S = 0.005
#: Largest ``|L|`` at the phase-0 crossing: a 6 dB gain margin.
MAX_CROSSING_GAIN = 0.5
#: Band searched for phase-0 crossings (Hz) and its resolution (points).
CROSSING_BAND_HZ, CROSSING_POINTS = (5.0, 150.0), 14_501


def estimator_yield_displacement_m(profile: ControlSections) -> float:
    """The estimator's pre-sliding (yield) displacement (m): ``control.estimator.yield_displacement_m``, else ``D_y``."""
    own = profile.control.estimator.yield_displacement_m
    return profile.bearing.yield_displacement_m if own is None else own


def estimator_loop(
    profile: ControlSections,
    freq_hz: np.ndarray,
    delay_s: float,
    feedforward_gain: float | None = None,
    estimator_yield_m: float | None = None,
) -> np.ndarray:
    """``L(j 2 pi f)`` of the friction estimator's loop on the stuck bearing (module docstring).

    Parameters
    ----------
    profile : ControlSections
    freq_hz : numpy.ndarray
        Frequencies (Hz).
    delay_s : float
        Delay around the loop (s).
    feedforward_gain : float, optional
        The servo controller's velocity feed-forward ``alpha``; the profile's if None.
    estimator_yield_m : float, optional
        The estimator's yield displacement (m); the profile's (:func:`estimator_yield_displacement_m`) if None.
    """
    hydraulics = profile.rig.actuator.hydraulics
    cylinder, feedforward = hydraulics.cylinder, hydraulics.feedforward
    alpha = feedforward.gain if feedforward_gain is None else feedforward_gain
    bearing, m_b = profile.bearing, profile.structure.base_mass_kg
    friction_at_rest_N = (bearing.mu_max - bearing.mu_delta) * profile.structure.total_weight_N
    k0 = friction_at_rest_N / bearing.yield_displacement_m
    own_yield_m = estimator_yield_displacement_m(profile) if estimator_yield_m is None else estimator_yield_m
    k0_estimator = friction_at_rest_N / own_yield_m
    w_f = hydraulics.bandwidth_rad_s()
    w_v, z_v = 2.0 * math.pi * cylinder.valve_bandwidth_hz, cylinder.valve_damping_ratio
    s = 2j * math.pi * np.asarray(freq_hz, dtype=float)
    valve = w_v**2 / (s * s + 2.0 * z_v * w_v * s + w_v**2)
    sampled = feedforward.lvdt.delay_s + 0.5 * profile.rig.physics_substep_s  # the LVDT and the backward difference
    lvdt = np.exp(-s * sampled) / (1.0 + s / (2.0 * math.pi * feedforward.velocity_filter_hz))
    k_h = cylinder.hydraulic_stiffness_N_per_m
    plant = w_f * valve / ((m_b * s * s + k0) * (s + w_f * valve) - k_h * (alpha * valve * lvdt - 1.0) * s)
    return k0_estimator * np.exp(-s * delay_s) * plant


def phase_crossings(
    profile: ControlSections, delay_s: float, feedforward_gain: float | None = None, estimator_yield_m: float | None = None
) -> list[tuple[float, float]]:
    """``(f Hz, |L|)`` where the loop's phase crosses 0 in :data:`CROSSING_BAND_HZ`."""
    freq = np.linspace(*CROSSING_BAND_HZ, CROSSING_POINTS)
    loop = estimator_loop(profile, freq, delay_s, feedforward_gain, estimator_yield_m)
    phase = np.angle(loop)
    found = np.nonzero(np.diff(np.sign(phase)) != 0)[0]
    return [(float(freq[i]), float(abs(loop[i]))) for i in found if abs(phase[i]) < 0.5]


def crossing_gain(
    profile: ControlSections, delay_s: float, feedforward_gain: float | None = None, estimator_yield_m: float | None = None
) -> float:
    """The largest ``|L|`` at a phase-0 crossing (0 if the phase does not cross 0 in the band)."""
    return max((gain for _, gain in phase_crossings(profile, delay_s, feedforward_gain, estimator_yield_m)), default=0.0)


def margin_yield_displacement_m(profile: ControlSections, delay_s: float = REALTIME_DELAY_S,
                                feedforward_gain: float = 0.0) -> float:
    """The least estimator yield displacement (m) with ``|L| <= MAX_CROSSING_GAIN`` at the crossing.

    ``L`` is proportional to ``1 / D_y_est`` at every frequency (the crossings do not move),
    so ``D_y_est = D_y |L(D_y)| / MAX_CROSSING_GAIN``, with ``|L(D_y)|`` the loop's gain at
    its crossing with the estimator on the bearing's own ``D_y``.
    """
    bearing_yield_m = profile.bearing.yield_displacement_m
    gain = crossing_gain(profile, delay_s, feedforward_gain, bearing_yield_m)
    return bearing_yield_m * gain / MAX_CROSSING_GAIN
