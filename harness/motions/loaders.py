"""Read accelerogram files into a :class:`RawRecord` (acceleration in m/s^2 at a fixed step).

Formats
-------
PEER NGA ``.AT2``
    Four header lines; line 4 gives the number of points and the step, as
    ``NPTS=  4000, DT= .01000 SEC`` (also ``NPTS= 4000 DT= 0.01`` and the older
    ``4000  .0100  NPTS, DT``). Values are in g, several per line.
Two-column text/CSV
    ``time, acceleration`` per line, separated by commas, semicolons, tabs or
    spaces; ``#`` comment lines and blank lines are skipped; empty trailing fields
    (``0.02,-0.7,,,,``) are ignored. An optional header row names the columns and
    may state the units (``t_s,accel_g``, ``time_s,acc_m_s2``, ``t,acc [gal]``).
    The time step must be uniform.
Single column with a ``dt=`` header
    ``key=value`` header lines (``dt=0.02``, optionally ``ndata=``/``npts=`` and
    ``Max.acc=``), then the values, one or more per line.

The acceleration unit comes from the file (AT2: g; a header that states it) or from
the caller's ``accel_unit``; where neither states it, loading fails and says how
to state it. Units are never guessed from the size of the numbers.

Every problem raises :class:`~harness.errors.RecordError` naming the file and,
where it applies, the line: a missing or empty file, binary content, a header that
does not fit, non-numeric, NaN or infinite values, fewer than
:data:`~harness.motions.checks.MIN_SAMPLES` samples, a time step that is not uniform or not positive, and
absurd values (beyond :data:`~harness.motions.checks.MAX_ABS_ACCEL_G`).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from harness.errors import RecordError
from harness.motions.accel_units import (
    G_M_S2,
    accel_factor,
    normalize_accel_unit,
    split_column_name,
    time_factor,
)
from harness.motions.checks import check_count, check_samples, uniform_step

_CONTROL_BYTES = bytes(range(0, 9)) + bytes(range(14, 32))
_AT2_NPTS_DT = re.compile(r"NPTS\s*=\s*(\d+)\s*,?\s*DT\s*=\s*([-+0-9.EeDd]+)", re.IGNORECASE)
_AT2_OLD = re.compile(r"^\s*(\d+)\s+([-+0-9.EeDd]+)\s+NPTS\s*,\s*DT", re.IGNORECASE)
_KEY_VALUE = re.compile(r"([A-Za-z][A-Za-z0-9_.]*)\s*=\s*([-+0-9.EeDd]+)")
_TIME_NAMES = ("t", "time", "sec", "seconds")

Line = tuple[int, str]

#: Most characters of a file's line an error message quotes: a file that is not a record (any readable
#: file named by mistake, or on purpose) must not have its content copied into messages and results.
EXCERPT_CHARS = 32


def excerpt(text: str) -> str:
    """``text`` quoted for an error message: at most :data:`EXCERPT_CHARS` characters, escaped to ASCII.

    Non-printable and non-ASCII characters are escaped (``ascii()``), so the excerpt cannot
    carry control sequences into a terminal, a log or ``cases.csv``; a longer line is cut and
    says how much was left out.
    """
    if len(text) <= EXCERPT_CHARS:
        return ascii(text)
    return f"{ascii(text[:EXCERPT_CHARS])}... ({len(text) - EXCERPT_CHARS} more characters)"


#: Largest record file read (bytes): a 600 s record at 200 Hz is about 2 MB of text; the cap
#: bounds what one read allocates (and refuses a disk image given by mistake).
MAX_RECORD_BYTES = 50_000_000


class SampledAcceleration:
    """Shared facts of anything with ``accel_m_s2`` sampled every ``dt_s`` (records and table motions)."""

    accel_m_s2: np.ndarray
    dt_s: float

    @property
    def n_samples(self) -> int:
        """Number of samples."""
        return int(self.accel_m_s2.size)

    @property
    def duration_s(self) -> float:
        """Time from the first to the last sample (s)."""
        return (self.n_samples - 1) * self.dt_s

    @property
    def pga_g(self) -> float:
        """Peak |acceleration| (g)."""
        return float(np.max(np.abs(self.accel_m_s2))) / G_M_S2


@dataclass(frozen=True, eq=False)
class RawRecord(SampledAcceleration):
    """An accelerogram as read from a file or generated: a fixed step and the samples.

    Parameters
    ----------
    name : str
        Short name, e.g. ``"el_centro"`` or the file stem.
    dt_s : float
        Sample step (s), > 0.
    accel_m_s2 : numpy.ndarray
        Ground acceleration (m/s^2), one-dimensional; stored read-only.
    source : str
        Where it came from (file path, or the generator and its seed).
    """

    name: str
    dt_s: float
    accel_m_s2: np.ndarray
    source: str

    def __post_init__(self) -> None:
        accel = np.array(self.accel_m_s2, dtype=float)
        if accel.ndim != 1:
            raise RecordError(f"record {self.name!r}: expected a 1-D acceleration array, found shape {accel.shape}")
        if not (np.isfinite(self.dt_s) and self.dt_s > 0):
            raise RecordError(f"record {self.name!r}: expected a time step > 0 s, found {self.dt_s!r}")
        accel.flags.writeable = False
        object.__setattr__(self, "dt_s", float(self.dt_s))
        object.__setattr__(self, "accel_m_s2", accel)



def load_record(path: str | Path, *, accel_unit: str | None = None, name: str | None = None) -> RawRecord:
    """Load an AT2 or text/CSV accelerogram.

    Parameters
    ----------
    path : str or Path
        The file. ``.AT2`` files (or files whose line 4 is an AT2 ``NPTS``/``DT``
        line) are read as AT2, everything else as text.
    accel_unit : str, optional
        Unit of the acceleration values: ``"g"``, ``"m/s^2"``, ``"cm/s^2"`` (or
        ``"gal"``), ``"mm/s^2"``. Needed where the file does not state it; where it
        does, the two must agree.
    name : str, optional
        Name of the record; default the file stem.

    Returns
    -------
    RawRecord
        Acceleration in m/s^2.

    Raises
    ------
    RecordError
        For anything that is not a clean, uniformly sampled accelerogram.
    """
    file = Path(path).expanduser()
    if file.is_file():  # parsed once per file version: a sweep runs hundreds of cases on a few records
        stat = file.stat()
        return _load_record_cached(str(file.resolve()), stat.st_size, stat.st_mtime_ns, accel_unit, name)
    return _parse_record(file, accel_unit, name)  # raises the clear "not found" error


@functools.lru_cache(maxsize=32)
def _load_record_cached(path: str, size: int, mtime_ns: int, accel_unit: str | None, name: str | None) -> RawRecord:
    """:func:`_parse_record`, remembered for one version (size, modification time) of a file."""
    return _parse_record(Path(path), accel_unit, name or Path(path).stem)


def _parse_record(file: Path, accel_unit: str | None, name: str | None) -> RawRecord:
    """Parse ``file`` into a :class:`RawRecord` whose acceleration array is read-only (it may be shared)."""
    lines = _content_lines(_read_text(file))
    unit = normalize_accel_unit(accel_unit) if accel_unit is not None else None
    if file.suffix.lower() == ".at2" or _is_at2(lines):
        dt, values, linenos = _parse_at2(lines, file, unit)
        stated = "g"
    else:
        dt, values, linenos, stated = _parse_text(lines, file, unit)
    check_samples(values, linenos, file, stated)  # in the file's unit, before a conversion could overflow
    accel = values * accel_factor(stated)
    accel.flags.writeable = False
    return RawRecord(name=name or file.stem, dt_s=dt, accel_m_s2=accel, source=str(file))


def _read_text(file: Path) -> str:
    if not file.is_file():
        where = file.resolve()
        what = "is a directory, not a file" if file.is_dir() else "does not exist"
        raise RecordError(f"record file {where} {what} (looked in {where.parent})")
    try:
        size = file.stat().st_size
        if size > MAX_RECORD_BYTES:
            raise RecordError(
                f"record file {file} is {size} bytes, expected at most {MAX_RECORD_BYTES} "
                "(a 10-minute record at 200 Hz is about 2 MB of text); is it a record?"
            )
        data = file.read_bytes()
    except OSError as err:
        raise RecordError(f"cannot read record file {file}: {err.strerror or err}") from err
    if not data.strip():
        raise RecordError(f"record file {file} is empty; expected an AT2 or two-column (time, acceleration) file")
    bad = next((i for i, byte in enumerate(data) if byte in _CONTROL_BYTES), None)
    if bad is not None:
        raise RecordError(
            f"record file {file} is not a text file (control byte 0x{data[bad]:02x} at offset {bad}); "
            "expected an AT2 or two-column (time, acceleration) text file"
        )
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def _content_lines(text: str) -> list[Line]:
    """Numbered lines (1-based) without blank lines; ``#`` comments kept out too."""
    result = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip().lstrip("\ufeff")
        if line and not line.startswith("#"):
            result.append((number, line))
    return result


def _to_float(text: str, file: Path, lineno: int, what: str) -> float:
    try:
        value = float(text.replace("D", "E").replace("d", "e"))
    except ValueError as err:
        raise RecordError(f"{file}:{lineno}: expected a number for {what}, found {excerpt(text)}") from err
    if not np.isfinite(value):
        raise RecordError(f"{file}:{lineno}: {what} is {excerpt(text)}; expected a finite number")
    return value


def _split(line: str) -> list[str]:
    """Fields of a data line; empty trailing fields (``1,2,,,``) dropped."""
    if "," in line or ";" in line:
        fields = [f.strip() for f in re.split(r"[,;]", line)]
        while fields and not fields[-1]:
            fields.pop()
        return fields
    return line.split()


def _is_numeric_line(line: str) -> bool:
    try:
        [float(f) for f in _split(line)]
    except ValueError:
        return False
    return True


# --- AT2 --------------------------------------------------------------------------------


def _is_at2(lines: Sequence[Line]) -> bool:
    return len(lines) >= 4 and bool(_AT2_NPTS_DT.search(lines[3][1]) or _AT2_OLD.match(lines[3][1]))


def _parse_at2(lines: Sequence[Line], file: Path, unit: str | None) -> tuple[float, np.ndarray, np.ndarray]:
    if unit is not None and unit != "g":
        raise RecordError(f"{file}: AT2 files are in g, but accel_unit={unit!r} was given; leave accel_unit unset or 'g'")
    if len(lines) < 5:
        raise RecordError(f"{file}: expected 4 AT2 header lines and then values, found {len(lines)} non-blank lines")
    lineno, header = lines[3]
    match = _AT2_NPTS_DT.search(header) or _AT2_OLD.match(header)
    if not match:
        raise RecordError(f"{file}:{lineno}: expected an AT2 line like 'NPTS=  4000, DT= .01000 SEC', found {excerpt(header)}")
    units_line = lines[2][1].upper()
    if "UNITS OF" in units_line and not re.search(r"UNITS OF G\b", units_line):
        raise RecordError(f"{file}:{lines[2][0]}: expected acceleration 'IN UNITS OF G', found {excerpt(lines[2][1])}")
    npts = int(match.group(1))
    dt = _to_float(match.group(2), file, lineno, "DT")
    if dt <= 0:
        raise RecordError(f"{file}:{lineno}: expected DT > 0 s, found {dt:g}")
    values: list[float] = []
    linenos: list[int] = []
    for number, line in lines[4:]:
        for field in line.split():
            values.append(_to_float(field, file, number, "an acceleration value"))
            linenos.append(number)
    if len(values) != npts:
        raise RecordError(f"{file}: header line {lineno} says NPTS={npts}, but the file holds {len(values)} values")
    return dt, np.array(values), np.array(linenos)


# --- text formats ------------------------------------------------------------------------


def _parse_text(lines: Sequence[Line], file: Path, unit: str | None) -> tuple[float, np.ndarray, np.ndarray, str]:
    if not lines:
        raise RecordError(f"{file}: no data lines (only comments or blank lines)")
    first = lines[0][1]
    if not _is_numeric_line(first) and "=" in first:
        return _parse_keyed(lines, file, unit)
    header_unit = None
    time_scale = 1.0
    body = lines
    if not _is_numeric_line(first):
        header_unit, time_scale = _parse_header(lines[0], file)
        body = lines[1:]
    stated = _decide_unit(header_unit, unit, file)
    dt, values, linenos = _parse_columns(body, file, time_scale)
    return dt, values, linenos, stated


def _parse_header(line: Line, file: Path) -> tuple[str | None, float]:
    """Return (acceleration unit stated in the header or None, factor of the time unit to s)."""
    lineno, text = line
    names = _split(text)
    example = "expected a header like 't_s,accel_g' or 'time_s,acc_m_s2' (time, then acceleration)"
    if len(names) != 2:
        raise RecordError(f"{file}:{lineno}: {example}, found {len(names)} columns: {excerpt(text)}")
    time_base, time_unit = split_column_name(names[0])
    accel_base, accel_unit = split_column_name(names[1])
    if time_base not in _TIME_NAMES or not (accel_base.startswith("a") or "acc" in accel_base):
        raise RecordError(f"{file}:{lineno}: {example}, found {excerpt(text)}")
    factor = 1.0
    if time_unit:
        found = time_factor(time_unit)
        if found is None:
            raise RecordError(f"{file}:{lineno}: unknown time unit {excerpt(time_unit)} in {excerpt(names[0])}; expected s or ms")
        factor = found
    if not accel_unit:
        return None, factor
    try:
        return normalize_accel_unit(accel_unit), factor
    except RecordError as err:
        raise RecordError(f"{file}:{lineno}: column {excerpt(names[1])}: {err}") from err


def _decide_unit(header_unit: str | None, given: str | None, file: Path) -> str:
    if header_unit and given and header_unit != given:
        raise RecordError(f"{file}: the header states acceleration in {header_unit}, but accel_unit={given!r} was given")
    unit = header_unit or given
    if unit is None:
        raise RecordError(
            f"{file}: the acceleration unit is not stated. State it in the file's header row "
            "(e.g. 't_s,accel_g', 'time_s,acc_m_s2', 't,acc_gal'), or set the profile key record.accel_unit "
            "('g', 'm/s^2', 'cm/s^2' or 'gal'; for dry-run, rig and run also --set record.accel_unit=g)"
        )
    return unit


def _parse_columns(body: Sequence[Line], file: Path, time_scale: float) -> tuple[float, np.ndarray, np.ndarray]:
    times: list[float] = []
    values: list[float] = []
    linenos: list[int] = []
    for number, line in body:
        fields = _split(line)
        if len(fields) != 2:
            hint = "; a single column of values needs a 'dt=...' header line" if len(fields) == 1 else ""
            raise RecordError(
                f"{file}:{number}: expected 2 values (time, acceleration), found {len(fields)}: {excerpt(line)}{hint}"
            )
        times.append(_to_float(fields[0], file, number, "the time"))
        values.append(_to_float(fields[1], file, number, "the acceleration"))
        linenos.append(number)
    if not values:
        raise RecordError(f"{file}: no data rows after the header")
    linenos_arr = np.array(linenos)
    check_count(len(values), file)
    dt = uniform_step(np.array(times) * time_scale, linenos_arr, file)
    return dt, np.array(values), linenos_arr


def _parse_keyed(lines: Sequence[Line], file: Path, unit: str | None) -> tuple[float, np.ndarray, np.ndarray, str]:
    keys: dict[str, tuple[int, str]] = {}
    index = 0
    while index < len(lines) and not _is_numeric_line(lines[index][1]):
        number, text = lines[index]
        for key, value in _KEY_VALUE.findall(text):
            keys[key.lower()] = (number, value)
        index += 1
    if "dt" not in keys:
        raise RecordError(f"{file}: header lines without 'dt=...'; expected a time column or a 'dt=' line")
    dt = _to_float(keys["dt"][1], file, keys["dt"][0], "dt")
    if dt <= 0:
        raise RecordError(f"{file}:{keys['dt'][0]}: expected dt > 0 s, found {dt:g}")
    stated = _decide_unit(None, unit, file)
    values: list[float] = []
    linenos: list[int] = []
    for number, line in lines[index:]:
        for field in _split(line):
            values.append(_to_float(field, file, number, "an acceleration value"))
            linenos.append(number)
    count_key = next((k for k in ("npts", "ndata") if k in keys), None)
    if count_key and int(float(keys[count_key][1])) != len(values):
        header_line, stated = keys[count_key]
        raise RecordError(f"{file}:{header_line}: header says {count_key}={stated}, found {len(values)} values")
    check_count(len(values), file)
    _check_stated_peak(keys.get("max.acc"), np.array(values), file)
    return dt, np.array(values), np.array(linenos), stated


def _check_stated_peak(entry: tuple[int, str] | None, values: np.ndarray, file: Path) -> None:
    if entry is None or values.size == 0:
        return
    stated = abs(_to_float(entry[1], file, entry[0], "Max.acc"))
    found = float(np.max(np.abs(values)))
    if abs(found - stated) > 0.01 * stated:
        raise RecordError(f"{file}:{entry[0]}: header says Max.acc={entry[1]}, but the largest |value| is {found:g}")
