"""Find record files by short name: the catalog, the records directory and its precedence.

The real accelerograms are not shipped with the harness (their licences do not
allow it). A user keeps them in a records directory, chosen in this order:

1. an explicit argument (the CLI flag ``--records-dir``);
2. the environment variable :data:`ENV_RECORDS_DIR` (``HARNESS_RECORDS_DIR``);
3. the profile's ``record.records_dir`` (relative to the profile file).

Short names map to the normalized file names of the shared data set; a file's stem
or name, or any path to a file, works too. ``synthetic`` (or ``synthetic:SEED``)
needs no file: it is generated (:mod:`harness.motions.synthetic`); nor does
``white_noise:LOW-HIGH[:PGA]``, band-limited white noise (:mod:`harness.motions.white_noise`).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from harness.config.input_limits import MAX_SEED
from harness.errors import RecordError
from harness.motions.white_noise_name import WHITE_NOISE, white_noise_spec

#: Environment variable that names the records directory.
ENV_RECORDS_DIR = "HARNESS_RECORDS_DIR"
#: Name of the generated record.
SYNTHETIC = "synthetic"
#: File suffixes :func:`list_records` reports.
RECORD_SUFFIXES = (".csv", ".at2", ".txt", ".dat")


@dataclass(frozen=True)
class CatalogRecord:
    """A record the harness knows by name."""

    name: str
    filename: str
    description: str
    source: str


CATALOG: dict[str, CatalogRecord] = {
    entry.name: entry
    for entry in (
        CatalogRecord(
            "el_centro",
            "elcentro_1940_NS.csv",
            "1940 Imperial Valley, El Centro Array #9, N-S (PEER I-ELC180, PGA 0.313 g)",
            "PEER NGA-West2 RSN6 Imperial Valley-02, El Centro Array #9 (https://ngawest2.berkeley.edu)",
        ),
        CatalogRecord(
            "el_centro_classic",
            "elcentro_1940_NS_classic.csv",
            "1940 Imperial Valley, El Centro N-S, classic uncorrected trace (PGA 0.348 g)",
            "PEER NGA-West2 RSN6 (https://ngawest2.berkeley.edu) or the USGS/Caltech Vol. II El Centro S00E",
        ),
        CatalogRecord(
            "pacoima",
            "pacoima_1971_S16E.csv",
            "1971 San Fernando, Pacoima Dam upper left abutment, S16E (NGA-West2 RSN77, PGA 1.22 g)",
            "PEER NGA-West2 RSN77 San Fernando, Pacoima Dam (https://ngawest2.berkeley.edu)",
        ),
        CatalogRecord(
            "hachinohe",
            "hachinohe_1968_NS.csv",
            "1968 Tokachi-oki, Hachinohe Harbor, N-S (PGA 0.234 g)",
            "PARI/PHRI strong-motion records (Port and Airport Research Institute, Japan)",
        ),
    )
}


@dataclass(frozen=True)
class RecordListing:
    """One line of ``harness records``: a name, where its file is (or would be), and whether it is there."""

    name: str
    path: Path | None
    available: bool
    description: str


def records_dir_from(
    flag: str | Path | None,
    profile_value: str | Path | None,
    env: Mapping[str, str] = os.environ,
    *,
    base_dir: str | Path | None = None,
) -> Path | None:
    """Choose the records directory: the flag, else ``$HARNESS_RECORDS_DIR``, else the profile's.

    Parameters
    ----------
    flag : str or Path, optional
        The CLI flag's value (relative paths are relative to the working directory).
    profile_value : str or Path, optional
        The profile's ``record.records_dir``; a relative path is taken relative to
        ``base_dir`` (the profile's directory).
    env : mapping
        The environment (default ``os.environ``).
    base_dir : str or Path, optional
        Directory of the profile file.

    Returns
    -------
    Path or None
        None when none of the three is set.
    """
    if flag:
        return Path(flag).expanduser()
    if env.get(ENV_RECORDS_DIR):
        return Path(env[ENV_RECORDS_DIR]).expanduser()
    if profile_value:
        path = Path(profile_value).expanduser()
        if not path.is_absolute() and base_dir is not None:
            path = Path(base_dir) / path
        return path
    return None


def synthetic_seed(name: str) -> int | None:
    """The seed named by ``synthetic`` (seed 0) or ``synthetic:SEED``; None for any other name.

    Raises
    ------
    RecordError
        For ``synthetic:`` followed by something other than a whole number.
    """
    text = name.strip()
    if text == SYNTHETIC:
        return 0
    if not text.startswith(SYNTHETIC + ":"):
        return None
    seed_text = text[len(SYNTHETIC) + 1 :]
    try:
        seed = int(seed_text)
    except ValueError as err:
        raise RecordError(f"expected 'synthetic:SEED' with a whole-number seed, found {name!r}") from err
    if not 0 <= seed <= MAX_SEED:
        raise RecordError(f"expected a seed in [0, {MAX_SEED}] in {name!r}")
    return seed


def looks_like_path(text: str) -> bool:
    """True when ``text`` names a path (has a directory separator or starts with ``~``), not a catalog name."""
    return "/" in text or "\\" in text or text.startswith("~")


def resolve_record(name_or_path: str, records_dir: str | Path | None) -> Path:
    """Find the file of a record.

    Parameters
    ----------
    name_or_path : str
        A catalog name (``el_centro``, ``el_centro_classic``, ``pacoima``,
        ``hachinohe``), a file stem or name inside ``records_dir``, or a path.
    records_dir : str or Path, optional
        The records directory (see :func:`records_dir_from`).

    Returns
    -------
    Path
        An existing file.

    Raises
    ------
    RecordError
        Naming the record, the directory searched, the known names, where to get
        the real records, and that ``synthetic`` always works.
    """
    if synthetic_seed(name_or_path) is not None:
        raise RecordError(f"{name_or_path!r} is generated, not read from a file; use synthetic_record()")
    if white_noise_spec(name_or_path) is not None:
        raise RecordError(f"{name_or_path!r} is generated, not read from a file; use white_noise_record()")
    given = Path(name_or_path).expanduser()
    if given.is_file():
        return given
    if looks_like_path(name_or_path):
        state = "is a directory, expected a record file" if given.is_dir() else "does not exist"
        raise RecordError(f"record file {given.resolve()} {state}. {_help_text()}")
    for candidate in _candidates(name_or_path, records_dir):
        if candidate.is_file():
            return candidate
    raise RecordError(_missing_message(name_or_path, records_dir))


def _candidates(name: str, records_dir: str | Path | None) -> list[Path]:
    if records_dir is None:
        return []
    folder = Path(records_dir).expanduser()
    names = [CATALOG[name].filename] if name in CATALOG else []
    names.append(name)
    names.extend(name + suffix for suffix in (".csv", ".AT2", ".at2"))
    return [folder / n for n in names]


def _help_text() -> str:
    known = ", ".join(CATALOG)
    sources = "; ".join(f"{entry.name}: {entry.source}" for entry in CATALOG.values())
    return (
        f"Known names: {known}, {SYNTHETIC} (or {SYNTHETIC}:SEED), {WHITE_NOISE}:LOW-HIGH[:PGA]. "
        f"The real records are not shipped with the harness; get them from {sources}. "
        f"'{SYNTHETIC}' always works: it is generated, no file needed."
    )


def _missing_message(name: str, records_dir: str | Path | None) -> str:
    if records_dir is None:
        where = (
            "no records directory is set (use --records-dir, the environment variable "
            f"{ENV_RECORDS_DIR}, or record.records_dir in the profile)"
        )
    else:
        folder = Path(records_dir).expanduser().resolve()
        state = ""
        if not folder.is_dir():
            state = " (that is a file, expected a directory)" if folder.exists() else " (that directory does not exist)"
        wanted = CATALOG[name].filename if name in CATALOG else f"{name}, {name}.csv or {name}.AT2"
        where = f"looked for {wanted} in {folder}{state}"
    return f"record {name!r} not found: {where}. {_help_text()}"


def list_records(records_dir: str | Path | None) -> list[RecordListing]:
    """The catalog (with availability), other record files in ``records_dir``, and ``synthetic``."""
    folder = Path(records_dir).expanduser() if records_dir is not None else None
    listing = []
    claimed: set[str] = set()
    for entry in CATALOG.values():
        path = folder / entry.filename if folder is not None else None
        available = path is not None and path.is_file()
        listing.append(RecordListing(entry.name, path, available, entry.description))
        claimed.add(entry.filename)
    if folder is not None and folder.is_dir():
        for path in sorted(folder.iterdir()):
            if path.is_file() and path.suffix.lower() in RECORD_SUFFIXES and path.name not in claimed:
                listing.append(RecordListing(path.stem, path, True, "a record file that is not in the catalog"))
    listing.append(RecordListing(SYNTHETIC, None, True, "Clough-Penzien filtered white noise, seeded (synthetic:SEED)"))
    listing.append(RecordListing(
        WHITE_NOISE, None, True, "band-limited white table acceleration for identification (white_noise:0.5-20[:PGA_G])",
    ))
    return listing
