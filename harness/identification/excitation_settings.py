"""What an identification run plays: the signal's kind, amplitude, band, duration, seed and resolution.

The settings of :mod:`harness.identification.excitation` on their own, with no numpy: the command
line's parser takes its defaults and choices from here (``harness --help`` imports nothing heavy,
tests/unit/test_startup_imports.py).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Literal

from harness.errors import HarnessError

SignalKind = Literal["chirp", "random"]
SIGNALS: tuple[SignalKind, ...] = ("chirp", "random")


class ExcitationError(HarnessError, ValueError):
    """An excitation the run refuses before anything moves; ``option`` names the command-line option to change.

    Parameters
    ----------
    option : str
        The option, e.g. ``--amplitude-N``.
    message : str
        What was found and what was expected.
    """

    def __init__(self, option: str, message: str):
        self.option = option
        super().__init__(f"{option}: {message}")


@dataclass(frozen=True)
class Excitation:
    """What to play: the options of ``harness identify actuator``.

    Attributes
    ----------
    signal : {"chirp", "random"}
    amplitude_N : float
        Peak force (N).
    band_hz : tuple of float
        Lowest and highest frequency (Hz).
    duration_s : float
        Length of the signal (s), tapers included.
    seed : int
        Seed of the random signal (the chirp has no randomness).
    resolution_hz : float
        Frequency resolution of the estimate (Hz): the Welch segment is the power of two of
        samples at least ``rate / resolution_hz`` long.
    """

    signal: SignalKind = "chirp"
    amplitude_N: float = 2000.0
    band_hz: tuple[float, float] = (1.0, 30.0)
    duration_s: float = 40.0
    seed: int = 0
    resolution_hz: float = 0.25

    @property
    def low_hz(self) -> float:
        return self.band_hz[0]

    @property
    def high_hz(self) -> float:
        return self.band_hz[1]

    @property
    def taper_s(self) -> tuple[float, float]:
        """Lengths of the raised-cosine tapers at the start and at the end (s), each at most a tenth of the duration.

        One period of the lowest frequency at both ends of a random signal (every frequency plays
        all the time) and at the start of a chirp; a chirp ends at the highest frequency, so five
        periods of it end it without fading the top of the band away.
        """
        start_s = min(1.0 / self.low_hz, 0.1 * self.duration_s)
        end_s = min(5.0 / self.high_hz if self.signal == "chirp" else 1.0 / self.low_hz, 0.1 * self.duration_s)
        return start_s, end_s

    @property
    def bound_rate_N_per_s(self) -> float:
        """Upper bound of the signal's force rate, ``2 pi f_high A`` (N/s)."""
        return 2.0 * math.pi * self.high_hz * self.amplitude_N

    def segment_samples(self, rate_hz: float) -> int:
        """Samples per Welch segment at ``rate_hz``: the power of two at least ``rate_hz / resolution_hz``."""
        return int(2 ** math.ceil(math.log2(rate_hz / self.resolution_hz)))

    def as_dict(self) -> dict:
        """Plain data for ``excitation.json`` (SI, the band as a list)."""
        data = asdict(self)
        data["band_hz"] = list(self.band_hz)
        data["taper_s"] = list(self.taper_s)
        return data
