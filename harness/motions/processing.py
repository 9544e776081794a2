"""Turn a raw accelerogram into the table's motion: a consistent (x_0, xd_0, xdd_0) triple.

Order of operations (SPEC section 4), in :func:`process_record`:

1. **Time compression** by the factor ``F = time_scale``: every step is divided by
   ``F`` (``dt -> dt/F``); acceleration values are unchanged, so velocity scales as
   ``1/F`` and displacement as ``1/F^2``.
2. **Cut** to ``duration_s`` (in the compressed time). A record shorter than that
   is zero-padded and a note says so. A record longer than that is *not* cut yet: it is
   scaled and baseline-corrected whole (steps 3-4), so the correction does not depend on
   where the cut falls, and only then cut (step 4e). A cut that leaves out more than
   :data:`ARIAS_WARNING_SHARE` of the record's Arias intensity gets a warning
   (:attr:`GroundMotion.warnings`).
3. **Scale** to the target PGA (or keep the record's own PGA when none is given).
4. **Baseline correction** (:mod:`harness.motions.baseline`), so that the table
   starts and ends at rest near zero displacement instead of drifting by tens of
   centimetres:

   a. a cosine taper (``taper_fraction`` of the record at each end) brings the
      acceleration to exactly 0 at both ends;
   b. optionally (``highpass_hz``, off by default) a zero-phase Butterworth
      high-pass (``scipy.signal.butter`` + ``sosfiltfilt``), then the taper again;
   c. the acceleration is integrated from rest (``x_0 = v_0 = 0``) with the
      piecewise-linear rule of :mod:`harness.motions.integration`;
   d. slow half-sine bumps ``sum_j b_j sin(j pi t/T)`` with frequencies up to
      ``baseline_corner_hz`` (default 0.1 Hz in the processed time) are added to
      the acceleration, each integrated with the same rule and added to velocity
      and displacement; the ``b_j`` minimise the mean square displacement subject
      to ``v(T) = x(T) = 0`` exactly. This is the exact-rule form of "subtract a
      low-order fit from the displacement": the bumps vanish at both ends, so the
      acceleration still starts and ends at 0, and the rule is linear, so the sum
      is still an exact triple. The notes report the end offsets removed.
   e. a record cut short keeps its first ``duration_s`` of the corrected motion and
      comes to rest over the last :data:`CUT_STOP_S` of them
      (:func:`harness.motions.baseline.stop_at_rest`: a cosine taper of the
      acceleration and two half-sine bumps that bring velocity and displacement to 0).
      Before the stop the table moves exactly as in the whole record.

5. **Re-scale** all three by one factor so the PGA equals the target exactly
   (one factor for all three keeps them consistent).

The result satisfies ``v_{k+1} = v_k + dt (a_k + a_{k+1})/2`` and
``x_{k+1} = x_k + dt v_k + dt^2 (a_k/3 + a_{k+1}/6)`` to round-off and starts and
ends with ``x = v = a = 0`` (to round-off; ``a`` ends exactly at 0 only when the
taper is on).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2
from harness.motions.baseline import bump_count, fit_rest, highpass, stop_at_rest, taper_window
from harness.motions.checks import MIN_SAMPLES
from harness.motions.integration import interpolate, interpolate_scalar
from harness.motions.loaders import RawRecord, SampledAcceleration

#: Default highest frequency of the drift correction (Hz, in the processed time axis).
DEFAULT_BASELINE_CORNER_HZ = 0.1
#: Default length of each cosine ramp, as a fraction of the processed record.
DEFAULT_TAPER_FRACTION = 0.01
#: Length of the stop at the end of a record cut short (s, processed time; at most half the cut):
#: a cosine taper of the acceleration and two half-sine bumps of 0.5 and 1 Hz that bring the
#: table to rest. On El Centro, Hachinohe and Pacoima (time scale 2, 0.34 g), cut anywhere
#: after 4 s, the stop adds at most 0.2 % to the PGD of the kept motion and 0.1 % to its PGA.
CUT_STOP_S = 1.0
#: How the note of a time scale begins (a white noise, generated for its band, replaces it).
TIME_COMPRESSED = "time compressed by"
#: A cut that leaves out more than this share of the record's Arias intensity is warned about.
ARIAS_WARNING_SHARE = 0.05


@dataclass(frozen=True, eq=False)
class GroundMotion(SampledAcceleration):
    """The table motion for one run: a consistent triple on a uniform time grid (SI).

    Parameters
    ----------
    name : str
        Record name.
    dt_s : float
        Sample step after time compression (s).
    time_scale : float
        Time-compression factor ``F`` that was applied (``dt = dt_raw / F``).
    t_s, accel_m_s2, velocity_m_s, displacement_m : numpy.ndarray
        Time (s), table acceleration ``xdd_0`` (m/s^2), velocity ``xd_0`` (m/s) and
        displacement ``x_0`` (m); read-only.
    notes : tuple of str
        What processing did that a user should know (padding, end offsets removed...).
    highpass_hz : float or None
        Corner of the zero-phase high-pass used (Hz), or None if none was used.
    baseline_corner_hz : float or None
        Highest frequency of the drift correction (Hz).
    taper_s : float
        Length of each cosine ramp (s).
    source : str
        Where the raw record came from.
    arias_left_out : float
        Share of the record's Arias intensity (of its acceleration after time compression)
        that the cut to ``duration_s`` left out, from 0 to 1; 0 when nothing was cut.
    """

    name: str
    dt_s: float
    time_scale: float
    t_s: np.ndarray
    accel_m_s2: np.ndarray
    velocity_m_s: np.ndarray
    displacement_m: np.ndarray
    notes: tuple[str, ...] = ()
    highpass_hz: float | None = None
    baseline_corner_hz: float | None = None
    taper_s: float = 0.0
    source: str = ""
    arias_left_out: float = 0.0

    def __post_init__(self) -> None:
        for field in ("t_s", "accel_m_s2", "velocity_m_s", "displacement_m"):
            array = np.array(getattr(self, field), dtype=float)
            if array.shape != (np.size(self.t_s),):
                expected = f"({np.size(self.t_s)},)"
                raise RecordError(f"ground motion {self.name!r}: {field} has shape {array.shape}, expected {expected}")
            array.flags.writeable = False
            object.__setattr__(self, field, array)


    @property
    def warnings(self) -> tuple[str, ...]:
        """What a user must know before running the motion: a cut that leaves out much of the record's shaking."""
        if self.arias_left_out <= ARIAS_WARNING_SHARE:
            return ()
        return (f"the cut to {self.duration_s:g} s leaves out {100 * self.arias_left_out:.0f} % of the record's Arias "
                f"intensity (more than {100 * ARIAS_WARNING_SHARE:g} %): the run misses that part of the shaking",)

    @property
    def pgv_m_s(self) -> float:
        """Peak |table velocity| (m/s)."""
        return float(np.max(np.abs(self.velocity_m_s)))

    @property
    def pgd_m(self) -> float:
        """Peak |table displacement| (m), the stroke the table needs."""
        return float(np.max(np.abs(self.displacement_m)))

    def state_at(self, t_s: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Table ``(x_0, xd_0, xdd_0)`` at time(s) ``t_s`` by the piecewise-linear rule.

        Before 0 and after the end the first and last samples are held. Scalars in,
        0-d arrays out; arrays in, arrays out.
        """
        return interpolate(t_s, self.dt_s, self.accel_m_s2, self.velocity_m_s, self.displacement_m)

    def sample(self, t_s: float) -> tuple[float, float, float]:
        """Scalar :meth:`state_at` for a loop tick: ``(x_0 in m, xd_0 in m/s, xdd_0 in m/s^2)`` as floats."""
        return interpolate_scalar(t_s, self.dt_s, self.accel_m_s2, self.velocity_m_s, self.displacement_m)


def process_record(
    raw: RawRecord,
    *,
    pga_g: float | None = None,
    time_scale: float = 1.0,
    duration_s: float | None = None,
    baseline_corner_hz: float = DEFAULT_BASELINE_CORNER_HZ,
    taper_fraction: float = DEFAULT_TAPER_FRACTION,
    highpass_hz: float | None = None,
    highpass_order: int = 2,
    name: str | None = None,
) -> GroundMotion:
    """Compress, cut, scale and baseline-correct a record into a consistent triple.

    Parameters
    ----------
    raw : RawRecord
        The accelerogram.
    pga_g : float, optional
        Target peak ground acceleration (g); default: keep the (cut) record's PGA.
    time_scale : float
        Time-compression factor ``F > 0``; every step becomes ``dt / F``.
    duration_s : float, optional
        Length of the result in compressed time (s); default: the whole record.
    baseline_corner_hz : float
        Highest frequency of the drift correction (Hz, compressed time), > 0.
    taper_fraction : float
        Length of each cosine ramp as a fraction of the record (0 <= . < 0.5).
    highpass_hz : float or None
        Corner of an extra zero-phase Butterworth high-pass (Hz, compressed time);
        None (default): off.
    highpass_order : int
        Order of that filter (applied forward and backward).
    name : str, optional
        Name of the result; default the raw record's.

    Returns
    -------
    GroundMotion
    """
    options = (highpass_hz, highpass_order, taper_fraction, baseline_corner_hz)
    _check_options(raw, pga_g, time_scale, duration_s, options)
    notes: list[str] = []
    dt = raw.dt_s / time_scale
    if time_scale != 1.0:
        notes.append(f"{TIME_COMPRESSED} {time_scale:g}: step {raw.dt_s:g} s -> {dt:g} s")
    record = np.array(raw.accel_m_s2, dtype=float)
    accel, n_content = _cut(record, dt, duration_s, notes)
    peak = float(np.max(np.abs(accel)))
    if peak == 0.0:
        raise RecordError(f"record {raw.name!r} holds only zeros in the selected {(accel.size - 1) * dt:g} s")
    target = pga_g * G_M_S2 if pga_g is not None else peak
    if pga_g is None:
        notes.append(f"PGA kept at the record's {peak / G_M_S2:.4g} g")
    kept = accel.size
    cut = kept < record.size
    if cut:  # correct the whole record, cut afterwards: the correction does not depend on where the cut falls
        accel, n_content = record, record.size
    accel = accel * (target / peak)
    accel, velocity, displacement, taper_s = _baseline(accel, n_content, dt, options, notes)
    arias_left_out = 0.0
    if cut:
        accel, velocity, displacement = _stop(accel[:kept], dt, notes)
        arias_left_out = _arias_left_out(record, kept, dt)
    remaining = float(np.max(np.abs(accel)))
    if remaining == 0.0:
        raise RecordError(f"record {raw.name!r}: no motion is left after the {taper_s:g} s tapers; lower taper_fraction")
    factor = target / remaining
    return GroundMotion(
        name=name or raw.name,
        dt_s=dt,
        time_scale=time_scale,
        t_s=np.arange(accel.size) * dt,
        accel_m_s2=accel * factor,
        velocity_m_s=velocity * factor,
        displacement_m=displacement * factor,
        notes=tuple(notes),
        highpass_hz=highpass_hz,
        baseline_corner_hz=baseline_corner_hz,
        taper_s=taper_s,
        source=raw.source,
        arias_left_out=arias_left_out,
    )


def _check_options(
    raw: RawRecord,
    pga_g: float | None,
    time_scale: float,
    duration_s: float | None,
    options: tuple[float | None, int, float, float],
) -> None:
    highpass_hz, highpass_order, taper_fraction, corner_hz = options
    if pga_g is not None and not (np.isfinite(pga_g) and pga_g > 0):
        raise RecordError(f"expected pga_g > 0 g, found {pga_g!r}")
    if not (np.isfinite(time_scale) and time_scale > 0):
        raise RecordError(f"expected time_scale > 0, found {time_scale!r}")
    dt = raw.dt_s / time_scale
    if duration_s is not None and not (np.isfinite(duration_s) and duration_s >= MIN_SAMPLES * dt):
        raise RecordError(
            f"expected duration_s >= {MIN_SAMPLES * dt:g} s ({MIN_SAMPLES} steps of {dt:g} s), found {duration_s!r}"
        )
    if highpass_hz is not None and not (np.isfinite(highpass_hz) and 0 < highpass_hz < 0.25 / dt):
        raise RecordError(
            f"expected 0 < highpass_hz < {0.25 / dt:g} Hz (half the Nyquist frequency), found {highpass_hz!r}"
        )
    if not 1 <= highpass_order <= 8:
        raise RecordError(f"expected highpass_order from 1 to 8, found {highpass_order!r}")
    if not 0.0 <= taper_fraction < 0.5:
        raise RecordError(f"expected 0 <= taper_fraction < 0.5, found {taper_fraction!r}")
    if not (np.isfinite(corner_hz) and corner_hz > 0):
        raise RecordError(f"expected baseline_corner_hz > 0 Hz, found {corner_hz!r}")


def _cut(accel: np.ndarray, dt: float, duration_s: float | None, notes: list[str]) -> tuple[np.ndarray, int]:
    """Cut or zero-pad to ``duration_s``; return the samples and how many hold the record."""
    if duration_s is None:
        return accel, accel.size
    n = int(np.floor(duration_s / dt + 1e-9)) + 1
    if abs((n - 1) * dt - duration_s) > 1e-9 * max(duration_s, 1.0):
        notes.append(f"duration {duration_s:g} s rounded down to {(n - 1) * dt:g} s (whole steps of {dt:g} s)")
    if n <= accel.size:
        return accel[:n].copy(), n
    notes.append(f"record is {(accel.size - 1) * dt:g} s long after compression; zero-padded to {(n - 1) * dt:g} s")
    return np.concatenate([accel, np.zeros(n - accel.size)]), accel.size


def _stop(accel: np.ndarray, dt: float, notes: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bring the kept part of a corrected record to rest over its last :data:`CUT_STOP_S` (at most half of it)."""
    n_stop = max(3, min(int(round(CUT_STOP_S / dt)) + 1, (accel.size + 1) // 2))
    notes.append(f"cut after the baseline correction of the whole record; brought to rest over the last "
                 f"{(n_stop - 1) * dt:g} s (cosine taper and two half-sine corrections)")
    return stop_at_rest(accel, dt, n_stop)


def _arias_left_out(record: np.ndarray, kept: int, dt: float) -> float:
    """Share of the Arias intensity of ``record`` (after compression, before any taper) after its first ``kept`` samples."""
    squared = record**2
    intensity = np.concatenate([[0.0], np.cumsum(0.5 * dt * (squared[:-1] + squared[1:]))])
    return float(1.0 - intensity[kept - 1] / intensity[-1]) if intensity[-1] > 0.0 else 0.0


def _baseline(
    accel: np.ndarray,
    n_content: int,
    dt: float,
    options: tuple[float | None, int, float, float],
    notes: list[str],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """Taper, optional high-pass, integrate and fit to rest; return the triple and the ramp (s)."""
    highpass_hz, order, taper_fraction, corner_hz = options
    ramp = min(int(round(taper_fraction * (n_content - 1))), (n_content - 1) // 2)
    window = taper_window(n_content, accel.size, ramp)
    accel = accel * window
    if ramp == 0 and accel[0] != 0.0:
        notes.append(f"no taper: the acceleration starts at {accel[0]:.4g} m/s^2, a step for the table")
    if highpass_hz is not None:
        accel = highpass(accel, dt, highpass_hz, order) * window
        notes.append(f"zero-phase Butterworth high-pass, order {order} (forward-backward), corner {highpass_hz:g} Hz")
    accel, velocity, displacement, (end_x, end_v) = fit_rest(accel, dt, corner_hz)
    count = bump_count((accel.size - 1) * dt, corner_hz)
    notes.append(
        f"baseline: {count} half-sine corrections up to {corner_hz:g} Hz removed end offsets of "
        f"{end_x * 1e3:.3g} mm and {end_v * 1e3:.3g} mm/s"
    )
    return accel, velocity, displacement, ramp * dt
