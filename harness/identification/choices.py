"""The identification commands' choices and fixed settings, in a module that imports nothing heavy.

The command line's parser shows these in ``--help`` and checks options against them; keeping them
here, not beside the fits that use them, lets ``harness --help`` start without importing scipy or
numba (the fits import them from here).
"""

from __future__ import annotations

from typing import Literal

#: Fewest frequencies of an estimate within the band an identification accepts: a fit of a model's parameters,
#: and a Bode plot, need a response over a band, not a point (the SPEC 7a fit frees up to five parameters, the
#: structure's up to two per story; ten bins, each a complex value, leave every one of them overdetermined).
MIN_BAND_BINS = 10

#: How the structure's damping is fitted: a ratio per story, or proportional to the stiffness.
DampingModel = Literal["per_story", "proportional"]
DAMPING_MODELS: tuple[DampingModel, ...] = ("per_story", "proportional")

#: Corner of the low-pass the bearing's fit applies to the measured and the fitted force alike (Hz).
LOWPASS_HZ = 30.0
