"""Detectors on the four control measurements ``x_0, xdot_0, y_b, ydot_b``.

Channels are indexed 0..3 in that order; channels 0-1 come from the table sensor
frame (fresh when ``health.table_fresh``), 2-3 from the base-mat frame
(``health.base_fresh``). Stuck, jump and disagreement checks count fresh samples
only, so a loop faster than the sensors does not see repeats that are not there.
"""

from __future__ import annotations

import math

from harness.safety.config import SensorConfig
from harness.safety.detector_base import TIME_EPS_S, Detector, LowPass, Persistence
from harness.safety.events import Action
from harness.safety.health import TickHealth

CHANNELS: tuple[str, ...] = ("x_0", "xdot_0", "y_b", "ydot_b")


def read_channels(health: TickHealth, out: list[float]) -> None:
    """Copy the four measurements into the preallocated ``out`` (SI)."""
    meas = health.meas
    out[0] = meas.table_displacement_m
    out[1] = meas.table_velocity_m_s
    out[2] = meas.base_displacement_m
    out[3] = meas.base_velocity_m_s


def _fresh(health: TickHealth, channel: int) -> bool:
    return health.table_fresh if channel < 2 else health.base_fresh


class SensorInvalid(Detector):
    """A measurement beyond its range: ``displacement_range_m`` for ``x_0, y_b``, ``velocity_range_m_s`` for
    ``xdot_0, ydot_b``."""

    NAME = "sensor_invalid"
    ACTION = Action.TRIP
    DETECTS = "NaN, infinite or out-of-range x_0, xdot_0, y_b or ydot_b"
    BOUND = "same tick"
    RESET = "explicit reset, refused while a value is still invalid"

    __slots__ = ("limits", "_now")

    def __init__(self, config: SensorConfig) -> None:
        super().__init__()
        d, v = config.displacement_range_m, config.velocity_range_m_s
        self.limits = (d, v, d, v)
        self._now = [0.0] * 4

    def _bad_channel(self, health: TickHealth) -> int:
        read_channels(health, self._now)
        for k in range(4):
            value = self._now[k]
            if not math.isfinite(value) or abs(value) > self.limits[k]:
                return k
        return -1

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while any measurement is invalid."""
        return self._bad_channel(health) >= 0

    def detail(self, health: TickHealth) -> str:
        """Which channel, its value and its allowed range."""
        k = self._bad_channel(health)
        if k < 0:
            return "all measurements valid"
        return f"{CHANNELS[k]} = {self._now[k]!r}, expected finite and within +/-{self.limits[k]:g}"

    def present(self, health: TickHealth) -> str:
        """Still invalid?"""
        return self.detail(health) if self._bad_channel(health) >= 0 else ""


class SensorStale(Detector):
    """Sensor data too old (``health.table_age_s``, ``health.base_age_s``)."""

    NAME = "sensor_stale"
    ACTION = Action.TRIP
    DETECTS = "table or base-mat sensor frame older than max_sensor_age_s, or its age not finite or negative"
    BOUND = "first tick with age > max_sensor_age_s"
    RESET = "explicit reset, refused while still stale"

    __slots__ = ("max_age_s",)

    def __init__(self, config: SensorConfig) -> None:
        super().__init__()
        self.max_age_s = config.max_sensor_age_s

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True while either age is above the limit."""
        limit = self.max_age_s + TIME_EPS_S  # a NaN or negative age is invalid (a clock mix-up) and trips too
        return not (0.0 <= health.table_age_s <= limit and 0.0 <= health.base_age_s <= limit)

    def detail(self, health: TickHealth) -> str:
        """Both ages and the limit."""
        return (
            f"table sensor frame age {health.table_age_s * 1e3:.3f} ms, base-mat {health.base_age_s * 1e3:.3f} ms, "
            f"expected 0 <= age <= {self.max_age_s * 1e3:.3f} ms (judged after polling the bus)"
        )

    def present(self, health: TickHealth) -> str:
        """Still stale?"""
        return self.detail(health) if self.update(0.0, 0.0, health) else ""


class SensorJump(Detector):
    """Implausible jump between consecutive fresh samples (``jump_limit_m`` for displacements,
    ``jump_limit_m_s`` for velocities); a reset is never refused (not knowable from one sample)."""

    NAME = "sensor_jump"
    ACTION = Action.TRIP
    DETECTS = "change between consecutive samples above jump_limit_m / jump_limit_m_s"
    BOUND = "the sample after the jump (1 sensor period)"
    RESET = "explicit reset; history cleared"

    __slots__ = ("limits", "_prev", "_primed", "_now", "_channel", "_delta")

    def __init__(self, config: SensorConfig) -> None:
        super().__init__()
        d, v = config.jump_limit_m, config.jump_limit_m_s
        self.limits = (d, v, d, v)
        self._prev = [0.0] * 4
        self._primed = [False] * 4
        self._now = [0.0] * 4
        self._channel = -1
        self._delta = 0.0

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True on a sample that jumped."""
        read_channels(health, self._now)
        fired = False
        for k in range(4):
            if not _fresh(health, k):
                continue
            value = self._now[k]
            if self._primed[k] and not fired:
                delta = value - self._prev[k]
                if abs(delta) > self.limits[k]:
                    fired = True
                    self._channel = k
                    self._delta = delta
            self._prev[k] = value
            self._primed[k] = True
        return fired

    def detail(self, health: TickHealth) -> str:
        """Channel, step and limit."""
        k = self._channel
        return f"{CHANNELS[k]} changed by {self._delta:.6g} in one sample, expected at most {self.limits[k]:g}"

    def reset(self) -> None:
        """Forget the previous samples."""
        for k in range(4):
            self._primed[k] = False


class SensorStuck(Detector):
    """A measurement frozen to the bit, whether the table moves or not.

    A healthy transducer is never bit-for-bit constant: its noise through the conditioning
    moves the last bits on every sample (with noise std at least 0.8 of the quantization step,
    50 repeats happen by chance with probability below 1e-9 per hour-long run; docs/SAFETY.md,
    "Stuck sensors"). A frame that is fresh (good counter and CRC) but frozen is a stuck
    conditioner or a sender that re-sends its last values. A noise-free (simulated) sensor is
    indistinguishable from a stuck one, and trips.
    """

    NAME = "sensor_stuck"
    ACTION = Action.TRIP
    DETECTS = "value unchanged to the bit for stuck_samples fresh samples in a row, at rest too"
    BOUND = "stuck_samples repeated samples"
    RESET = "explicit reset; counts cleared"

    __slots__ = ("samples", "_prev", "_primed", "_repeats", "_now", "_channel")

    def __init__(self, config: SensorConfig) -> None:
        super().__init__()
        self.samples = config.stuck_samples
        self._prev = [0.0] * 4
        self._primed = [False] * 4
        self._repeats = [0] * 4
        self._now = [0.0] * 4
        self._channel = -1

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once a channel has repeated ``stuck_samples`` times in a row."""
        read_channels(health, self._now)
        fired = False
        for k in range(4):
            if not _fresh(health, k):
                continue
            value = self._now[k]
            same = self._primed[k] and value == self._prev[k]
            self._repeats[k] = self._repeats[k] + 1 if same else 0
            self._prev[k] = value
            self._primed[k] = True
            if self._repeats[k] >= self.samples and not fired:
                fired = True
                self._channel = k
        return fired

    def detail(self, health: TickHealth) -> str:
        """Channel and count."""
        k = self._channel
        return (
            f"{CHANNELS[k]} = {self._prev[k]!r} repeated to the bit {self._repeats[k]} times in a row, "
            f"expected fewer than {self.samples} (a healthy sensor's noise moves its last bits; a sensor whose "
            "noise is below its quantization step needs a larger safety.sensors.stuck_samples: docs/SAFETY.md)"
        )

    def reset(self) -> None:
        """Forget samples and counts."""
        for k in range(4):
            self._primed[k] = False
            self._repeats[k] = 0


class _PairRates(Detector):
    """What ``sensor_disagree`` and ``sensor_sign_flip`` share: per pair (table ``x_0``/``xdot_0``,
    base mat ``y_b``/``ydot_b``) the finite-difference derivative of the displacement between two
    fresh samples and the mean of the two velocity samples at the same instants (trapezoidal
    rule), both through the same first-order low-pass (``disagree_filter_s``), updated on fresh
    samples, and a persistence timer per pair on a condition of the two. Subclasses give the
    condition (:meth:`_bad`).

    Why the mean and not the newest velocity: the derivative is the mean velocity over the span
    between the two samples, centred half a span back. Compared with the newest velocity it lags
    by half the span, which is half a period on time but half a stall after one: through a
    reversal after a ridden-through stall of 60-80 ms the two had opposite signs for 20 ms and
    more with nothing wrong (docs/SAFETY.md, "Sign flips"). The endpoint mean is centred where
    the derivative is, whatever the span.

    A span of ``persist_s`` or more (a stall, an outage) is a gap: one derivative across it
    would stand for the whole window the condition must persist through, and it averages the
    motion over as long. The pair starts again from the new sample (filters primed with the
    velocity, so the condition clears and its persistence restarts).
    """

    __slots__ = ("_deriv", "_vel", "_timers", "_gap_s", "_prev_x", "_prev_v", "_since_s", "_primed", "_now", "_pair")

    def __init__(self, filter_s: float, persist_s: float) -> None:
        super().__init__()
        self._deriv = (LowPass(filter_s), LowPass(filter_s))
        self._vel = (LowPass(filter_s), LowPass(filter_s))
        self._timers = (Persistence(persist_s), Persistence(persist_s))
        self._gap_s = persist_s
        self._prev_x = [0.0, 0.0]
        self._prev_v = [0.0, 0.0]
        self._since_s = [0.0, 0.0]
        self._primed = [False, False]
        self._now = [0.0] * 4
        self._pair = 0

    def _bad(self, pair: int) -> bool:
        """The condition on the filtered derivative and velocity of ``pair``."""
        raise NotImplementedError

    def _step_pair(self, t: float, dt: float, pair: int, fresh: bool) -> bool:
        self._since_s[pair] += dt
        if fresh:
            x, v = self._now[2 * pair], self._now[2 * pair + 1]
            span = self._since_s[pair]
            if self._primed[pair] and 0.0 < span < self._gap_s:
                self._deriv[pair].update((x - self._prev_x[pair]) / span, span)
                self._vel[pair].update(0.5 * (self._prev_v[pair] + v), span)
            elif not self._primed[pair] or span >= self._gap_s:  # first sample, or after a gap: start again
                self._deriv[pair].reset(v, True)
                self._vel[pair].reset(v, True)
            self._prev_x[pair] = x
            self._prev_v[pair] = v
            self._primed[pair] = True
            self._since_s[pair] = 0.0
        return self._timers[pair].update(t, self._bad(pair))

    def _either_pair(self, t: float, dt: float, health: TickHealth) -> bool:
        """Step both pairs; True (and :attr:`_pair` set) once either condition has persisted."""
        read_channels(health, self._now)
        table = self._step_pair(t, dt, 0, health.table_fresh)
        base = self._step_pair(t, dt, 1, health.base_fresh)
        if table or base:
            self._pair = 0 if table else 1
        return table or base

    def reset(self) -> None:
        """Clear filters and timers."""
        for p in range(2):
            self._primed[p] = False
            self._since_s[p] = 0.0
            self._deriv[p].reset()
            self._vel[p].reset()
            self._timers[p].reset()


class SensorDisagree(_PairRates):
    """Displacement and velocity sensors that disagree, on the table (``x_0``, ``xdot_0``) or the base mat
    (``y_b``, ``ydot_b``); both signals go through the low-pass ``disagree_filter_s``, which adds its own
    lag to the onset."""

    NAME = "sensor_disagree"
    ACTION = Action.TRIP
    DETECTS = "filtered d(displacement)/dt and measured velocity differ by more than disagree_tolerance_m_s"
    BOUND = "disagree_time_s after the filtered difference exceeds the tolerance"
    RESET = "explicit reset; filters cleared"

    __slots__ = ("tolerance_m_s",)

    def __init__(self, config: SensorConfig) -> None:
        super().__init__(config.disagree_filter_s, config.disagree_time_s)
        self.tolerance_m_s = config.disagree_tolerance_m_s

    def _bad(self, pair: int) -> bool:
        return abs(self._deriv[pair].y - self._vel[pair].y) > self.tolerance_m_s

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once either pair has disagreed for ``disagree_time_s``."""
        return self._either_pair(t, dt, health)

    def detail(self, health: TickHealth) -> str:
        """Which pair, both filtered values, tolerance."""
        p = self._pair
        return (
            f"d{CHANNELS[2 * p]}/dt filtered = {self._deriv[p].y:.6g} m/s, {CHANNELS[2 * p + 1]} filtered = "
            f"{self._vel[p].y:.6g} m/s, expected within {self.tolerance_m_s:g} m/s"
        )


class SensorSignFlip(_PairRates):
    """A displacement/velocity pair whose signs disagree: a polarity or wiring fault.

    One signal of the pair (table or base mat) is negated: a swapped wire, a sensor mounted the
    other way, a wrong sign in the conditioning; the controller would push the wrong way. Both
    signals go through the low-pass of ``sensor_disagree`` (``disagree_filter_s``), which adds
    its own lag to the onset.

    Why both this and ``sensor_disagree``: ``sensor_disagree`` bounds the magnitude of
    the difference, which catches scale errors, offsets and drifts of the same sign
    that this check never sees, but it sees a sign flip only once
    ``2 |v| > disagree_tolerance_m_s`` (25 mm/s by default), and then calls it a
    disagreement. This check needs only the signs, above a floor well clear of the
    noise (2 mm/s, eight times the 0.25 mm/s std of the filtered derivative at rest
    with the shipped profile's LVDT noise), so it catches a flip at speeds the other
    never reaches, with the default settings before the other at any speed
    (docs/SAFETY.md, "Sign flips"), and names the polarity. A pair flipped together
    (both signals negated) is self-consistent and is caught by neither; a frozen
    displacement gives a derivative below the floor, and is left to ``sensor_stuck``.
    """

    NAME = "sensor_sign_flip"
    ACTION = Action.TRIP
    DETECTS = "filtered d(displacement)/dt and filtered velocity of opposite signs, both above sign_flip_floor_m_s"
    BOUND = "sign_flip_time_s after both exceed the floor with opposite signs"
    RESET = "explicit reset; filters cleared"

    __slots__ = ("floor_m_s", "time_s", "_held_s")

    def __init__(self, config: SensorConfig) -> None:
        super().__init__(config.disagree_filter_s, config.sign_flip_time_s)
        self.floor_m_s = config.sign_flip_floor_m_s
        self.time_s = config.sign_flip_time_s
        self._held_s = 0.0

    def _bad(self, pair: int) -> bool:
        d, v, floor = self._deriv[pair].y, self._vel[pair].y, self.floor_m_s
        return (d > floor and v < -floor) or (d < -floor and v > floor)

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once either pair has had opposite signs for ``sign_flip_time_s``."""
        if self._either_pair(t, dt, health):
            self._held_s = self._timers[self._pair].held_s(t)
            return True
        return False

    def detail(self, health: TickHealth) -> str:
        """Which pair, both filtered values, floor and time."""
        p = self._pair
        x, v = CHANNELS[2 * p], CHANNELS[2 * p + 1]
        return (
            f"sign flip on {x}/{v}: d{x}/dt filtered = {self._deriv[p].y:.6g} m/s, {v} filtered = "
            f"{self._vel[p].y:.6g} m/s, opposite signs above {self.floor_m_s:g} m/s for "
            f"{self._held_s * 1e3:.1f} ms (limit {self.time_s * 1e3:.1f} ms); "
            "expected the same sign (polarity or wiring fault: the controller would push the wrong way)"
        )


class SensorPolarity(_PairRates):
    """A displacement/velocity pair whose product has a negative mean: a polarity fault held below the sign floor.

    ``sensor_sign_flip`` needs both filtered signals above ``sign_flip_floor_m_s`` (2 mm/s). With a
    harness-side compensation a negated ``ydot_b`` is fed back through the flow term as a damper on
    the base mat's own velocity, which holds the base mat below that floor: the flip stays latent
    (docs/SAFETY.md, "A sign flip held below the floor: sensor_polarity"). This check needs no floor
    per sample: it keeps the running mean (time constant ``polarity_window_s``) of the product of
    the filtered derivative and the filtered velocity of each pair, ``-E[v^2]`` for a flipped pair
    and ``+E[v^2]`` for a sound one, and fires while the mean is below ``-polarity_floor_m_s^2``
    for ``sign_flip_time_s``. The noise of the two sensors is independent, so at rest the mean
    is zero within a small fraction of the floor. A product that is not finite counts as wrong (fail safe).
    """

    NAME = "sensor_polarity"
    ACTION = Action.TRIP
    DETECTS = (
        "running mean over polarity_window_s of filtered d(displacement)/dt times filtered velocity "
        "below -polarity_floor_m_s^2"
    )
    BOUND = "sign_flip_time_s after the running mean falls below -polarity_floor_m_s^2"
    RESET = "explicit reset; filters and running means cleared"

    __slots__ = ("floor_m_s", "threshold_m2_s2", "_mean", "_dt")

    def __init__(self, config: SensorConfig) -> None:
        super().__init__(config.disagree_filter_s, config.sign_flip_time_s)
        self.floor_m_s = config.polarity_floor_m_s
        self.threshold_m2_s2 = -config.polarity_floor_m_s * config.polarity_floor_m_s
        self._mean = (LowPass(config.polarity_window_s), LowPass(config.polarity_window_s))
        for mean in self._mean:
            mean.reset(0.0, True)
        self._dt = 0.0

    def _bad(self, pair: int) -> bool:
        product = self._deriv[pair].y * self._vel[pair].y
        mean = self._mean[pair].update(product, self._dt)
        return not mean >= self.threshold_m2_s2

    def update(self, t: float, dt: float, health: TickHealth) -> bool:
        """True once either pair's running mean product has been below the threshold for ``sign_flip_time_s``."""
        self._dt = dt
        return self._either_pair(t, dt, health)

    def mean_m2_s2(self, pair: int) -> float:
        """The running mean of the product of ``pair`` (0 table, 1 base mat) (m^2/s^2)."""
        return self._mean[pair].y

    def detail(self, health: TickHealth) -> str:
        """Which pair, its running mean product, the threshold."""
        p = self._pair
        x, v = CHANNELS[2 * p], CHANNELS[2 * p + 1]
        return (
            f"polarity of {x}/{v}: running mean of d{x}/dt * {v} (filtered) = {self._mean[p].y:.6g} m^2/s^2, "
            f"expected at least {self.threshold_m2_s2:.6g} m^2/s^2 (-({self.floor_m_s:g} m/s)^2): "
            "the velocity moves against the displacement (a polarity or wiring fault the sign check's floor hides)"
        )

    def reset(self) -> None:
        """Clear filters, timers and running means."""
        super().reset()
        for p in range(2):
            self._mean[p].reset(0.0, True)
