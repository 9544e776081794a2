"""The control actuator's servo controller: velocity feed-forward from its own stroke LVDT (SPEC 7a').

A plain proportional force loop ``i = K_p (u_cmd - u_meas)`` on a piston that strokes at
``xdot_b`` leaves the natural velocity feedback ``c = A / (K_q K_p K_v)`` (``k_h / w_f``)
between table and base mat. Labs that control force on a moving specimen open the valve
for the flow the moving piston takes (Dimig, Shield, French et al., J. Struct. Eng.
125(9), 1999; Shield, French & Timm 2001; Zhao, Shield, French & Posbergh 2005; MTS
digital controllers' feed-forward gain for force control of soft specimens)::

    i = K_p (u_cmd - u_meas) + alpha (A / (K_q K_v)) v_s

``v_s`` is the stroke velocity as the servo controller measures it: the derivative of its
own stroke LVDT (noise, quantization and conversion delay), through a first-order low-pass
at ``velocity_filter_hz``. ``alpha`` is the fraction of nominal cancellation and ``K_q`` the
controller's nominal valve gain (``rig.actuator.hydraulics``, the design), not the plant's.
In the normalized units of :mod:`harness.hydraulics.cylinder` (``K_v = 1``, ``K_q = q_nl``) the
feed-forward current is ``alpha A v_s / q_nl``.

The law's force-loop part is evaluated continuously in the plant's derivative
(:func:`harness.hydraulics.cylinder.force_loop_current`); the feed-forward current is the
digital part, computed once per physics sub-step by :class:`StrokeVelocityFeedforward`
and held over it, as a servo controller's sample-and-hold does.

What feed-forward leaves behind is physics: at steady stroke velocity ``v`` and load
pressure ``p_L`` the force lost is ``c v (1 / s - alpha K_q,true / K_q,nom)`` with the
orifice's ``s = sqrt(1 - sign(v) p_L / p_s)`` (:func:`steady_bleed_N`), plus the
sensor's delay and filter lag times ``c`` times the stroke acceleration.

No Delta-P term in this force loop (SPEC 7a' leaves it optional): the load cell measures
``A p_L`` less the seal friction, so a differential-pressure gain here would be a second
proportional gain on the same quantity, not a new one. Delta-P stabilisation damps an oil
column under displacement control, where nothing else feeds the pressure back: the shaking
table's own loop has it (``rig.table.pressure_feedback_damping_ratio``).
"""

from __future__ import annotations

import math

import numpy as np

from harness.hydraulics.config import VelocityFeedforwardConfig


def orifice_gain(load_pressure_Pa: float, supply_pressure_Pa: float, flow_sign: float) -> float:
    """``s = sqrt(1 - sign(q) p_L / p_s)``: the valve's flow per opening relative to no load (0 past the supply)."""
    drop = 1.0 - math.copysign(1.0, flow_sign) * load_pressure_Pa / supply_pressure_Pa
    return math.sqrt(drop) if drop > 0.0 else 0.0


def steady_bleed_N(
    loop_damping_Ns_per_m: float, stroke_velocity_m_s: float, load_pressure_Pa: float, supply_pressure_Pa: float,
    feedforward_gain: float, flow_gain_ratio: float = 1.0,
) -> float:
    """The force a force loop with velocity feed-forward loses at steady stroke velocity (N).

    At steady state the valve passes the piston's flow, ``q_nl x_v s = A v``, and the
    spool sits at ``K_p e + alpha A v / q_nom``, so the force error is

        e = c v (1 / s - alpha q_nl / q_nom),    c = A / (K_p q_nl) = k_h / w_f

    (leakage neglected). ``alpha = 0`` is the plain loop's ``c v / s``; with ``alpha = 1`` and
    the nominal valve gain the plant's, it is ``c v (1 / s - 1)``: zero at no load, and of the
    sign that lowers ``|u|`` otherwise (``s < 1`` when the force pushes along the stroke).

    Parameters
    ----------
    loop_damping_Ns_per_m : float
        ``c = k_h / w_f`` (N s/m) of the plant's loop.
    stroke_velocity_m_s : float
        ``v`` (m/s), the piston's velocity (the sliding velocity).
    load_pressure_Pa, supply_pressure_Pa : float
        ``p_L`` and ``p_s`` (Pa).
    feedforward_gain : float
        ``alpha``.
    flow_gain_ratio : float
        ``q_nl / q_nom``, the plant's valve gain over the controller's nominal one.
    """
    s = orifice_gain(load_pressure_Pa, supply_pressure_Pa, stroke_velocity_m_s)
    return loop_damping_Ns_per_m * stroke_velocity_m_s * (1.0 / s - feedforward_gain * flow_gain_ratio)


class StrokeVelocityFeedforward:
    """The feed-forward current of the servo controller, one physics sub-step at a time.

    Parameters
    ----------
    config : VelocityFeedforwardConfig
        ``gain`` (alpha), the filter's corner and the LVDT.
    current_per_m_s : float
        ``A / q_nl`` of the controller's nominal cylinder (normalized current per m/s at alpha = 1).
    substep_s : float
        The servo controller's sample period, the physics sub-step (s).
    rng : numpy.random.Generator
        The LVDT's noise.
    """

    def __init__(self, config: VelocityFeedforwardConfig, current_per_m_s: float, substep_s: float,
                 rng: np.random.Generator):
        self.config = config
        self.gain_per_m_s = config.gain * current_per_m_s
        self.substep_s = float(substep_s)
        self._rng = rng
        lvdt = config.lvdt
        self._delay_line = np.zeros(int(math.floor(lvdt.delay_s / self.substep_s + 0.5)) + 1)
        self._head = 0
        self._smoothing = 1.0 - math.exp(-2.0 * math.pi * config.velocity_filter_hz * self.substep_s)
        self._last_reading_m = 0.0
        #: The filtered stroke velocity v_s (m/s).
        self.velocity_m_s = 0.0

    def reset(self, stroke_m: float) -> None:
        """At rest at ``stroke_m`` (m): the delay line filled, the velocity zero."""
        self._delay_line[:] = stroke_m
        self._last_reading_m = self._read(stroke_m)
        self.velocity_m_s = 0.0

    def _read(self, stroke_m: float) -> float:
        lvdt = self.config.lvdt
        reading = stroke_m + (lvdt.noise_std_m * float(self._rng.standard_normal()) if lvdt.noise_std_m > 0.0 else 0.0)
        if lvdt.quantization_m > 0.0:
            reading = lvdt.quantization_m * math.floor(reading / lvdt.quantization_m + 0.5)
        return reading

    def update(self, stroke_m: float) -> float:
        """Sample the true stroke ``stroke_m`` (m); return the feed-forward current to hold (normalized)."""
        line = self._delay_line
        self._head = (self._head + 1) % line.size
        line[self._head] = stroke_m
        reading = self._read(float(line[(self._head + 1) % line.size]))
        raw = (reading - self._last_reading_m) / self.substep_s
        self._last_reading_m = reading
        self.velocity_m_s += self._smoothing * (raw - self.velocity_m_s)
        return self.gain_per_m_s * self.velocity_m_s
