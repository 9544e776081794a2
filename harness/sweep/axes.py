"""Parameter points of a study: its ``set`` and ``scale`` axes and Monte-Carlo samples as profile overrides.

A point is what a case changes in the base profile: ``KEY.PATH=VALUE`` overrides (values as
JSON, which is YAML, so ``--set`` reads them back exactly) and the input columns of its row.
Every value is checked on the base profile here, before anything runs, and a value the
profile refuses is refused as an error of the study file, at the axis's key:
``axes.set.bearing.mu_max[1]: found -0.1, expected a value >= 0 (bearing.mu_max of eight_story.yaml)``.
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.errors import ProfileError
from harness.profile import Profile
from harness.sweep.distributions import draw
from harness.sweep.resolve import BaseProfile, case_profile
from harness.sweep.study import Study

#: Input column of a scale axis: ``scale:KEY.PATH`` holds the factor.
SCALE_PREFIX = "scale:"
#: Input column of the Monte-Carlo sample number (-1 without Monte Carlo).
SAMPLE_COLUMN = "sample"


@dataclass(frozen=True)
class Point:
    """Overrides of one grid point or one sample, with the input columns they fill.

    Attributes
    ----------
    overrides : tuple of str
        ``KEY.PATH=VALUE`` items.
    inputs : tuple of (str, value)
        Column name and value: the SI value a ``set`` axis gives its key, the factor of a
        ``scale`` axis.
    """

    overrides: tuple[str, ...] = ()
    inputs: tuple[tuple[str, Any], ...] = ()

    def __add__(self, other: Point) -> Point:
        return Point(self.overrides + other.overrides, self.inputs + other.inputs)


def override(key: str, value: Any) -> str:
    """``KEY.PATH=VALUE`` with the value as JSON (floats written exactly: ``repr`` precision)."""
    return f"{key}={json.dumps(value, default=str)}"


def value_at(profile: Profile, key: str) -> Any:
    """The value of a profile at a dotted key path (``control.designs.FSF-I.delta``)."""
    node: Any = profile
    for part in key.split("."):
        node = node[part] if isinstance(node, Mapping) else getattr(node, part)
    return node


def column_value(value: Any) -> Any:
    """A value as a results column holds it: numbers and strings as they are, anything else as JSON."""
    if isinstance(value, bool) or value is None:
        return json.dumps(value)
    if isinstance(value, (int, float, str)):
        return value
    return json.dumps(value, default=str)


def scaled(base_value: Any, factor: float) -> float | list[float]:
    """``base_value`` times ``factor``: a number, or every element of a list of numbers.

    Raises
    ------
    ValueError
        If the value is not a number or a list of numbers.
    """
    if isinstance(base_value, (int, float)) and not isinstance(base_value, bool):
        return float(base_value) * factor
    if isinstance(base_value, (tuple, list)) and all(isinstance(v, (int, float)) for v in base_value):
        return [float(v) * factor for v in base_value]
    raise ValueError(f"found {base_value!r} there; expected a number or a list of numbers to scale")


def _label(profile_path: str, key: str) -> str:
    return f"{key} of {Path(profile_path).name}"


def _checked(base: BaseProfile, overrides: tuple[str, ...], study: Study, key_path: str, what: str) -> Profile:
    """The base profile with ``overrides``; a refusal becomes an error of the study file at ``key_path``."""
    try:
        return case_profile(base, overrides)
    except ProfileError as err:
        at = f" ({_label(base.path, err.key_path)})" if err.key_path else ""
        said = err.detail if err.detail.startswith("found") and what.startswith("found") else f"{what}: {err.detail}"
        raise ProfileError(f"{said}{at}", study.source_path, key_path) from err


def _set_axis(base: BaseProfile, study: Study, key: str, values: Sequence[Any]) -> list[Point]:
    """A ``set`` axis; a key of several key paths joined by commas sets each of them to the axis's value."""
    keys = tuple(part.strip() for part in key.split(","))
    points = []
    for i, value in enumerate(values):
        items = tuple(override(part, value) for part in keys)
        profile = _checked(base, items, study, f"axes.set.{key}[{i}]", f"found {value!r}")
        points.append(Point(items, tuple((part, column_value(value_at(profile, part))) for part in keys)))
    return points


def _scale_axis(base: BaseProfile, study: Study, key: str, factors: Sequence[float]) -> list[Point]:
    nominal = _nominal(base, study, key, f"axes.scale.{key}")
    points = []
    for i, factor in enumerate(factors):
        item = override(key, scaled(nominal, float(factor)))
        _checked(base, (item,), study, f"axes.scale.{key}[{i}]", f"factor {factor:g}")
        points.append(Point((item,), ((SCALE_PREFIX + key, float(factor)),)))
    return points


def _nominal(base: BaseProfile, study: Study, key: str, key_path: str) -> Any:
    """The base profile's value at ``key``, which a scale axis multiplies."""
    try:
        value = value_at(base.load(), key)
        scaled(value, 1.0)
    except (AttributeError, KeyError, TypeError) as err:
        raise ProfileError(f"the profile has no key {key}; expected a key path of the profile",
                           study.source_path, key_path) from err
    except ValueError as err:
        raise ProfileError(str(err), study.source_path, key_path) from err
    return value


def grid_points(study: Study, base: BaseProfile) -> list[Point]:
    """Every combination of the study's ``set`` and ``scale`` axes (one empty point without any)."""
    axes = [_set_axis(base, study, key, values) for key, values in study.axes.set.items()]
    axes += [_scale_axis(base, study, key, factors) for key, factors in study.axes.scale.items()]
    return [sum(combination, Point()) for combination in itertools.product(*axes)]


def sample_points(study: Study, base: BaseProfile) -> list[Point]:
    """The Monte-Carlo samples as points, each checked on the base profile (one empty point without them)."""
    mc = study.monte_carlo
    if mc is None:
        return [Point(inputs=((SAMPLE_COLUMN, -1),))]
    keys = mc.keys()
    distributions = [mc.set[key] if group == "set" else mc.scale[key] for group, key in keys]
    values = draw(distributions, mc.samples, mc.seed, mc.sampling)
    nominal = {key: _nominal(base, study, key, f"monte_carlo.scale.{key}") for group, key in keys if group == "scale"}
    points = []
    for i, row in enumerate(values):
        point = Point(inputs=((SAMPLE_COLUMN, i),)) + _sample(keys, row, nominal)
        _checked(base, point.overrides, study, "monte_carlo", f"sample {i} ({_describe(point.inputs[1:])})")
        points.append(point)
    return points


def _sample(keys: Iterable[tuple[str, str]], row: Sequence[float], nominal: Mapping[str, Any]) -> Point:
    overrides, inputs = [], []
    for (group, key), value in zip(keys, row, strict=True):
        value = float(value)
        if group == "set":
            overrides.append(override(key, value))
            inputs.append((key, value))
        else:
            overrides.append(override(key, scaled(nominal[key], value)))
            inputs.append((SCALE_PREFIX + key, value))
    return Point(tuple(overrides), tuple(inputs))


def _describe(inputs: Iterable[tuple[str, Any]]) -> str:
    return ", ".join(f"{name} = {value:.6g}" if isinstance(value, float) else f"{name} = {value}" for name, value in inputs)
