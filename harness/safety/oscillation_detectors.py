"""A sustained oscillation of the actuator force above the controller's band: a limit cycle."""

from __future__ import annotations

import math

from harness.safety.config import ForceConfig
from harness.safety.detector_base import Detector, HighPass, LowPass
from harness.safety.events import ACTION_BY_NAME, Action
from harness.safety.health import TickHealth

#: The two forces watched, by index: the command the supervisor sent, the actuator's load cell.
FORCES: tuple[str, ...] = ("commanded", "measured")


class ForceOscillation(Detector):
    """The commanded or the measured force oscillates above the controller's band, for longer than a transient.

    Each force goes through a second-order Butterworth high-pass at ``oscillation_corner_hz``
    (above the structure's modes, the time-compressed record's content and the force loop's own
    bandwidth), then a running mean square with time constant ``oscillation_window_s``; the check
    fires while the RMS of either exceeds ``oscillation_limit_N``, the force amplitude at which
    every cycle fatigues the load path (docs/SAFETY.md, "Sustained oscillation", derives all
    three). The commanded force is the one the supervisor sent on the previous tick (it writes it
    to :attr:`command_N`, as for ``force_tracking``). The window is the persistence: a sinusoid
    whose RMS is ``r`` times the limit fires ``oscillation_window_s * ln(r^2 / (r^2 - 1))`` after it
    begins, and a transient of energy ``E`` (N^2 s) above the corner raises the mean square by at
    most ``E / oscillation_window_s``. A load cell that is not finite fires too (fail safe). The
    action is ``oscillation_action`` (a safe stop by default); a reset is never refused (an
    oscillation is not knowable from one sample).
    """

    NAME = "force_oscillation"
    ACTION = Action.SAFE_STOP
    DETECTS = (
        "RMS over oscillation_window_s of the commanded force (each tick) or the measured force (each load-cell "
        "sample) above oscillation_corner_hz (2nd-order high-pass) above oscillation_limit_N"
    )
    BOUND = "first tick the running RMS exceeds oscillation_limit_N"
    RESET = "explicit reset; filters and running mean squares cleared"

    __slots__ = (
        "limit_N", "window_s", "command_N", "_high", "_mean_square", "rms_N", "peak_rms_N", "_force", "_load_cell_dt_s",
    )
    #: Loop time since the load cell's last sample entered the filter (s); set by :meth:`reset`.
    _load_cell_dt_s: float

    def __init__(self, config: ForceConfig) -> None:
        super().__init__(ACTION_BY_NAME[config.oscillation_action])
        self.limit_N = config.oscillation_limit_N
        self.window_s = config.oscillation_window_s
        self.command_N = 0.0
        self._high = (HighPass(config.oscillation_corner_hz), HighPass(config.oscillation_corner_hz))
        self._mean_square = (LowPass(self.window_s), LowPass(self.window_s))
        #: The running RMS of each force of :data:`FORCES` (N), after the latest update.
        self.rms_N = [0.0, 0.0]
        #: The largest running RMS of either force since the last reset (N): the figure docs/SAFETY.md reports.
        self.peak_rms_N = 0.0
        self._force = 0
        self.reset()

    def _over(self, index: int, force_N: float, dt: float) -> bool:
        """Step force ``index``; True while its running RMS is above the limit (or not finite)."""
        high = self._high[index].update(force_N, dt)
        rms = math.sqrt(self._mean_square[index].update(high * high, dt))
        self.rms_N[index] = rms
        if rms > self.peak_rms_N:
            self.peak_rms_N = rms
        return not rms <= self.limit_N

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while either force's running RMS above the corner exceeds the limit.

        The command changes every tick; the load cell only with each actuator status frame
        (``health.actuator_status_fresh``, at ``can.status_rate_hz``). Its filters step once per
        sample, over the time since the previous one: filtered every tick, a 250 Hz sample held
        through a 2 kHz loop is a staircase whose steps are content far above the corner that
        the force never had (docs/SAFETY.md, "Sustained oscillation"). A load cell that is not
        finite is judged at once.
        """
        commanded = self._over(0, self.command_N, dt)
        self._load_cell_dt_s += dt
        if health.actuator_status_fresh or not math.isfinite(health.measured_force_N):
            measured = self._over(1, health.measured_force_N, self._load_cell_dt_s)
            self._load_cell_dt_s = 0.0
        else:
            measured = not self.rms_N[1] <= self.limit_N
        if commanded or measured:
            self._force = 0 if commanded else 1
        return commanded or measured

    def detail(self, health: TickHealth) -> str:
        """Which force, its RMS above the corner, the limit, and what it means."""
        k = self._force
        return (
            f"{FORCES[k]} force RMS above {self._high[k].corner_hz:g} Hz over a {self.window_s:g} s window "
            f"{self.rms_N[k]:.6g} N (commanded {self.rms_N[0]:.6g} N, measured {self.rms_N[1]:.6g} N), expected at most "
            f"{self.limit_N:g} N: a sustained oscillation above the controller's band (a limit cycle of the force loop)"
        )

    def reset(self) -> None:
        """Clear the filters (next input at rest), the mean squares (to zero), the RMS and its peak."""
        self.command_N = 0.0
        for k in range(2):
            self._high[k].reset()
            self._mean_square[k].reset(0.0, True)
            self.rms_N[k] = 0.0
        self.peak_rms_N = 0.0
        self._load_cell_dt_s = 0.0
