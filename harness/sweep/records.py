"""The records of a study: names, files and folders turned into record files, each with a content digest.

A case hands its record to the simulation as an absolute file path (or ``synthetic:SEED``),
so a worker on another machine of a cluster reads the same file whatever its own
``$HARNESS_RECORDS_DIR`` says (the folder must be on a shared file system there). The digest
(SHA-256 of the file) goes into the case's key: a record file that changes makes its
cases new, and a rerun simulates them again.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from harness.errors import ProfileError, RecordError
from harness.motions.catalog import RECORD_SUFFIXES, looks_like_path, resolve_record, synthetic_seed
from harness.motions.loaders import load_record
from harness.motions.white_noise_name import white_noise_spec


@dataclass(frozen=True)
class StudyRecord:
    """One record of a study.

    Attributes
    ----------
    label : str
        Its name in the results (``el_centro``, a file's stem, ``synthetic:2``).
    source : str
        What the simulation is given: an absolute file path, ``synthetic[:SEED]`` or ``white_noise:LOW-HIGH[:PGA]``.
    digest : str
        SHA-256 of the file's bytes, or the generated record's name (in full, for white noise).
    """

    label: str
    source: str
    digest: str


def file_digest(path: Path) -> str:
    """SHA-256 (hex) of a file's bytes."""
    digest = hashlib.sha256()
    with path.open("rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _from_file(label: str, path: Path, accel_unit: str | None = None) -> StudyRecord:
    """The study record of the file at ``path``, once the record loader has read it as a record.

    A study names its records by path, and each case's results carry what the loader said about its
    record; so a file that is not a record (any readable file) is refused here, before any case, with
    the loader's reason, which quotes at most a short escaped excerpt of it
    (:func:`harness.motions.loaders.excerpt`).
    """
    path = path.resolve()
    if path.suffix.lower() not in RECORD_SUFFIXES:
        raise RecordError(
            f"{path} is not a record file: a study reads ground-motion records ending in {', '.join(RECORD_SUFFIXES)}"
        )
    try:
        load_record(path, accel_unit=accel_unit)
    except RecordError as err:
        raise RecordError(f"{path} is not a ground-motion record the loader reads: {err}") from err
    return StudyRecord(label, str(path), file_digest(path))


def _folder_records(folder: Path, accel_unit: str | None) -> list[StudyRecord]:
    """Every record file of a folder (suffixes of ``harness records``), sorted by name."""
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in RECORD_SUFFIXES)
    return [_from_file(p.stem, p, accel_unit) for p in files]


def study_records(
    entries: tuple[str, ...], base_dir: Path, records_dir: Path | None, accel_unit: str | None = None,
) -> list[StudyRecord]:
    """The records that ``entries`` name.

    Parameters
    ----------
    entries : tuple of str
        Names (``el_centro``, ``synthetic:3``, ``white_noise:0.5-20``), record files, or folders (every record file in it).
    base_dir : Path
        Relative paths are relative to this (the study file's directory, or the profile's).
    records_dir : Path, optional
        Where names are looked up (as ``--records-dir``).
    accel_unit : str, optional
        The profile's ``record.accel_unit``, for files that do not state their unit.

    Raises
    ------
    RecordError
        For an entry that names no record, or a file that is not one, with what was looked for
        or why (the caller adds the key).
    """
    found: list[StudyRecord] = []
    for entry in entries:
        if synthetic_seed(entry) is not None:
            found.append(StudyRecord(entry.strip(), entry.strip(), entry.strip()))
            continue
        noise = white_noise_spec(entry)  # generated from the profile's record.seed: its name is its content
        if noise is not None:
            found.append(StudyRecord(entry.strip(), entry.strip(), noise.name))
            continue
        path = Path(entry).expanduser()
        path = path if path.is_absolute() else base_dir / path
        if path.is_dir():
            in_folder = _folder_records(path, accel_unit)
            if not in_folder:
                raise RecordError(f"folder {path} holds no record file ({', '.join(RECORD_SUFFIXES)})")
            found.extend(in_folder)
        elif path.is_file() or looks_like_path(entry):
            found.append(_from_file(path.stem, resolve_record(str(path), records_dir), accel_unit))
        else:
            found.append(_from_file(entry, resolve_record(entry, records_dir), accel_unit))
    return found


def count_records(entries: tuple[str, ...], base_dir: Path) -> int:
    """How many records :func:`study_records` gives for ``entries``, without reading any of them.

    A name, a file or ``synthetic:SEED`` counts one; a folder counts its record files (by
    suffix, as :func:`study_records` takes them). Whether each exists is checked when the
    study is expanded; this count sizes the study before that (``harness sweep --plan``).
    """
    total = 0
    for entry in entries:
        path = Path(entry).expanduser()
        path = path if path.is_absolute() else base_dir / path
        if synthetic_seed(entry) is None and path.is_dir():
            total += sum(1 for p in path.iterdir() if p.is_file() and p.suffix.lower() in RECORD_SUFFIXES)
        else:
            total += 1
    return total


def checked_records(
    entries: tuple[str, ...], base_dir: Path, records_dir: Path | None, source: str, key: str,
    accel_unit: str | None = None,
) -> list[StudyRecord]:
    """:func:`study_records`, each problem refused as a :class:`ProfileError` of the study file at ``key``."""
    records = []
    for i, entry in enumerate(entries):
        try:
            records.extend(study_records((entry,), base_dir, records_dir, accel_unit))
        except RecordError as err:
            raise ProfileError(f"found {entry!r}: {err}", source, f"{key}[{i}]") from err
    labels = [record.label for record in records]
    repeated = sorted({label for label in labels if labels.count(label) > 1})
    if repeated:
        raise ProfileError(f"record {repeated[0]!r} is named twice; expected each record once", source, key)
    return records
