"""Ground motions for the shaking table (SPEC section 4).

Pipeline: a file (PEER ``.AT2`` or two-column text/CSV, :mod:`.loaders`) or the
seeded generator (:mod:`.synthetic`) gives a :class:`RawRecord`;
:func:`process_record` (:mod:`.processing`, :mod:`.baseline`) compresses time,
cuts, scales to the target PGA and corrects the baseline into a
:class:`GroundMotion` whose displacement, velocity and acceleration are exact
integrals of one another under the piecewise-linear rule of :mod:`.integration`;
:func:`check_table_limits` (:mod:`.limits`) refuses what the table cannot follow;
:func:`summarize` (:mod:`.summary`) reports PGA/PGV/PGD, Arias intensity,
significant duration and periods; :func:`response_spectrum` (:mod:`.spectrum`) the
damped elastic response spectrum. :mod:`.catalog` finds record files by name and
:func:`load_motion` (:mod:`.config`) does all of it from the profile's ``record:``
section and CLI overrides.
"""

from harness.motions.accel_units import ACCEL_UNITS, G_M_S2, normalize_accel_unit
from harness.motions.catalog import (
    CATALOG,
    ENV_RECORDS_DIR,
    CatalogRecord,
    RecordListing,
    list_records,
    records_dir_from,
    resolve_record,
    synthetic_seed,
)
from harness.motions.checks import MAX_ABS_ACCEL_G, MIN_SAMPLES
from harness.motions.config import RecordConfig
from harness.motions.integration import (
    integrate_from_rest,
    interpolate,
    interpolate_scalar,
    rule_residuals,
)
from harness.motions.limits import (
    LimitExcess,
    TableLimitError,
    TableLimits,
    check_table_limits,
    largest_fitting_pga_g,
    table_excesses,
)
from harness.motions.loaders import RawRecord, load_record
from harness.motions.loading import load_motion, load_raw
from harness.motions.processing import GroundMotion, process_record
from harness.motions.spectrum import ResponseSpectrum, response_spectrum
from harness.motions.summary import MotionSummary, summarize
from harness.motions.synthetic import synthetic_record

__all__ = [
    "ACCEL_UNITS",
    "CATALOG",
    "ENV_RECORDS_DIR",
    "G_M_S2",
    "MAX_ABS_ACCEL_G",
    "MIN_SAMPLES",
    "CatalogRecord",
    "GroundMotion",
    "LimitExcess",
    "MotionSummary",
    "RawRecord",
    "RecordConfig",
    "RecordListing",
    "ResponseSpectrum",
    "TableLimitError",
    "TableLimits",
    "check_table_limits",
    "integrate_from_rest",
    "largest_fitting_pga_g",
    "interpolate",
    "interpolate_scalar",
    "list_records",
    "load_motion",
    "load_raw",
    "load_record",
    "normalize_accel_unit",
    "process_record",
    "records_dir_from",
    "resolve_record",
    "response_spectrum",
    "rule_residuals",
    "summarize",
    "synthetic_record",
    "synthetic_seed",
    "table_excesses",
]
