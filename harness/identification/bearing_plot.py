"""The bearing identification's plot: friction against sliding velocity, and the hysteresis loop, measured against fitted.

Left: the friction force (low-passed, as fitted) against the sliding velocity, every sample
of every run, measured in grey and fitted in colour, with the fitted law's envelope
``+/- mu(xdot_b) mbar g`` (the force while sliding) drawn over them. Right: the hysteresis
loop, force against sliding displacement, of the run that slid farthest, measured and
fitted. A fit that is right puts the coloured points on the grey ones in both panels.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np

from harness.identification.friction_fit import FrictionFit, SlidingRecord
from harness.report.figure import figure, style

MEASURED = "#9a9a9a"
FITTED = "#d62728"
ENVELOPE = "#1f77b4"
HEIGHT_PX = 560
#: Points drawn per run, at most (every k-th sample beyond it).
MAX_POINTS = 6000


def _thinned(values: np.ndarray) -> np.ndarray:
    step = max(1, len(values) // MAX_POINTS)
    return values[::step]


def friction_plot(records: list[SlidingRecord], fit: FrictionFit, weight_N: float, path: Path, title: str) -> Path:
    """Write the two panels to ``path`` (PNG); returns ``path``."""
    with matplotlib.rc_context(style()):
        fig = figure(HEIGHT_PX)
        velocity_ax, loop_ax = fig.subplots(1, 2)
        for index, record in enumerate(records):
            label = index == 0
            velocity = _thinned(record.velocity_m_s) * 1e3
            velocity_ax.plot(velocity, _thinned(fit.measured_N[index]) / 1e3, ".", color=MEASURED, markersize=2,
                             label="measured (force balance)" if label else None)
            velocity_ax.plot(velocity, _thinned(fit.fitted_N[index]) / 1e3, ".", color=FITTED, markersize=1.5,
                             label="fitted" if label else None)
        reach = max(float(np.abs(r.velocity_m_s).max()) for r in records)
        speeds = np.linspace(0.0, reach, 201)
        bearing = fit.bearing
        sliding_N = (bearing.mu_max - bearing.mu_delta * np.exp(-bearing.a_mu_s_per_m * speeds)) * weight_N * bearing.nu_bound
        for sign in (1.0, -1.0):  # sliding, the force has the velocity's sign
            velocity_ax.plot(sign * speeds * 1e3, sign * sliding_N / 1e3, "-", color=ENVELOPE, linewidth=1.2,
                             label="fitted law, sliding: mu(v) mbar g" if sign > 0 else None)
        velocity_ax.set_xlabel("sliding velocity (mm/s)")
        velocity_ax.set_ylabel("friction force (kN)")
        velocity_ax.set_title("friction against sliding velocity")
        velocity_ax.legend(loc="lower right", markerscale=4)
        widest = int(np.argmax([np.ptp(r.displacement_m) for r in records]))
        record = records[widest]
        loop_ax.plot(record.displacement_m * 1e3, fit.measured_N[widest] / 1e3, "-", color=MEASURED, linewidth=0.8,
                     label="measured")
        loop_ax.plot(record.displacement_m * 1e3, fit.fitted_N[widest] / 1e3, "-", color=FITTED, linewidth=0.6, label="fitted")
        loop_ax.set_xlabel("sliding displacement (mm)")
        loop_ax.set_ylabel("friction force (kN)")
        loop_ax.set_title(f"hysteresis loop: {record.label}")
        loop_ax.legend(loc="lower right")
        fig.suptitle(title)
        fig.savefig(path, format="png")
    return path
