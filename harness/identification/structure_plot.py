"""The structure identification's plot: each floor's response to the base mat's acceleration, measured against fitted.

Three panels share a logarithmic frequency axis over the band: the magnitude of
``a_j / a_b`` (log scale), its phase (deg), and the measured coherence. Per floor one colour:
measured (H1, solid), the story model with the profile's masses (dashed) and the modal fit
(dotted). Where the story model leaves the modal fit, the masses or the shear-building form
do not fit the rig.

The measured curve is a Welch average of Hann-windowed segments, one value every ``df`` Hz; a
peak narrower than the window's main lobe (about ``2 df``) shows lower and wider than it is. The
lightly damped first mode's half-power width ``2 zeta f`` (0.046 Hz at 1 % and 2.3 Hz) is half a
0.1 Hz bin, so its measured peak reads several times below the fitted one (about 7 against 25 on
the shipped rig): that is the window, not the fit, which is made in the time domain. The plot
says so on its face (:func:`smearing_note`).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from harness.identification.structure_records import MeasuredResponse
from harness.report.figure import figure, style

COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")
HEIGHT_PX = 900


def smearing_note(measured: MeasuredResponse) -> str:
    """The line the plot carries on the measured curve's resolution."""
    step_hz = float(measured.freq_hz[1] - measured.freq_hz[0])
    return (f"measured: H1, Hann-windowed Welch segments, one bin every {step_hz:.3g} Hz: a peak narrower than "
            f"~{2 * step_hz:.2g} Hz "
            "(a lightly damped mode) shows lower and wider than it is; the fits are in the time domain")


def response_plot(measured: MeasuredResponse, story_model: np.ndarray, modal_model: np.ndarray, band_hz: tuple[float, float],
                  path: Path, title: str) -> Path:
    """Write the plot to ``path`` (PNG); ``story_model`` and ``modal_model`` are (n, F) at ``measured.freq_hz``."""
    inside = (measured.freq_hz >= band_hz[0]) & (measured.freq_hz <= band_hz[1])
    freq = measured.freq_hz[inside]
    with matplotlib.rc_context(style()):
        fig = figure(HEIGHT_PX)
        magnitude, phase, coherence = fig.subplots(3, 1, sharex=True, height_ratios=(3, 2, 1))
        for j in range(measured.response.shape[0]):
            colour = COLOURS[j % len(COLOURS)]
            for values, line, label in ((measured.response, "-", "measured"), (story_model, "--", "story model"),
                                        (modal_model, ":", "modal fit")):
                shown = values[j, inside]
                magnitude.loglog(freq, np.abs(shown), line, color=colour, linewidth=1.0, label=f"floor {j + 1}, {label}")
                phase.semilogx(freq, np.degrees(np.unwrap(np.angle(shown))), line, color=colour, linewidth=1.0)
            coherence.semilogx(freq, measured.coherence[j, inside], "-", color=colour, linewidth=1.0)
        magnitude.set_ylabel("|a_j / a_b|")
        phase.set_ylabel("phase (deg)")
        coherence.set_ylabel("coherence")
        coherence.set_ylim(0.0, 1.05)
        coherence.set_xlabel("frequency (Hz)")
        coherence.set_xlim(freq[0], freq[-1])
        coherence.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        coherence.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
        coherence.xaxis.set_minor_formatter(NullFormatter())
        magnitude.legend(loc="lower left", ncol=3, fontsize=8)
        magnitude.set_title(title)
        magnitude.text(0.99, 0.98, smearing_note(measured), transform=magnitude.transAxes, ha="right", va="top", fontsize=7,
                       wrap=True)
        fig.savefig(path, format="png")
    return path
