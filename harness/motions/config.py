"""The profile's ``record:`` section: which ground motion, and how to scale it (settings only).

:mod:`harness.motions.loading` turns the section into a motion.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.config.input_limits import (
    MAX_DURATION_S,
    MAX_PGA_G,
    MAX_SEED,
    MAX_TIME_SCALE,
    MIN_TIME_SCALE,
)
from harness.config.schema import quantity
from harness.errors import RecordError
from harness.motions.accel_units import normalize_accel_unit
from harness.motions.white_noise_name import white_noise_spec

#: Length of a run when neither the profile nor the CLI gives one (s, processed time).
DEFAULT_SYNTHETIC_DURATION_S = 30.0
#: Sample step of the synthetic record before time compression (s).
SYNTHETIC_DT_S = 0.01
#: PGA the synthetic record is generated with when none is asked for (g).
DEFAULT_SYNTHETIC_PGA_G = 0.3


@dataclass(frozen=True)
class RecordConfig:
    """Profile section ``record:``: which ground motion, and how to scale it."""

    name: str = quantity(
        "synthetic", doc="catalog name, file name or path, synthetic / synthetic:SEED, or white_noise:LOW-HIGH[:PGA]"
    )
    records_dir: str | None = quantity(None, doc="directory of the real records (relative to the profile)")
    # Bounds shared with the command line; harness/config/input_limits.py gives the reasons.
    pga_g: float | None = quantity(
        None, unit="g", gt=0, le=MAX_PGA_G, doc="target peak table acceleration (g); none: the record's"
    )
    time_scale: float = quantity(
        1.0, ge=MIN_TIME_SCALE, le=MAX_TIME_SCALE, doc="time compression factor F: every step is divided by F"
    )
    duration_s: float | None = quantity(
        None, unit="s", gt=0, le=MAX_DURATION_S, doc="run length after compression (s); none: whole record"
    )
    accel_unit: str | None = quantity(None, doc="unit of a file that does not state it: g, m/s^2, cm/s^2 (gal)")
    seed: int = quantity(0, ge=0, le=MAX_SEED, doc="seed of the synthetic record")

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ValueError("name: expected a record name, found an empty string")
        try:
            white_noise_spec(self.name)
        except RecordError as err:
            raise ValueError(f"name: {err}") from err
        if self.accel_unit is not None:
            try:
                normalize_accel_unit(self.accel_unit)
            except RecordError as err:
                raise ValueError(f"accel_unit: {err}") from err
