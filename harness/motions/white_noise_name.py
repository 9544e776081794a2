"""The grammar of a ``white_noise:LOW-HIGH[:PGA]`` record name and what it asks for (settings only).

:mod:`harness.motions.white_noise` generates the motion; the profile's ``record`` section
(:mod:`harness.motions.config`) checks a name with :func:`white_noise_spec` when it is loaded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from harness.config.input_limits import MAX_PGA_G
from harness.errors import RecordError

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
