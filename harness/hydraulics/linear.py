"""The force loop linearised: hydraulic stiffness, loop bandwidth and velocity feedback (SPEC 7a, 7a').

About zero load pressure the servo-valve driven cylinder of :mod:`harness.hydraulics.cylinder`
under its proportional force loop obeys, below the valve's bandwidth (SPEC 7a)::

    udot = w_f (u_c - u) - k_h xdot_b,                                              (A1)
    k_h = 4 beta_e A^2 / V_t,        w_f = K_p (4 beta_e / V_t) A q_nl,

and with the servo controller's velocity feed-forward at gain ``alpha`` (SPEC 7a') the
velocity feedback left is ``c = (1 - alpha) k_h / w_f`` (N s/m). These functions are the one
place these relations are written: the compiled plant's parameters
(:class:`harness.hydraulics.config.HydraulicActuatorConfig`), the design models
(:class:`harness.control.actuator_aware.ActuatorModel`, and through it the compensators) and
the identification (:mod:`harness.identification.actuator_fit`) all call them.

Plain floats in, plain floats out: no numpy, no numba, so the profile and the command line can
import them cheaply. The order of the floating-point operations is part of each function's
contract (the plant's parameters are packed from them, and a simulation must not change by a
rounding).
"""

from __future__ import annotations

import math


def angular_frequency_rad_s(frequency_hz: float) -> float:
    """``w = 2 pi f`` (rad/s) of a loop's or a valve's bandwidth given in hertz.

    Parameters
    ----------
    frequency_hz : float
        ``f`` (Hz), e.g. ``force_loop_bandwidth_hz``.

    Returns
    -------
    float
        ``w`` (rad/s).
    """
    return 2.0 * math.pi * frequency_hz


def pressure_gain_Pa_per_m3(bulk_modulus_Pa: float, oil_volume_m3: float) -> float:
    """``4 beta_e / V_t`` (Pa/m^3): the load pressure's rise per volume of oil pressed in (SPEC 7a).

    Parameters
    ----------
    bulk_modulus_Pa : float
        ``beta_e`` (Pa), the effective bulk modulus.
    oil_volume_m3 : float
        ``V_t`` (m^3), the trapped oil of both chambers.

    Returns
    -------
    float
        ``4 beta_e / V_t`` (Pa/m^3).
    """
    return 4.0 * bulk_modulus_Pa / oil_volume_m3


def hydraulic_stiffness_N_per_m(bulk_modulus_Pa: float, piston_area_m2: float, oil_volume_m3: float) -> float:
    """``k_h = 4 beta_e A^2 / V_t`` (N/m): the oil column's stiffness with the valve blocked (SPEC 7a).

    The gain of the natural velocity feedback ``-k_h xdot_b`` of (A1).

    Parameters
    ----------
    bulk_modulus_Pa : float
        ``beta_e`` (Pa).
    piston_area_m2 : float
        ``A`` (m^2), the effective piston area.
    oil_volume_m3 : float
        ``V_t`` (m^3).

    Returns
    -------
    float
        ``k_h`` (N/m).
    """
    return 4.0 * bulk_modulus_Pa * piston_area_m2**2 / oil_volume_m3


def bulk_modulus_Pa(hydraulic_stiffness_N_per_m: float, piston_area_m2: float, oil_volume_m3: float) -> float:
    """``beta_e = k_h V_t / (4 A^2)`` (Pa): the bulk modulus a measured ``k_h`` gives with the cylinder's geometry.

    The inverse of :func:`hydraulic_stiffness_N_per_m`.

    Parameters
    ----------
    hydraulic_stiffness_N_per_m : float
        ``k_h`` (N/m).
    piston_area_m2 : float
        ``A`` (m^2).
    oil_volume_m3 : float
        ``V_t`` (m^3).

    Returns
    -------
    float
        ``beta_e`` (Pa).
    """
    return hydraulic_stiffness_N_per_m * oil_volume_m3 / (4.0 * piston_area_m2**2)


def force_gain_per_N(
    bandwidth_rad_s: float, pressure_gain_Pa_per_m3: float, piston_area_m2: float, valve_flow_m3_per_s: float,
) -> float:
    """``K_p = w_f V_t / (4 beta_e A q_nl)`` (1/N): the force loop's gain that gives it the bandwidth ``w_f`` (SPEC 7a').

    Normalized valve current per newton of force error, on a blocked piston.

    Parameters
    ----------
    bandwidth_rad_s : float
        ``w_f`` (rad/s).
    pressure_gain_Pa_per_m3 : float
        ``4 beta_e / V_t`` (Pa/m^3, :func:`pressure_gain_Pa_per_m3`).
    piston_area_m2 : float
        ``A`` (m^2).
    valve_flow_m3_per_s : float
        ``q_nl`` (m^3/s), the valve's no-load flow at full opening.

    Returns
    -------
    float
        ``K_p`` (1/N).
    """
    return bandwidth_rad_s / (pressure_gain_Pa_per_m3 * piston_area_m2 * valve_flow_m3_per_s)


def force_loop_bandwidth_rad_s(
    gain_per_N: float, pressure_gain_Pa_per_m3: float, piston_area_m2: float, valve_flow_m3_per_s: float,
) -> float:
    """``w_f = K_p (4 beta_e / V_t) A q_nl`` (rad/s): the blocked force loop's bandwidth (SPEC 7a).

    The inverse of :func:`force_gain_per_N`.

    Parameters
    ----------
    gain_per_N : float
        ``K_p`` (1/N).
    pressure_gain_Pa_per_m3 : float
        ``4 beta_e / V_t`` (Pa/m^3).
    piston_area_m2 : float
        ``A`` (m^2).
    valve_flow_m3_per_s : float
        ``q_nl`` (m^3/s).

    Returns
    -------
    float
        ``w_f`` (rad/s).
    """
    return gain_per_N * pressure_gain_Pa_per_m3 * piston_area_m2 * valve_flow_m3_per_s


def loop_damping_Ns_per_m(hydraulic_stiffness_N_per_m: float, bandwidth_rad_s: float) -> float:
    """``c = k_h / w_f`` (N s/m): the damper a plain force loop leaves between table and base mat (SPEC 7a).

    Below the loop's bandwidth (A1) gives ``u = u_c - (k_h / w_f) xdot_b``.

    Parameters
    ----------
    hydraulic_stiffness_N_per_m : float
        ``k_h`` (N/m); for a design model, the velocity feedback's gain it carries.
    bandwidth_rad_s : float
        ``w_f`` (rad/s).

    Returns
    -------
    float
        ``k_h / w_f`` (N s/m).
    """
    return hydraulic_stiffness_N_per_m / bandwidth_rad_s


def velocity_feedback_Ns_per_m(hydraulic_stiffness_N_per_m: float, bandwidth_rad_s: float, feedforward_gain: float) -> float:
    """``c_eff = (1 - alpha) k_h / w_f`` (N s/m): the velocity feedback left with the feed-forward (SPEC 7a').

    The force lost per m/s of stroke at low frequency and zero load pressure, the feed-forward
    acting on the nominal valve gain; ``alpha = 0`` is the plain loop's :func:`loop_damping_Ns_per_m`.

    Parameters
    ----------
    hydraulic_stiffness_N_per_m : float
        ``k_h`` (N/m).
    bandwidth_rad_s : float
        ``w_f`` (rad/s).
    feedforward_gain : float
        ``alpha``, the servo controller's fraction of nominal cancellation.

    Returns
    -------
    float
        ``(1 - alpha) k_h / w_f`` (N s/m).
    """
    return (1.0 - feedforward_gain) * loop_damping_Ns_per_m(hydraulic_stiffness_N_per_m, bandwidth_rad_s)


def velocity_feedback_stiffness_N_per_m(velocity_feedback_Ns_per_m: float, bandwidth_rad_s: float) -> float:
    """``c_eff w_f = (1 - alpha) k_h`` (N/m): the gain on ``xdot_b`` in the first-order model (A1) with feed-forward.

    With velocity feed-forward the term ``k_h xdot_b`` of (A1) becomes ``(1 - alpha) k_h xdot_b``
    (SPEC 7a'); the design models carry it as their ``k_h``.

    Parameters
    ----------
    velocity_feedback_Ns_per_m : float
        ``c_eff`` (N s/m, :func:`velocity_feedback_Ns_per_m`).
    bandwidth_rad_s : float
        ``w_f`` (rad/s).

    Returns
    -------
    float
        ``(1 - alpha) k_h`` (N/m).
    """
    return velocity_feedback_Ns_per_m * bandwidth_rad_s


def feedforward_current_per_m_s(piston_area_m2: float, valve_flow_m3_per_s: float) -> float:
    """``A / q_nl`` (s/m): the normalized valve current that passes the flow of 1 m/s of stroke at no load (SPEC 7a').

    Parameters
    ----------
    piston_area_m2 : float
        ``A`` (m^2).
    valve_flow_m3_per_s : float
        ``q_nl`` (m^3/s).

    Returns
    -------
    float
        ``A / q_nl`` (s/m).
    """
    return piston_area_m2 / valve_flow_m3_per_s


def leakage_pole_per_s(hydraulic_stiffness_N_per_m: float, leakage_m3_per_s_Pa: float, piston_area_m2: float) -> float:
    """``k_h C_l / A^2`` (1/s): the pole the cross-piston leakage adds to the force loop (SPEC 7a).

    Parameters
    ----------
    hydraulic_stiffness_N_per_m : float
        ``k_h`` (N/m).
    leakage_m3_per_s_Pa : float
        ``C_l`` (m^3/(s Pa)).
    piston_area_m2 : float
        ``A`` (m^2).

    Returns
    -------
    float
        ``c = k_h C_l / A^2`` (1/s), i.e. ``(4 beta_e / V_t) C_l``.
    """
    return hydraulic_stiffness_N_per_m * leakage_m3_per_s_Pa / piston_area_m2**2
