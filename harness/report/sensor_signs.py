"""Does the base-mat sensor move with the table? The sign check of the base-mat sensor, after a run.

A sensor of reversed polarity as a whole (displacement, velocity and acceleration flipped
together: mounted the other way, or its conditioning inverted) is self-consistent, so neither
``sensor_sign_flip`` nor ``sensor_polarity`` can see it. The table's sensor is judged against
the record the table was told (the table check, :mod:`harness.report.table_check`); the base
mat's has no record, but it rides on the table: through the bearing's friction and the actuator
between them, its absolute velocity ``ydot_b`` follows the table's ``xdot_0``. Over the record
(the rows in RUNNING) a sound base-mat sensor correlates positively with the table's; a reversed
one negatively. Measured on the virtual rig of the shipped profile (lockstep dry runs, 20 s,
white noise 0.5-5 Hz): sound +0.86 at 0.01 g and +0.70 at 0.05 g; reversed -0.49 and -0.79. At the
test's level, with the base mat sliding and the controller isolating it, a sound sensor still gives
+0.62 (the synthetic record, 0.34 g) and +0.52 (El Centro, 0.34 g), so a sound rig is not warned.
A correlation below :data:`AGAINST_THE_TABLE` is a warning on the outcome, never a silent pass;
a table that barely moved (RMS velocity below :data:`MIN_TABLE_RMS_M_S`) is not judged, and says so.

This judges the sensor's sign only, after the run, as commissioning step 1 reads it (README,
"Commissioning a rig"); it is not a safety check and acts on nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from harness.signals import columns as layout

#: A correlation of ydot_b with xdot_0 below this over the record: the base mat moved against the table.
AGAINST_THE_TABLE = 0.0
#: Least RMS table velocity over the record to judge by (m/s): ten times the velocity sensors' noise
#: (0.2 mm/s in the shipped profile); white noise 0.5-5 Hz at 0.01 g gives 2.4 mm/s.
MIN_TABLE_RMS_M_S = 0.002
#: The lifecycle state whose rows are the record (harness.safety.lifecycle.State.RUNNING).
_RUNNING = 2


@dataclass(frozen=True)
class BaseSensorSign:
    """The verdict on the base-mat sensor's sign.

    Attributes
    ----------
    verdict : str
        ``with_table`` (sound), ``against_table`` (reversed: a warning), ``not_judged`` (the table
        barely moved, or no record rows: a warning too).
    correlation : float
        Correlation of ``ydot_b`` with ``xdot_0`` over the record (NaN when not judged).
    line : str
        One line for the outcome.
    """

    verdict: str
    correlation: float
    line: str

    @property
    def warns(self) -> bool:
        """True when the outcome must carry a warning (anything but a sound sensor)."""
        return self.verdict != "with_table"


def base_sensor_sign(state: np.ndarray, table_velocity_m_s: np.ndarray, base_velocity_m_s: np.ndarray) -> BaseSensorSign:
    """Judge the base-mat sensor's sign from a run's ``state``, ``xdot_0`` and ``ydot_b`` columns.

    Parameters
    ----------
    state : ndarray
        The lifecycle state per row (``signals.csv``'s ``state``).
    table_velocity_m_s, base_velocity_m_s : ndarray
        ``xdot_0`` and ``ydot_b`` per row (m/s).
    """
    record = np.asarray(state).astype(int) == _RUNNING
    table = np.asarray(table_velocity_m_s, dtype=float)[record]
    base = np.asarray(base_velocity_m_s, dtype=float)[record]
    finite = np.isfinite(table) & np.isfinite(base)
    table, base = table[finite], base[finite]
    rms = float(np.sqrt(np.mean(table**2))) if table.size else 0.0
    if table.size < 2 or rms < MIN_TABLE_RMS_M_S or not np.std(base) > 0.0:
        return BaseSensorSign("not_judged", float("nan"), (
            f"base-mat sensor sign: not judged: the table's RMS velocity over the record was {rms * 1e3:.1f} mm/s, "
            f"expected at least {MIN_TABLE_RMS_M_S * 1e3:.1f} mm/s. WARNING: the base-mat sensor's polarity was not "
            "checked (README, Commissioning a rig)"))
    correlation = float(np.corrcoef(table, base)[0, 1])
    if correlation < AGAINST_THE_TABLE:
        return BaseSensorSign("against_table", correlation, (
            f"base-mat sensor sign: WARNING: the base mat moved against the table (correlation of ydot_b with "
            f"xdot_0 over the record {correlation:+.2f}, expected above {AGAINST_THE_TABLE:+.2f}): a base-mat sensor "
            "of reversed polarity (displacement and velocity flipped together)? Check its mounting and conditioning "
            "before any test"))
    return BaseSensorSign("with_table", correlation, (
        f"base-mat sensor sign: moves with the table (correlation of ydot_b with xdot_0 over the record "
        f"{correlation:+.2f})"))


def run_base_sensor_sign(signals) -> BaseSensorSign:
    """:func:`base_sensor_sign` of a loaded run (:class:`harness.recording.reader.RunData`)."""
    return base_sensor_sign(signals[layout.STATE], signals[layout.TABLE_VELOCITY], signals[layout.BASE_VELOCITY])
