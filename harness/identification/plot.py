"""The Bode plot of frequency responses, as a lab's FRF tool draws it.

Three panels share a logarithmic frequency axis: magnitude (dB), phase (deg, unwrapped)
and coherence (0..1). Every response given is overlaid and labelled (e.g. the free and
the blocked actuator).
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from harness.identification.frf import FrequencyResponse
from harness.report.figure import figure, style

#: One colour and line style per condition, in the order given (dashed lines keep a curve that lies on another visible).
COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd")
LINE_STYLES = ("-", "--", "-.", ":")
HEIGHT_PX = 900


def bode_plot(responses: Mapping[str, FrequencyResponse], path: Path, title: str) -> Path:
    """Write the Bode plot of ``responses`` (label -> response) to ``path`` (PNG); returns ``path``.

    Parameters
    ----------
    responses : mapping of str to FrequencyResponse
        Drawn in order, each in its own colour with its label in the legend; at least one, not empty.
    path : Path
        The PNG file to write.
    title : str
        The figure's title.
    """
    with matplotlib.rc_context(style()):
        fig = figure(HEIGHT_PX)
        magnitude, phase, coherence = fig.subplots(3, 1, sharex=True, height_ratios=(3, 3, 2))
        for index, (label, response) in enumerate(responses.items()):
            line = {"color": COLOURS[index % len(COLOURS)], "linestyle": LINE_STYLES[index % len(LINE_STYLES)], "label": label}
            magnitude.semilogx(response.freq_hz, response.magnitude_db, **line)
            phase.semilogx(response.freq_hz, response.phase_deg, **line)
            coherence.semilogx(response.freq_hz, response.coherence, **line)
        magnitude.set_ylabel("magnitude (dB, N/N)")
        phase.set_ylabel("phase (deg)")
        coherence.set_ylabel("coherence")
        coherence.set_ylim(0.0, 1.05)
        coherence.set_xlabel("frequency (Hz)")
        low = min(float(r.freq_hz[0]) for r in responses.values() if len(r.freq_hz))
        high = max(float(r.freq_hz[-1]) for r in responses.values() if len(r.freq_hz))
        coherence.set_xlim(low, high)
        coherence.xaxis.set_major_locator(LogLocator(base=10.0, subs=(1.0, 2.0, 5.0)))
        coherence.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
        coherence.xaxis.set_minor_formatter(NullFormatter())
        for ax in (magnitude, phase, coherence):
            ax.grid(True, which="both", alpha=0.3)
        magnitude.legend(loc="lower left")
        magnitude.set_title(title)
        fig.savefig(path, format="png")
    return path
