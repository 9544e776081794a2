"""The cases of a study: records x PGA levels x controllers x grid points x Monte-Carlo samples.

Each case is keyed by a hash of its resolved inputs: the base profile as resolved (SI values,
variant and the study's ``set`` applied), the record file's content, the PGA, the controller,
the case's overrides and the options. Two studies that share a case share its key, so a rerun,
or a study extended by more levels or samples, skips the cases already in the results.
"""

from __future__ import annotations

import hashlib
import itertools
import json
from dataclasses import dataclass
from typing import Any

from harness.errors import ProfileError
from harness.profile import Profile
from harness.sweep.axes import Point, grid_points, sample_points
from harness.sweep.records import StudyRecord, checked_records, count_records
from harness.sweep.resolve import BaseProfile
from harness.sweep.study import MAX_CASES, Study

#: Bump when what a key stands for changes (the results of old keys are then simulated again).
KEY_VERSION = 1
#: Controller name of a passive-only case (as ``harness simulate --controller none``).
NO_CONTROLLER = "none"


@dataclass(frozen=True)
class CaseSpec:
    """One case: everything a worker needs to simulate it, in plain values.

    Attributes
    ----------
    index : int
        Position in the study's expansion.
    key : str
        Hash of the resolved inputs (hex, 20 characters).
    record : StudyRecord
    pga_g : float or None
        Target PGA (g); None keeps the profile's.
    controller : str
        A design of the profile, or ``"none"``.
    overrides : tuple of str
        ``KEY.PATH=VALUE`` items over the base profile.
    inputs : tuple of (str, value)
        Input columns of the row besides record, PGA and controller (axes, sample, factors).
    options : tuple of (str, value)
        The options every case shares (``StudyOptions`` fields: duration, time scale, ...).
    """

    index: int
    key: str
    record: StudyRecord
    pga_g: float | None
    controller: str
    overrides: tuple[str, ...]
    inputs: tuple[tuple[str, Any], ...]
    options: tuple[tuple[str, Any], ...]

    def study_options(self) -> dict[str, Any]:
        """Keyword arguments of ``harness.runs.options.StudyOptions`` for this case."""
        return {**dict(self.options), "record": self.record.source, "pga_g": self.pga_g, "controller": self.controller}

    def input_columns(self) -> dict[str, Any]:
        """The case's inputs as row columns."""
        return {
            "case_id": self.key, "case_index": self.index, "record": self.record.label,
            "pga_g": float("nan") if self.pga_g is None else self.pga_g, "controller": self.controller,
            **dict(self.inputs),
        }

    def simulate_argv(self, base: BaseProfile) -> list[str]:
        """The ``harness simulate`` arguments that run this very case (for checks and for ``--case``)."""
        argv = ["simulate", base.path, "--record", self.record.source, "--controller", self.controller]
        if base.variant:
            argv += ["--variant", base.variant]
        if base.overlay:
            argv += ["--overlay", base.overlay]
        if self.pga_g is not None:
            argv += ["--pga", repr(self.pga_g)]
        flags = {"duration_s": "--duration", "time_scale": "--time-scale", "rate_hz": "--rate",
                 "friction": "--friction", "transport_delay_s": "--delay"}
        for name, value in self.options:
            argv += ["--rig-effects"] if name == "rig_effects" else [flags[name], str(value)]
        for item in (*base.overrides, *self.overrides):
            argv += ["--set", item]
        return argv


def options_of(study: Study) -> tuple[tuple[str, Any], ...]:
    """The study's shared options that are given, as (``StudyOptions`` field, value)."""
    given = {
        "duration_s": study.options.duration_s, "time_scale": study.options.time_scale, "rate_hz": study.options.rate_hz,
        "friction": study.options.friction, "transport_delay_s": study.options.transport_delay_s,
        "rig_effects": study.options.rig_effects or None,  # false is the default: the same cases as leaving it out
    }
    return tuple((name, value) for name, value in given.items() if value is not None)


def profile_digest(profile: Profile) -> str:
    """SHA-256 of the resolved profile's values (where it was loaded from left out)."""
    data = profile.resolved_data()
    data.pop("loaded_from", None)
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=str).encode()).hexdigest()


def case_key(profile_sha: str, record: StudyRecord, pga_g: float | None, controller: str, point: Point,
             options: tuple[tuple[str, Any], ...]) -> str:
    """The hash of a case's resolved inputs (20 hex characters: 80 bits)."""
    inputs = {
        "version": KEY_VERSION, "profile": profile_sha, "record": record.digest, "pga_g": pga_g,
        "controller": controller, "overrides": sorted(point.overrides), "options": dict(options),
    }
    return hashlib.sha256(json.dumps(inputs, sort_keys=True).encode()).hexdigest()[:20]


@dataclass(frozen=True)
class CaseCount:
    """How many cases a study has, from its axes alone: each factor, and their product."""

    records: int
    pga_levels: int
    controllers: int
    grid_points: int
    samples: int

    @property
    def total(self) -> int:
        """Cases of the study: the product of the factors."""
        return self.records * self.pga_levels * self.controllers * self.grid_points * self.samples

    def describe(self) -> str:
        """The factors in words, e.g. ``3 records x 4 PGA levels x 2 controllers x 1 grid point x 8 samples``."""
        factors = ((self.records, "record"), (self.pga_levels, "PGA level"), (self.controllers, "controller"),
                   (self.grid_points, "grid point"), (self.samples, "sample"))
        return " x ".join(f"{count} {name}{'' if count == 1 else 's'}" for count, name in factors)


def case_count(study: Study) -> CaseCount:
    """Count the study's cases from its axes, without building them, and refuse more than :data:`MAX_CASES`.

    Nothing is loaded or checked but the folders of the ``records`` axis (their record files are
    counted); an axis left out counts one (the profile's record, PGA or controller).

    Raises
    ------
    ProfileError
        At ``axes``, with the count, its factors and the limit.
    """
    axes = study.axes
    pga_levels = axes.pga_list()
    grid = 1
    for values in (*axes.set.values(), *axes.scale.values()):
        grid *= len(values)
    count = CaseCount(
        records=1 if axes.records is None else count_records(axes.records, study.base_dir),
        pga_levels=1 if pga_levels is None else len(pga_levels),
        controllers=1 if axes.controllers is None else len(axes.controllers),
        grid_points=grid,
        samples=1 if study.monte_carlo is None else study.monte_carlo.samples,
    )
    if count.total > MAX_CASES:
        raise ProfileError(
            f"the study has {count.total} cases ({count.describe()}), expected at most {MAX_CASES} (MAX_CASES): "
            "split it into studies of fewer levels, values or samples (a study extended later runs only its new cases)",
            study.source_path, "axes",
        )
    return count


def _controllers(study: Study, profile: Profile) -> tuple[str, ...]:
    names = study.axes.controllers or (profile.control.controller,)
    for i, name in enumerate(names):
        if name != NO_CONTROLLER and name not in profile.control.designs:
            known = ", ".join(profile.control.designs)
            raise ProfileError(f"found {name!r}, expected a design of the profile ({known}) or 'none'",
                               study.source_path, f"axes.controllers[{i}]")
    return names


def _records(study: Study, profile: Profile) -> list[StudyRecord]:
    from harness.motions.catalog import records_dir_from

    records_dir = records_dir_from(study.records_dir(), profile.record.records_dir, base_dir=profile.base_dir)
    unit = profile.record.accel_unit
    if study.axes.records is None:
        return checked_records((profile.record.name,), profile.base_dir, records_dir, study.source_path, "axes.records",
                               unit)
    return checked_records(study.axes.records, study.base_dir, records_dir, study.source_path, "axes.records", unit)


def base_of(study: Study) -> BaseProfile:
    """Where the study's base profile comes from."""
    overlay = study.overlay_path()
    return BaseProfile(str(study.profile_path()), study.variant, tuple(study.set), None if overlay is None else str(overlay))


def expand(study: Study) -> list[CaseSpec]:
    """Every case of the study, each input checked on the base profile first.

    Raises
    ------
    ProfileError
        For more than :data:`MAX_CASES` cases (:func:`case_count`, before anything is built), and
        for the study file's first refused value: its key, what was found and what was expected.
    """
    case_count(study)
    base = base_of(study)
    try:
        profile = base.load()
    except ProfileError as err:
        raise ProfileError(f"the profile is refused: {err}", study.source_path, "profile" if not study.set else "set") from err
    records, controllers = _records(study, profile), _controllers(study, profile)
    pgas: tuple[float | None, ...] = study.axes.pga_list() or (profile.record.pga_g,)
    points = [grid + sample for grid, sample in itertools.product(grid_points(study, base), sample_points(study, base))]
    options, sha = options_of(study), profile_digest(profile)
    cases: list[CaseSpec] = []
    for record, pga_g, controller, point in itertools.product(records, pgas, controllers, points):
        key = case_key(sha, record, pga_g, controller, point, options)
        cases.append(CaseSpec(len(cases), key, record, pga_g, controller, point.overrides, point.inputs, options))
    _refuse_repeats(cases, study)
    return cases


def _refuse_repeats(cases: list[CaseSpec], study: Study) -> None:
    """Refuse two cases with the same inputs (a value repeated on an axis): one row could not tell them apart."""
    seen: dict[str, CaseSpec] = {}
    for case in cases:
        if case.key in seen:
            first = seen[case.key]
            raise ProfileError(
                f"cases {first.index} and {case.index} have the same inputs ({case.record.label}, {case.controller}, "
                f"{', '.join(case.overrides) or 'no overrides'}); expected each value once per axis", study.source_path, "axes",
            )
        seen[case.key] = case
