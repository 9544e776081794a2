"""A plot of one ground motion (``harness records NAME --plot``): the raw record beside the processed one, and spectra.

Left column: the record as read (acceleration, and velocity and displacement integrated
from rest without any correction, so a drifting baseline shows). Right column: the
processed table motion (time scale, cut, PGA, baseline correction), with the table's
limits where the profile has them. Bottom: the 5 %-damped pseudo-acceleration response
spectra of both (the processed one's periods are shorter by the time scale).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib
import numpy as np
from matplotlib.axes import Axes

from harness.motions.accel_units import G_M_S2
from harness.motions.integration import integrate_from_rest
from harness.motions.spectrum import DEFAULT_DAMPING, response_spectrum
from harness.report.figure import PlotFile, figure, save, style

RAW_COLOUR = "#7f7f7f"
PROCESSED_COLOUR = "#1f77b4"
LIMIT_COLOUR = "#d62728"


def _series(t_s: np.ndarray, accel: np.ndarray, velocity: np.ndarray, displacement: np.ndarray) -> list[tuple]:
    return [
        (t_s, accel / G_M_S2, "acceleration (g)", f"PGA {np.max(np.abs(accel)) / G_M_S2:.3f} g"),
        (t_s, velocity, "velocity (m/s)", f"PGV {np.max(np.abs(velocity)):.3f} m/s"),
        (t_s, displacement * 1e3, "displacement (mm)", f"PGD {np.max(np.abs(displacement)) * 1e3:.1f} mm"),
    ]


def _column(axes: Sequence[Axes], series: list[tuple], colour: str, title: str) -> None:
    for ax, (t, values, label, peak) in zip(axes, series, strict=True):
        ax.plot(t, values, lw=0.8, color=colour, label=peak)
        ax.set_ylabel(label)
        ax.legend(loc="upper right")
    axes[0].set_title(title)
    axes[-1].set_xlabel("time (s)")


def _limits(axes: Sequence[Axes], table: Any) -> None:
    """The table's acceleration, velocity and stroke limits as dashed lines on the processed column."""
    for ax, value in zip(axes, (table.acceleration_limit_g, table.velocity_limit_m_s, table.stroke_limit_m * 1e3),
                         strict=True):
        ax.axhline(value, color=LIMIT_COLOUR, ls="--", lw=1.0, label=f"table limit ±{value:g}")
        ax.axhline(-value, color=LIMIT_COLOUR, ls="--", lw=1.0)
        ax.legend(loc="upper right")


def _spectra(ax: Axes, raw: Any, motion: Any) -> None:
    for record, colour, what in ((raw, RAW_COLOUR, "raw record"), (motion, PROCESSED_COLOUR, "processed")):
        if record is None:
            continue
        spectrum = response_spectrum(record.accel_m_s2, record.dt_s)
        peak, period = spectrum.peak()
        ax.plot(spectrum.periods_s, spectrum.sa_m_s2 / G_M_S2, color=colour, lw=1.4,
                label=f"{what}: peak {peak / G_M_S2:.2f} g at {period:.2f} s")
    ax.set_xscale("log")
    ax.set(xlabel="period T (s)", ylabel="Sa (g)",
           title=f"{DEFAULT_DAMPING * 100:g} %-damped pseudo-acceleration response spectrum")
    ax.legend(loc="upper right")


def motion_plot(motion: Any, path: str | Path, raw: Any = None, table: Any = None) -> PlotFile:
    """Raw record, processed table motion and their response spectra, as one PNG.

    Parameters
    ----------
    motion : harness.motions.GroundMotion
        The processed motion.
    path : str or Path
        The PNG to write (its folder is created).
    raw : harness.motions.RawRecord, optional
        The record as read; without it only the processed column and spectrum are drawn.
    table : harness.motions.TableLimits, optional
        The table's limits, drawn on the processed motion.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context(style()):
        fig = figure(1150)
        grid = fig.add_gridspec(4, 2, height_ratios=(1, 1, 1, 1.3))
        processed_axes = [fig.add_subplot(grid[row, 1]) for row in range(3)]
        processed = _series(motion.t_s, motion.accel_m_s2, motion.velocity_m_s, motion.displacement_m)
        _column(processed_axes, processed, PROCESSED_COLOUR,
                f"processed: time scale {motion.time_scale:g}, step {motion.dt_s * 1e3:g} ms")
        if table is not None:
            _limits(processed_axes, table)
        if raw is not None:
            raw_axes = [fig.add_subplot(grid[row, 0]) for row in range(3)]
            velocity, displacement = integrate_from_rest(raw.accel_m_s2, raw.dt_s)
            t_raw = np.arange(raw.accel_m_s2.size) * raw.dt_s
            _column(raw_axes, _series(t_raw, raw.accel_m_s2, velocity, displacement), RAW_COLOUR,
                    f"raw record as read: step {raw.dt_s * 1e3:g} ms (integrated from rest, uncorrected)")
        _spectra(fig.add_subplot(grid[3, :]), raw, motion)
        fig.suptitle(f"{motion.name}: the record as read and the table motion after processing")
        return save(fig, path.stem, f"{motion.name}: raw and processed motion, response spectra", path.parent)
