"""The study file of ``harness sweep``: a base profile and its axes, validated like a profile.

A study file is YAML, read into the frozen dataclasses below with :func:`harness.config.schema.build`,
so it is refused exactly as a profile is: unknown keys, wrong types, units and ranges are
reported with the file, the key path, what was found and what was expected. Example::

    name: robustness_table2
    profile: ../eight_story.yaml          # relative to this file
    options: {duration_s: 30}
    axes:
      records: [el_centro]
      pga_g: [0.3]
      controllers: [FSF-I]
      set:
        control.design_stiffness_scale: [0.7, 1.0, 1.3]
    monte_carlo:                          # optional: crossed with every grid point
      samples: 8
      seed: 2024
      sampling: latin_hypercube           # or random
      set:   {bearing.mu_max: {kind: uniform, low: 0.05, high: 0.12}}
      scale: {structure.story_stiffness_N_per_m: {kind: normal, mean: 1.0, std: 0.1}}

The values of a ``set`` axis replace the profile's value at the key (units allowed, as in
``--set``); a key of several key paths joined by commas sets each of them to the same value
(one axis, e.g. a servo controller's feed-forward gain and the gain the safety checks expect:
``rig.actuator.hydraulics.feedforward.gain,safety.force.velocity_feedforward_gain: [0, 1]``); a
``scale`` axis multiplies the profile's value (every element of a list) by a factor. What each
axis value does to the profile is checked when the study is expanded (:mod:`harness.sweep.cases`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import yaml

from harness.config.input_limits import (
    MAX_DELAY_S,
    MAX_DURATION_S,
    MAX_PGA_G,
    MAX_RATE_HZ,
    MAX_SEED,
    MAX_TIME_SCALE,
    MIN_TIME_SCALE,
)
from harness.config.schema import build, internal, quantity
from harness.config.yamlload import MAX_YAML_CHARS, DuplicateKeyError, load_unique
from harness.errors import ProfileError
from harness.sweep.distributions import Distribution

#: Largest study file read (bytes): a study is a page of YAML; the limit of every YAML text (harness/config/yamlload.py).
MAX_STUDY_BYTES = MAX_YAML_CHARS
#: Most Monte-Carlo samples per grid point.
MAX_SAMPLES = 1_000_000
#: Most PGA levels of an ``pga_levels`` range.
MAX_LEVELS = 1000
#: Most cases of a study: records x PGA levels x controllers x grid points x samples. Each axis is
#: capped on its own above, but their product was not, and a study of 10^7 cases held the
#: command for minutes while its cases filled 2.3 GB. Expanding a study builds every case, with
#: its key, in the parent process before any runs (100,000 cases: 3.2 s and about 100 MB on the
#: 2-vCPU VM), and its results are one table. At the 7 cases/s a worker reaches (benchmarks/README.md)
#: 100,000 cases are 4 hours on 2 workers and minutes on a cluster; a larger campaign is several
#: studies, and a study extended later runs only its new cases.
MAX_CASES = 100_000


@dataclass(frozen=True)
class PgaLevels:
    """Evenly spaced intensity levels of an incremental dynamic analysis (g)."""

    start_g: float = quantity(unit="g", gt=0, le=MAX_PGA_G, doc="first PGA level")
    stop_g: float = quantity(unit="g", gt=0, le=MAX_PGA_G, doc="last PGA level")
    count: int = quantity(ge=2, le=MAX_LEVELS, doc="number of levels, ends included")

    def __post_init__(self) -> None:
        if self.stop_g <= self.start_g:
            raise ValueError(f"stop_g ({self.stop_g:g} g) is not above start_g ({self.start_g:g} g); expected start_g < stop_g")

    def levels(self) -> tuple[float, ...]:
        """The PGA levels (g), rounded to 1e-9 g so that they print as typed."""
        step = (self.stop_g - self.start_g) / (self.count - 1)
        return tuple(round(self.start_g + i * step, 9) for i in range(self.count))


@dataclass(frozen=True)
class CaseOptions:
    """What every case shares, as ``harness simulate``'s options; none keeps the profile's value."""

    duration_s: float | None = quantity(None, unit="s", gt=0, le=MAX_DURATION_S, doc="run length (s)")
    time_scale: float | None = quantity(None, ge=MIN_TIME_SCALE, le=MAX_TIME_SCALE, doc="time compression F")
    records_dir: str | None = quantity(None, doc="where named records are found (relative to the study file)")
    rate_hz: float | None = quantity(None, unit="Hz", gt=0, le=MAX_RATE_HZ, doc="controller sample rate (Hz)")
    friction: Literal["estimator", "model"] | None = None
    transport_delay_s: float | None = quantity(None, unit="s", ge=0, le=MAX_DELAY_S, doc="further delay (s)")
    rig_effects: bool | None = dataclasses.field(
        default=None, metadata={"doc": "run the rig's twin, as --rig-effects (the actuator, the table, the sensors)"},
    )


@dataclass(frozen=True)
class Axes:
    """The grid: every combination of the values below is a case (before Monte Carlo)."""

    records: tuple[str, ...] | None = quantity(
        None, min_len=1, doc="record names, files or folders (every record file in it); none: the profile's record"
    )
    pga_g: tuple[float, ...] | None = quantity(None, unit="g", gt=0, le=MAX_PGA_G, min_len=1, doc="PGA levels (g)")
    pga_levels: PgaLevels | None = None
    controllers: tuple[str, ...] | None = quantity(None, min_len=1, doc="designs of the profile, or 'none'")
    set: Mapping[str, tuple[Any, ...]] = dataclasses.field(default_factory=dict)
    scale: Mapping[str, tuple[float, ...]] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.pga_g is not None and self.pga_levels is not None:
            raise ValueError("give pga_g (a list) or pga_levels (a range), not both")
        for group, axes in (("set", self.set), ("scale", self.scale)):
            for key, values in axes.items():
                if not values:
                    raise ValueError(f"{group}.{key}: found an empty list, expected at least one value")
        for key, factors in self.scale.items():
            for i, factor in enumerate(factors):
                if isinstance(factor, bool) or not isinstance(factor, (int, float)) or not factor > 0:
                    raise ValueError(f"scale.{key}[{i}]: found {factor!r}, expected a factor > 0")
        _refuse_shared_keys(self.set, self.scale, "axes")

    def pga_list(self) -> tuple[float, ...] | None:
        """The PGA levels (g) of ``pga_g`` or ``pga_levels``; None keeps the profile's."""
        return self.pga_levels.levels() if self.pga_levels is not None else self.pga_g


@dataclass(frozen=True)
class MonteCarlo:
    """Samples of uncertain parameters, the same samples at every grid point (common random numbers)."""

    samples: int = quantity(ge=1, le=MAX_SAMPLES, doc="samples per grid point")
    seed: int = quantity(ge=0, le=MAX_SEED, doc="seed of the sampler: the same seed gives the same samples")
    sampling: Literal["latin_hypercube", "random"] = "latin_hypercube"
    set: Mapping[str, Distribution] = dataclasses.field(default_factory=dict)
    scale: Mapping[str, Distribution] = dataclasses.field(default_factory=dict)

    def __post_init__(self) -> None:
        if not self.set and not self.scale:
            raise ValueError("no distribution given; expected at least one key under set or scale")
        _refuse_shared_keys(self.set, self.scale, "monte_carlo")

    def keys(self) -> list[tuple[str, str]]:
        """(``"set"`` or ``"scale"``, key) of every distribution, in file order."""
        return [("set", key) for key in self.set] + [("scale", key) for key in self.scale]


@dataclass(frozen=True)
class Fragility:
    """Limits whose exceedance the fragility curves count; none: see :class:`Study`."""

    sliding_displacement_limit_m: float | None = quantity(
        None, unit="m", gt=0, doc="bearing stroke limit on |x_b| (m); none: the profile's safety.stroke.hard_limit_m"
    )
    drift_limit_m: float | None = quantity(None, unit="m", gt=0, doc="limit on the largest story drift (m); none: no curve")


@dataclass(frozen=True)
class Study:
    """A whole validated study file."""

    name: str = quantity(doc="short name, used for the results folder")
    profile: str = quantity(doc="the base profile (relative to the study file), or a shipped profile's name")
    description: str = ""
    variant: str | None = quantity(None, doc="a variant of the profile applied to every case")
    set: tuple[str, ...] = quantity((), doc="KEY.PATH=VALUE overrides applied to every case, as --set")
    overlay: str | None = quantity(
        None, doc="a profile overlay (e.g. an identification's identified.yaml, relative to the study file) merged after "
                  "the variant and before set, as --overlay",
    )
    options: CaseOptions = dataclasses.field(default_factory=CaseOptions)
    axes: Axes = dataclasses.field(default_factory=Axes)
    monte_carlo: MonteCarlo | None = None
    fragility: Fragility = dataclasses.field(default_factory=Fragility)
    source_path: str = internal("", "the study file")

    def __post_init__(self) -> None:
        # "." and ".." name the results folder's parent or itself: logs/sweeps/.. is logs/
        dots_only = set(self.name) <= {"."}
        if not self.name.strip() or any(ch in self.name for ch in "/\\") or dots_only or not self.name.isprintable():
            raise ValueError(f"name: found {self.name!r}, expected a short name without slashes, not made of dots only")
        axes = [key for key in self.axes.set] + [key for key in self.axes.scale]
        sampled = [] if self.monte_carlo is None else [key for _, key in self.monte_carlo.keys()]
        both = sorted(set(axes) & set(sampled))
        if both:
            raise ProfileError(f"{both[0]} is also a grid axis (axes); expected each key in one place", None, "monte_carlo")

    @property
    def base_dir(self) -> Path:
        """Directory of the study file: relative paths in it are relative to this."""
        return Path(self.source_path).parent if self.source_path else Path.cwd()

    def profile_path(self) -> Path:
        """The base profile file, absolute: a file relative to the study file, else a shipped profile's name.

        A name the command line takes for a shipped profile (``nceer_4dof``,
        ``profiles/eight_story.yaml``) names it here too, found by the same resolver
        (:func:`harness.paths.shipped_profile`); a file beside the study wins.
        """
        from harness.paths import shipped_profile

        beside = (self.base_dir / Path(self.profile).expanduser()).resolve()
        shipped = None if beside.is_file() else shipped_profile(self.profile, existing_wins=False)
        return beside if shipped is None else shipped.resolve()

    def overlay_path(self) -> Path | None:
        """The overlay file, absolute, or None."""
        return None if self.overlay is None else (self.base_dir / Path(self.overlay).expanduser()).resolve()

    def records_dir(self) -> Path | None:
        """``options.records_dir`` made absolute (relative to the study file), or None."""
        given = self.options.records_dir
        return None if given is None else (self.base_dir / Path(given).expanduser()).resolve()


def _refuse_shared_keys(set_axes: Mapping[str, Any], scale_axes: Mapping[str, Any], where: str) -> None:
    """Refuse a key that is both set and scaled: which would apply first is not obvious."""
    shared = sorted(set(set_axes) & set(scale_axes))
    if shared:
        raise ValueError(f"{where}: {shared[0]} is under both set and scale; expected it under one of them")


def read_study_data(path: Path) -> dict:
    """The YAML mapping of a study file.

    Raises
    ------
    ProfileError
        If the file is missing, too large, not UTF-8, not YAML, repeats a key, or is not a mapping.
    """
    source = str(path)
    if not path.is_file():
        raise ProfileError("study file not found; expected an existing YAML file (see profiles/studies/)", source)
    if path.stat().st_size > MAX_STUDY_BYTES:
        raise ProfileError(
            f"file is {path.stat().st_size} bytes; expected a study of at most {MAX_STUDY_BYTES} bytes (MAX_YAML_CHARS)", source
        )
    try:
        data = load_unique(path.read_bytes().decode("utf-8"))
    except UnicodeDecodeError as err:
        raise ProfileError(f"not UTF-8 text (byte {err.start}); expected a YAML study file", source) from err
    except DuplicateKeyError as err:
        raise ProfileError(err.describe(), source) from err
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        raise ProfileError(f"invalid YAML{where}: {getattr(err, 'problem', None) or err}", source) from err
    if not isinstance(data, dict):
        raise ProfileError(f"found {type(data).__name__}; expected a mapping with name, profile and axes", source)
    return data


def load_study(path: str | Path) -> Study:
    """Read and validate a study file.

    Parameters
    ----------
    path : str or Path
        The YAML file.

    Returns
    -------
    Study
        With ``source_path`` set to the absolute file name.

    Raises
    ------
    ProfileError
        Naming the file, the key path, what was found and what was expected.
    """
    file = Path(path).expanduser().resolve()
    try:
        study = build(Study, read_study_data(file), source=str(path))
    except ProfileError as err:
        if err.source:
            raise
        raise ProfileError(err.detail, str(path), err.key_path) from err  # a check that names its key itself
    return dataclasses.replace(study, source_path=str(file))
