"""Stroke and force interlocks: small, pure, clock-free objects, configured in SI units.

Each interlock has a stable :attr:`NAME` (see :mod:`harness.safety.events`), an
:attr:`ACTION`, and the four documentation strings the safety table is built from
(:attr:`DETECTS`, :attr:`BOUND`, :attr:`RESET`, and the action). After each call
:attr:`acted` says whether the interlock changed the force or fired on that call.
"""

from __future__ import annotations

from harness.safety.config import ForceConfig, StrokeConfig
from harness.safety.events import Action

#: Fade factors at or below this are exactly zero, so the band end is exact despite rounding of soft + band.
_ZERO_FACTOR = 1e-9


class StrokeSoftFade:
    """Fade the outward force beyond the soft stroke limit.

    The outward force (same sign as ``x_b``) is scaled by ``1 - (|x_b| - soft_limit_m) / fade_band_m``,
    down to zero at and after ``soft_limit_m + fade_band_m``; a force towards the centre passes untouched.
    """

    NAME = "stroke_soft"
    ACTION = Action.FADE
    DETECTS = "outward force with |x_b| beyond the soft stroke limit"
    BOUND = "same tick"
    RESET = "none (acts only while |x_b| > soft limit)"

    __slots__ = ("soft_m", "band_m", "acted")

    def __init__(self, config: StrokeConfig) -> None:
        self.soft_m = config.soft_limit_m
        self.band_m = config.fade_band_m
        self.acted = False

    def scale(self, x_b_m: float) -> float:
        """Factor applied to an outward force at sliding displacement ``x_b_m`` (m); 1 inside the soft limit."""
        beyond = abs(x_b_m) - self.soft_m
        if beyond <= 0.0:
            return 1.0
        factor = 1.0 - beyond / self.band_m
        return factor if factor > _ZERO_FACTOR else 0.0

    def apply(self, force_N: float, x_b_m: float) -> float:
        """Return the force after the fade (N)."""
        self.acted = False
        if force_N * x_b_m <= 0.0:  # towards the centre, zero force, or x_b == 0
            return force_N
        factor = self.scale(x_b_m)
        if factor >= 1.0:
            return force_N
        self.acted = True
        return force_N * factor

    def detail(self, demand_N: float, x_b_m: float) -> str:
        """What it faded: the stroke against the soft limit, the demanded force and what is left (built on an event only)."""
        return (
            f"x_b = {x_b_m:.6g} m beyond the soft limit +/-{self.soft_m:g} m (safety.stroke.soft_limit_m): outward "
            f"force {demand_N:.6g} N faded to {demand_N * self.scale(x_b_m):.6g} N"
        )


class StrokeHardLimit:
    """Trip at the hard stroke limit ``hard_limit_m``."""

    NAME = "stroke_hard"
    ACTION = Action.TRIP
    DETECTS = "|x_b| at or beyond the hard stroke limit"
    BOUND = "same tick"
    RESET = "explicit reset, refused while |x_b| >= hard limit"

    __slots__ = ("hard_m", "acted")

    def __init__(self, config: StrokeConfig) -> None:
        self.hard_m = config.hard_limit_m
        self.acted = False

    def check(self, x_b_m: float) -> bool:
        """True (trip) if ``|x_b_m| >= hard_limit_m``."""
        self.acted = abs(x_b_m) >= self.hard_m
        return self.acted

    def detail(self, x_b_m: float) -> str:
        """Why it tripped (built only on a trip)."""
        return f"|x_b| = {abs(x_b_m):.6g} m, expected < {self.hard_m:g} m"


class StrokePredictiveLimit:
    """Trip when the stroke, projected over the stopping time ``stop_time_s``, would pass the hard limit."""

    NAME = "stroke_predictive"
    ACTION = Action.TRIP
    DETECTS = "x_b + xdot_b * stop_time_s at or beyond the hard stroke limit"
    BOUND = "same tick"
    RESET = "explicit reset, refused while the projection is beyond the hard limit"

    __slots__ = ("hard_m", "stop_time_s", "acted")

    def __init__(self, config: StrokeConfig) -> None:
        self.hard_m = config.hard_limit_m
        self.stop_time_s = config.stop_time_s
        self.acted = False

    def projected(self, x_b_m: float, xdot_b_m_s: float) -> float:
        """Projected stroke ``x_b + xdot_b * stop_time_s`` (m)."""
        return x_b_m + xdot_b_m_s * self.stop_time_s

    def check(self, x_b_m: float, xdot_b_m_s: float) -> bool:
        """True (trip) if the projected stroke reaches the hard limit."""
        self.acted = abs(self.projected(x_b_m, xdot_b_m_s)) >= self.hard_m
        return self.acted

    def detail(self, x_b_m: float, xdot_b_m_s: float) -> str:
        """Why it tripped (built only on a trip)."""
        return (
            f"x_b + xdot_b * {self.stop_time_s:g} s = {self.projected(x_b_m, xdot_b_m_s):.6g} m "
            f"(x_b = {x_b_m:.6g} m, xdot_b = {xdot_b_m_s:.6g} m/s), expected inside +/-{self.hard_m:g} m"
        )


class ForceClamp:
    """Clamp the setpoint to ``max_force_N`` and a compensator's addition to ``max_flow_term_N``.

    The setpoint is the force the harness asks for (the controller's); a harness-side compensator
    adds a flow term and a correction to it, the command. The two are bounded apart, as a lab's
    controller bounds its setpoint and its own feed-forward: the command sent is
    ``clamp(setpoint, max_force_N) + clamp(command - setpoint, max_flow_term_N)``
    (docs/SAFETY.md, "What max_force_N must bound"). Without a compensator the command is the
    setpoint and only ``max_force_N`` acts.
    """

    NAME = "force_clamp"
    ACTION = Action.CLAMP
    DETECTS = "|setpoint| above max_force_N, or |command - setpoint| (a compensator's addition) above max_flow_term_N"
    BOUND = "same tick"
    RESET = "none (acts only while the demand exceeds the limit)"

    __slots__ = ("max_N", "max_flow_N", "acted")

    def __init__(self, config: ForceConfig) -> None:
        self.max_N = config.max_force_N
        self.max_flow_N = config.max_flow_term_N
        self.acted = False

    @staticmethod
    def _clip(value: float, bound: float) -> float:
        return bound if value > bound else -bound if value < -bound else value

    def apply(self, force_N: float) -> float:
        """Return the force clamped to ``[-max_force_N, max_force_N]`` (N); the input must be finite."""
        clamped = self._clip(force_N, self.max_N)
        self.acted = clamped != force_N
        return clamped

    def apply_compensated(self, setpoint_N: float, command_N: float) -> float:
        """The command (N) with its setpoint clamped to ``max_force_N`` and its addition to ``max_flow_term_N``.

        Both inputs must be finite.
        """
        setpoint = self._clip(setpoint_N, self.max_N)
        addition_N = command_N - setpoint_N
        addition = self._clip(addition_N, self.max_flow_N)
        self.acted = setpoint != setpoint_N or addition != addition_N
        return setpoint + addition

    def detail(self, demand_N: float, setpoint_N: float | None = None) -> str:
        """What it clamped: the demand (and its setpoint) against the limits (built only on an event, its rising edge)."""
        if setpoint_N is None:
            return f"demanded {demand_N:.6g} N, clamped to +/-{self.max_N:g} N (safety.force.max_force_N)"
        return (
            f"setpoint {setpoint_N:.6g} N within +/-{self.max_N:g} N (safety.force.max_force_N), compensator's "
            f"addition {demand_N - setpoint_N:.6g} N within +/-{self.max_flow_N:g} N (safety.force.max_flow_term_N): "
            f"command {demand_N:.6g} N clamped to {self.apply_compensated(setpoint_N, demand_N):.6g} N"
        )


class ForceRateLimit:
    """Clamp the change of force per tick to ``max_force_rate_N_per_s * dt``, from the last force the
    supervisor commanded (0 whenever the drive is off)."""

    NAME = "force_rate"
    ACTION = Action.CLAMP
    DETECTS = "|d force / dt| above max_force_rate_N_per_s"
    BOUND = "same tick"
    RESET = "none (acts only while the demand changes too fast)"

    __slots__ = ("max_rate_N_per_s", "acted")

    def __init__(self, config: ForceConfig) -> None:
        self.max_rate_N_per_s = config.max_force_rate_N_per_s
        self.acted = False

    def apply(self, force_N: float, previous_N: float, dt: float) -> float:
        """Return ``force_N`` limited to ``previous_N +/- max_rate * dt`` (N)."""
        step = self.max_rate_N_per_s * dt
        if force_N > previous_N + step:
            self.acted = True
            return previous_N + step
        if force_N < previous_N - step:
            self.acted = True
            return previous_N - step
        self.acted = False
        return force_N

    def detail(self, demand_N: float, previous_N: float, dt: float) -> str:
        """What it limited: the demanded rate against the limit (built only on an event, its rising edge)."""
        return (
            f"demanded {(demand_N - previous_N) / dt:.6g} N/s ({previous_N:.6g} N to {demand_N:.6g} N in "
            f"{dt * 1e3:.4g} ms), limited to +/-{self.max_rate_N_per_s:g} N/s (safety.force.max_force_rate_N_per_s)"
        )

