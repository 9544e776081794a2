"""A plot of one processed ground motion (``harness records NAME --plot PNG``)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

from harness.report.figure import PlotFile, figure, save, style


def motion_plot(motion, path: str | Path) -> PlotFile:
    """Table acceleration (g), velocity (m/s) and displacement (mm) of ``motion`` against time.

    Parameters
    ----------
    motion : harness.motions.GroundMotion
    path : str or Path
        The PNG to write (its folder is created).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with matplotlib.rc_context(style()):
        fig = figure(900)
        axes = fig.subplots(3, 1, sharex=True)
        t = motion.t_s
        series = (
            (motion.accel_m_s2 / 9.80665, "acceleration (g)", f"PGA {motion.pga_g:.3f} g"),
            (motion.velocity_m_s, "velocity (m/s)", f"PGV {motion.pgv_m_s:.3f} m/s"),
            (motion.displacement_m * 1e3, "displacement (mm)", f"PGD {motion.pgd_m * 1e3:.1f} mm"),
        )
        for ax, (values, label, peak) in zip(axes, series):
            ax.plot(t, values, lw=0.8, label=peak)
            ax.set_ylabel(label)
            ax.legend(loc="upper right")
            ax.grid(alpha=0.3)
        axes[-1].set_xlabel("time (s)")
        fig.suptitle(f"{motion.name}: processed table motion (time scale {motion.time_scale:g})")
        return save(fig, path.stem, "table motion", path.parent)
