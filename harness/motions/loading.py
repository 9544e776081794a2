"""The one-call entry point that turns a profile's ``record:`` section into a motion.

Precedence: keyword arguments (from CLI flags) win over the profile; the records
directory comes from the flag, then ``$HARNESS_RECORDS_DIR``, then the profile
(:func:`harness.motions.catalog.records_dir_from`). Relative paths in the profile
(``records_dir`` and a ``name`` that is a path) are relative to the profile's
directory, passed as ``base_dir``.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping
from pathlib import Path

from harness.config.input_limits import MAX_DURATION_S
from harness.errors import RecordError
from harness.motions.catalog import (
    CATALOG,
    looks_like_path,
    records_dir_from,
    resolve_record,
    synthetic_seed,
)
from harness.motions.checks import MIN_SAMPLES
from harness.motions.config import (
    DEFAULT_SYNTHETIC_DURATION_S,
    DEFAULT_SYNTHETIC_PGA_G,
    SYNTHETIC_DT_S,
    RecordConfig,
)
from harness.motions.loaders import RawRecord, load_record
from harness.motions.processing import TIME_COMPRESSED, GroundMotion, process_record
from harness.motions.synthetic import synthetic_record
from harness.motions.white_noise import white_noise_record
from harness.motions.white_noise_name import WhiteNoiseSpec, white_noise_spec


def load_raw(
    name_or_path: str,
    records_dir: str | Path | None,
    *,
    accel_unit: str | None = None,
    seed: int = 0,
    synthetic_duration_s: float = DEFAULT_SYNTHETIC_DURATION_S,
    synthetic_pga_g: float = DEFAULT_SYNTHETIC_PGA_G,
    time_scale: float = 1.0,
) -> RawRecord:
    """Load a record by catalog name, file name or path, or generate ``synthetic[:SEED]`` or ``white_noise:...``.

    Parameters
    ----------
    name_or_path : str
        See :func:`harness.motions.catalog.resolve_record`; ``synthetic`` uses ``seed``
        and ``synthetic:SEED`` its own seed.
    records_dir : str or Path, optional
        The records directory.
    accel_unit : str, optional
        Unit of a file that does not state it.
    seed : int
        Seed for plain ``synthetic``.
    synthetic_duration_s, synthetic_pga_g : float
        Length (s, before compression) and PGA (g) of a generated record; white noise takes
        its PGA from its name.
    time_scale : float
        The time compression the record will get: white noise is generated so that it plays
        its band after it (:mod:`harness.motions.white_noise`).
    """
    spec = white_noise_spec(name_or_path)
    if spec is not None:
        return white_noise_record(spec, seed=seed, duration_s=synthetic_duration_s / time_scale, time_scale=time_scale)
    named_seed = synthetic_seed(name_or_path)
    if named_seed is not None:
        chosen = seed if name_or_path.strip() == "synthetic" else named_seed
        return synthetic_record(seed=chosen, duration_s=synthetic_duration_s, dt_s=SYNTHETIC_DT_S, pga_g=synthetic_pga_g)
    path = resolve_record(name_or_path, records_dir)
    return load_record(path, accel_unit=accel_unit, name=name_or_path if name_or_path in CATALOG else None)


def load_motion(
    config: RecordConfig,
    *,
    base_dir: str | Path,
    records_dir_flag: str | Path | None = None,
    name: str | None = None,
    pga_g: float | None = None,
    time_scale: float | None = None,
    duration_s: float | None = None,
    accel_unit: str | None = None,
    env: Mapping[str, str] = os.environ,
) -> GroundMotion:
    """Build the table motion of a run from the profile's ``record:`` section and CLI overrides.

    Parameters
    ----------
    config : RecordConfig
        The profile section.
    base_dir : str or Path
        Directory of the profile file (for its relative paths).
    records_dir_flag : str or Path, optional
        ``--records-dir`` from the CLI.
    name, pga_g, time_scale, duration_s, accel_unit : optional
        CLI overrides; each wins over the profile when given. ``name`` may be a
        path (relative to the working directory).
    env : mapping
        The environment (for ``HARNESS_RECORDS_DIR``).

    Returns
    -------
    GroundMotion
        Compressed, cut, scaled and baseline-corrected.
    """
    return load_raw_and_motion(config, base_dir=base_dir, records_dir_flag=records_dir_flag, name=name, pga_g=pga_g,
                               time_scale=time_scale, duration_s=duration_s, accel_unit=accel_unit, env=env)[1]


def load_raw_and_motion(
    config: RecordConfig,
    *,
    base_dir: str | Path,
    records_dir_flag: str | Path | None = None,
    name: str | None = None,
    pga_g: float | None = None,
    time_scale: float | None = None,
    duration_s: float | None = None,
    accel_unit: str | None = None,
    env: Mapping[str, str] = os.environ,
) -> tuple[RawRecord, GroundMotion]:
    """:func:`load_motion`, and the raw record it was processed from (``harness records`` shows both).

    Parameters and errors as :func:`load_motion`.
    """
    chosen_name = name if name is not None else resolve_record_name(config.name, base_dir)
    scale = time_scale if time_scale is not None else config.time_scale
    duration = duration_s if duration_s is not None else config.duration_s
    target = pga_g if pga_g is not None else config.pga_g
    records_dir = records_dir_from(records_dir_flag, config.records_dir, env, base_dir=base_dir)
    spec = white_noise_spec(chosen_name)
    if synthetic_seed(chosen_name) is not None:  # its time step is known before it is made
        _check_duration(duration, SYNTHETIC_DT_S, scale, chosen_name)
    if spec is not None:
        _check_duration(duration, spec.step_s * scale, scale, chosen_name)
    raw = load_raw(
        chosen_name,
        records_dir,
        accel_unit=accel_unit if accel_unit is not None else config.accel_unit,
        seed=config.seed,
        synthetic_duration_s=(duration or DEFAULT_SYNTHETIC_DURATION_S) * scale,
        synthetic_pga_g=target or DEFAULT_SYNTHETIC_PGA_G,
        time_scale=scale,
    )
    _check_duration(duration, raw.dt_s, scale, chosen_name)
    if spec is not None:
        motion = _white_noise_motion(raw, spec, target, scale, duration)
    else:
        motion = process_record(raw, pga_g=target, time_scale=scale, duration_s=duration)
    if motion.duration_s > MAX_DURATION_S:
        raise RecordError(
            f"record {motion.name!r} runs {motion.duration_s:g} s after a time scale of {scale:g}, expected at most "
            f"{MAX_DURATION_S:g} s (what a run or a simulation may allocate); cut it with --duration or record.duration_s"
        )
    return raw, motion


def _white_noise_motion(
    raw: RawRecord, spec: WhiteNoiseSpec, pga_g: float | None, time_scale: float, duration_s: float | None,
) -> GroundMotion:
    """White noise processed at the amplitude of its name, with a note where ``record.pga_g`` asked for another."""
    motion = process_record(raw, pga_g=spec.pga_g, time_scale=time_scale, duration_s=duration_s)
    kept = tuple(note for note in motion.notes if not note.startswith(TIME_COMPRESSED))  # its band is not compressed
    notes = [f"white noise {spec.low_hz:g}-{spec.high_hz:g} Hz as the table plays it, at the {spec.pga_g:g} g its name gives"]
    if time_scale != 1.0:
        notes.append(f"time scale {time_scale:g}: generated over a band {time_scale:g} times lower, so the table still "
                     f"plays {spec.low_hz:g}-{spec.high_hz:g} Hz (the band is not compressed)")
    if pga_g is not None and abs(pga_g - spec.pga_g) > 1e-9 * spec.pga_g:
        notes.append(f"record.pga_g (or --pga) of {pga_g:g} g does not apply to white noise: give the amplitude in its name, "
                     f"e.g. {WhiteNoiseSpec(spec.low_hz, spec.high_hz, pga_g).name}")
    return dataclasses.replace(motion, notes=(*kept, *notes))


def _check_duration(duration_s: float | None, raw_dt_s: float, time_scale: float, name: str) -> None:
    """Refuse a run length shorter than :data:`MIN_SAMPLES` samples of the record, naming where it was given.

    The record's step after the time scale is ``raw_dt_s / time_scale``; the range of ``--duration``
    cannot say it, so the option and the profile key are named here (the records' own checks
    speak of a synthetic record's uncompressed length, which the user never typed).

    Raises
    ------
    RecordError
        With the length found, the least accepted, and why.
    """
    if duration_s is None:
        return
    dt_s = raw_dt_s / time_scale
    shortest_s = MIN_SAMPLES * dt_s
    if not duration_s >= shortest_s * (1.0 - 1e-9):
        raise RecordError(
            f"record {name!r}: found a run length (--duration or record.duration_s) of {duration_s:g} s, expected at "
            f"least {shortest_s:g} s: {MIN_SAMPLES} samples of the record, {dt_s:g} s each after the time scale of "
            f"{time_scale:g}"
        )


def resolve_record_name(name: str, base_dir: str | Path) -> str:
    """A record name, with a relative path in it taken relative to ``base_dir``.

    ``base_dir`` is the profile's directory for the profile's own ``record.name``, and the
    working directory for ``--record``.
    """
    path = Path(name).expanduser()
    if synthetic_seed(name) is None and looks_like_path(name) and not path.is_absolute():
        return str(Path(base_dir) / path)
    return name
