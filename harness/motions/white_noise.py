"""Band-limited white-noise table motion: the excitation for identifying the structure.

``white_noise:LOW-HIGH`` (e.g. ``white_noise:0.5-20``) names Gaussian table acceleration with a
flat spectrum from LOW to HIGH Hz and nothing outside, ``white_noise:LOW-HIGH:PGA`` the same at a
peak acceleration of PGA g (``white_noise:0.5-20:0.08``; a trailing ``g`` is accepted). Without
PGA it plays at :data:`DEFAULT_PGA_G`: a low amplitude, at which the table stays well inside its
stroke and the bearings barely slide, while every mode in the band is excited at once.

Where a record is named like ``synthetic:SEED``, this is named the same way, and it is generated
like the synthetic record: from ``numpy.random.default_rng(seed)`` with the profile's
``record.seed``, so the same seed gives the same motion.

What differs from an accelerogram, and why:

- the band is the band the table plays: under a time scale ``F`` (``record.time_scale``) the
  noise is generated over ``LOW/F .. HIGH/F`` in the raw time axis, so that compression puts it
  back where the name says;
- the amplitude is the one in the name: ``record.pga_g`` (and ``--pga``, which sets it) is meant
  for earthquake records and is not applied; the motion's notes say so when it differs.

The signal starts and ends at zero through raised-cosine tapers one period of LOW long (at
most a tenth of the record), then goes through :func:`harness.motions.process_record` like any
record (baseline correction, exact triple, PGA).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from harness.config.input_limits import MAX_PGA_G
from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2
from harness.motions.loaders import RawRecord

#: The name's prefix.
WHITE_NOISE = "white_noise"
#: Peak table acceleration when the name gives none (g): low (a table stroke of about 8 mm for 0.5-20 Hz),
#: yet enough that the base mat's acceleration stands well above its sensor's noise at the first mode, where
#: the structure's reaction makes it smallest (at 0.05 g the first mode's damping came out 50 % high on the rig).
DEFAULT_PGA_G = 0.1
#: Highest frequency a name may ask for (Hz): a shaking table's servo plays little above it.
MAX_BAND_HZ = 50.0
#: Samples per period of the highest frequency, at most (the record's step follows from it).
SAMPLES_PER_PERIOD = 10
#: Longest record step in the table's time (s).
MAX_STEP_S = 0.005

_FORMAT = "white_noise:LOW-HIGH or white_noise:LOW-HIGH:PGA (Hz, Hz, g), e.g. white_noise:0.5-20"


@dataclass(frozen=True)
class WhiteNoiseSpec:
    """What a ``white_noise:...`` name asks for.

    Attributes
    ----------
    low_hz, high_hz : float
        The band the table plays (Hz), ``0 < low_hz < high_hz <= MAX_BAND_HZ``.
    pga_g : float
        Peak table acceleration (g).
    """

    low_hz: float
    high_hz: float
    pga_g: float = DEFAULT_PGA_G

    @property
    def name(self) -> str:
        """The name that gives this spec back, with the amplitude spelled out."""
        return f"{WHITE_NOISE}:{self.low_hz:g}-{self.high_hz:g}:{self.pga_g:g}"

    @property
    def step_s(self) -> float:
        """Record step as played (s): :data:`SAMPLES_PER_PERIOD` per period of ``high_hz``, at most :data:`MAX_STEP_S`."""
        return min(MAX_STEP_S, 1.0 / (SAMPLES_PER_PERIOD * self.high_hz))


def _number(text: str, what: str, name: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise RecordError(f"record {name!r}: found {text!r} for {what}, expected a number; {_FORMAT}") from None
    if not math.isfinite(value):
        raise RecordError(f"record {name!r}: found {text!r} for {what}, expected a finite number; {_FORMAT}")
    return value


def white_noise_spec(name: str) -> WhiteNoiseSpec | None:
    """The spec a ``white_noise:...`` name gives; None for any other name.

    Raises
    ------
    RecordError
        For a ``white_noise`` name that does not follow the format, or a band or amplitude out of range.
    """
    text = name.strip()
    if text != WHITE_NOISE and not text.startswith(WHITE_NOISE + ":"):
        return None
    parts = text.split(":")
    if len(parts) not in (2, 3) or not parts[1]:
        raise RecordError(f"record {name!r}: expected {_FORMAT}")
    band = parts[1].split("-")
    if len(band) != 2:
        raise RecordError(f"record {name!r}: found the band {parts[1]!r}, expected LOW-HIGH in Hz; {_FORMAT}")
    low = _number(band[0], "LOW", name)
    high = _number(band[1], "HIGH", name)
    if not 0.0 < low < high <= MAX_BAND_HZ:
        raise RecordError(f"record {name!r}: found the band {low:g}-{high:g} Hz, expected 0 < LOW < HIGH <= {MAX_BAND_HZ:g} Hz")
    pga = DEFAULT_PGA_G
    if len(parts) == 3:
        amplitude = parts[2].strip()
        pga = _number(amplitude[:-1] if amplitude.endswith("g") else amplitude, "PGA", name)
        if not 0.0 < pga <= MAX_PGA_G:
            raise RecordError(f"record {name!r}: found a PGA of {pga:g} g, expected a number of g in (0, {MAX_PGA_G:g}]")
    return WhiteNoiseSpec(low, high, pga)


def white_noise_record(spec: WhiteNoiseSpec, *, seed: int, duration_s: float, time_scale: float = 1.0) -> RawRecord:
    """Generate the raw record of ``spec``: after a time scale of ``time_scale`` it plays ``spec``'s band.

    Parameters
    ----------
    spec : WhiteNoiseSpec
    seed : int
        Seed of ``numpy.random.default_rng``.
    duration_s : float
        Length as played, after the time scale (s).
    time_scale : float
        The time compression the record will get (``record.time_scale``).

    Returns
    -------
    RawRecord
        Named ``spec.name``, peak ``spec.pga_g``, zero at both ends.
    """
    dt_s = spec.step_s * time_scale
    n = int(round(duration_s * time_scale / dt_s)) + 1
    rng = np.random.default_rng(seed)
    spectrum = np.fft.rfft(rng.standard_normal(n))
    freq_hz = np.fft.rfftfreq(n, dt_s)
    spectrum[(freq_hz < spec.low_hz / time_scale) | (freq_hz > spec.high_hz / time_scale)] = 0.0
    noise = np.fft.irfft(spectrum, n)
    ramp_n = max(2, min(int(round(time_scale / spec.low_hz / dt_s)), n // 10))
    window = np.ones(n)
    ramp = 0.5 - 0.5 * np.cos(np.pi * np.arange(ramp_n) / (ramp_n - 1))
    window[:ramp_n] = ramp
    window[n - ramp_n:] *= ramp[::-1]
    accel = noise * window
    peak = float(np.max(np.abs(accel)))
    if peak == 0.0:
        raise RecordError(f"record {spec.name!r}: {duration_s:g} s is too short to hold any of the band {spec.low_hz:g}-"
                          f"{spec.high_hz:g} Hz; expected a longer run")
    accel *= spec.pga_g * G_M_S2 / peak
    source = (f"band-limited Gaussian white noise, {spec.low_hz:g}-{spec.high_hz:g} Hz as played, seed {seed}, "
              f"peak {spec.pga_g:g} g")
    return RawRecord(name=spec.name, dt_s=dt_s, accel_m_s2=accel, source=source)
