"""Band-limited white-noise table motion: the excitation for identifying the structure.

``white_noise:LOW-HIGH`` (e.g. ``white_noise:0.5-20``) names Gaussian table acceleration with a
flat spectrum from LOW to HIGH Hz and nothing outside, ``white_noise:LOW-HIGH:PGA`` the same at a
peak acceleration of PGA g (``white_noise:0.5-20:0.08``; a trailing ``g`` is accepted). Without
PGA it plays at :data:`~harness.motions.white_noise_name.DEFAULT_PGA_G`: a low amplitude, at which the table stays well inside its
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

import numpy as np

from harness.errors import RecordError
from harness.motions.accel_units import G_M_S2
from harness.motions.loaders import RawRecord
from harness.motions.white_noise_name import WhiteNoiseSpec


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
