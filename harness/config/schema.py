"""Frozen, validated configuration objects built from plain YAML data.

Every section of a profile is a frozen dataclass whose fields say their type, unit
and range with :func:`quantity`. :func:`build` turns a mapping into such an object
and refuses, with the key path, what was found and what was expected:

- unknown keys (otherwise "your input is being ignored"), missing required keys;
- wrong types (a string where a number belongs, a bool where a number belongs);
- values out of range, NaN or infinity;
- numbers given with a unit of the wrong kind (``"3 kg"`` for a length).

A dataclass's own ``__post_init__`` may raise ``ValueError`` for checks that span
fields; the message is reported at that section's key path.
"""

from __future__ import annotations

import dataclasses
import math
import reprlib
import types
import typing
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Literal, TypeVar, Union, get_args, get_origin, get_type_hints

from harness.config.units import UnitError, parse_quantity
from harness.errors import ProfileError

if TYPE_CHECKING:
    from _typeshed import DataclassInstance

#: A configuration section: a dataclass.
T = TypeVar("T", bound="DataclassInstance")

_RANGE_KEYS = ("gt", "ge", "lt", "le")


def quantity(
    default: Any = dataclasses.MISSING,
    *,
    unit: str | None = None,
    gt: float | None = None,
    ge: float | None = None,
    lt: float | None = None,
    le: float | None = None,
    min_len: int | None = None,
    doc: str = "",
) -> Any:
    """Declare a dataclass field with a unit and a range.

    Parameters
    ----------
    default : optional
        Default value; a list or tuple default is stored as a tuple.
    unit : str, optional
        The unit the value is held in (and that the key names), e.g. ``"m"``.
        Strings such as ``"5 mm"`` in the YAML are converted to it.
    gt, ge, lt, le : float, optional
        Exclusive and inclusive bounds, applied to every element of a tuple.
    min_len : int, optional
        Least number of elements for a tuple field.
    doc : str
        One line for the profile reference.
    """
    metadata = {"unit": unit, "gt": gt, "ge": ge, "lt": lt, "le": le, "min_len": min_len, "doc": doc}
    if isinstance(default, (list, tuple)):
        frozen = tuple(default)
        return dataclasses.field(default_factory=lambda: frozen, metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


#: Longest quotation of a value in a message (characters).
DESCRIBE_CHARS = 60

#: Reprs of values for messages, bounded before they are built: a message quotes what was found,
#: and a value of a YAML file can be a list of lists that aliases make a billion strings long.
#: At most 3 levels, 4 items per list or mapping and 60 characters per string are looked at, so
#: a quotation costs the same whatever the value holds (at most 4^3 leaves).
_BOUNDED_REPR = reprlib.Repr()
_BOUNDED_REPR.maxlevel = 3
_BOUNDED_REPR.maxlist = _BOUNDED_REPR.maxtuple = _BOUNDED_REPR.maxdict = _BOUNDED_REPR.maxset = 4
_BOUNDED_REPR.maxstring = _BOUNDED_REPR.maxother = _BOUNDED_REPR.maxlong = DESCRIBE_CHARS


def _describe(value: Any) -> str:
    """``repr(value)`` cut to :data:`DESCRIBE_CHARS` characters, without building the whole of it.

    reprlib elides what lies beyond the bounds of :data:`_BOUNDED_REPR` ("..."), so the cost
    and the size of the text do not grow with the value.
    """
    text = _BOUNDED_REPR.repr(value)
    return text if len(text) <= DESCRIBE_CHARS else text[: DESCRIBE_CHARS - 3] + "..."


def _expected_range(meta: Mapping[str, Any], unit: str | None) -> str:
    parts = []
    symbols = {"gt": ">", "ge": ">=", "lt": "<", "le": "<="}
    for key in _RANGE_KEYS:
        if meta.get(key) is not None:
            parts.append(f"{symbols[key]} {meta[key]:g}")
    suffix = f" {unit}" if unit and unit != "1" else ""  # "1": a ratio, which has no unit to name ("<= 1", not "<= 1 1")
    return " and ".join(parts) + suffix


def _expected_value(tp: Any, meta: Mapping[str, Any]) -> str:
    """Words for what a field takes, for 'missing key' messages."""
    doc = meta.get("doc")
    unit = meta.get("unit")
    kind = getattr(tp, "__name__", str(tp).replace("typing.", ""))
    text = f"{kind}" + (f" in {unit}" if unit and unit != "1" else "")
    return f"{text} ({doc})" if doc else text


def _check_range(value: float, meta: Mapping[str, Any], path: str, source: str | None) -> None:
    if not math.isfinite(value):
        raise ProfileError(f"found {value!r}, expected a finite number", source, path)
    bad = (
        (meta.get("gt") is not None and not value > meta["gt"])
        or (meta.get("ge") is not None and not value >= meta["ge"])
        or (meta.get("lt") is not None and not value < meta["lt"])
        or (meta.get("le") is not None and not value <= meta["le"])
    )
    if bad:
        expected = _expected_range(meta, meta.get("unit"))
        raise ProfileError(f"found {value:g}, expected a value {expected}", source, path)


def _to_float(value: Any, meta: Mapping[str, Any], path: str, source: str | None) -> float:
    unit = meta.get("unit")
    if isinstance(value, bool) or value is None:
        raise ProfileError(f"found {_describe(value)}, expected a number" + (f" in {unit}" if unit else ""), source, path)
    if isinstance(value, (int, float)):
        result = float(value)
    elif isinstance(value, str):
        try:
            result = parse_quantity(value, unit or "1")
        except UnitError as err:
            raise ProfileError(f"found {_describe(value)}: {err}", source, path) from err
    else:
        raise ProfileError(f"found {type(value).__name__} {_describe(value)}, expected a number", source, path)
    _check_range(result, meta, path, source)
    return result


def _build_value(tp: Any, value: Any, meta: Mapping[str, Any], path: str, source: str | None) -> Any:
    origin = get_origin(tp)
    if tp is Any:
        return value
    if origin in (Union, types.UnionType):
        return _build_union(tp, value, meta, path, source)
    if origin is Literal:
        choices = get_args(tp)
        if value not in choices:
            raise ProfileError(f"found {_describe(value)}, expected one of {', '.join(map(repr, choices))}", source, path)
        return value
    if tp is float:
        return _to_float(value, meta, path, source)
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ProfileError(f"found {_describe(value)}, expected a whole number", source, path)
        _check_range(float(value), meta, path, source)
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ProfileError(f"found {_describe(value)}, expected true or false", source, path)
        return value
    if tp is str:
        if not isinstance(value, str):
            raise ProfileError(f"found {_describe(value)}, expected a string", source, path)
        return value
    if origin is tuple:
        return _build_tuple(tp, value, meta, path, source)
    if origin in (dict, Mapping, typing.Mapping):
        return _build_mapping(tp, value, path, source)
    if isinstance(tp, type) and dataclasses.is_dataclass(tp):
        return build(tp, value, source=source, path=path)
    raise TypeError(f"schema type {tp!r} at {path} is not supported")


def _build_union(tp: Any, value: Any, meta: Mapping[str, Any], path: str, source: str | None) -> Any:
    options = [arg for arg in get_args(tp) if arg is not type(None)]
    if value is None:
        if type(None) in get_args(tp):
            return None
        raise ProfileError("found nothing (null), expected a value", source, path)
    classes = [opt for opt in options if isinstance(opt, type) and dataclasses.is_dataclass(opt)]
    if classes and isinstance(value, Mapping) and len(classes) > 1:
        kinds = {get_args(get_type_hints(c)["kind"])[0]: c for c in classes}
        kind = value.get("kind")
        if kind not in kinds:
            raise ProfileError(f"found kind {_describe(kind)}, expected kind one of {', '.join(map(repr, kinds))}", source, path)
        return build(kinds[kind], value, source=source, path=path)
    errors: list[ProfileError] = []
    for option in options:
        try:
            return _build_value(option, value, meta, path, source)
        except ProfileError as err:
            errors.append(err)
    expected = [err.detail.split("expected ", 1)[1] for err in errors if "expected " in err.detail]
    if len(expected) == len(errors) > 1 and not classes:  # a scalar of either kind: say both, e.g. 0..99 or 'auto'
        raise ProfileError(f"found {_describe(value)}, expected {' or '.join(expected)}", source, path)
    raise errors[-1]


def _build_tuple(tp: Any, value: Any, meta: Mapping[str, Any], path: str, source: str | None) -> tuple:
    if not isinstance(value, (list, tuple)):
        raise ProfileError(f"found {_describe(value)}, expected a list", source, path)
    args = get_args(tp)
    if len(args) == 2 and args[1] is Ellipsis:
        element_types = [args[0]] * len(value)
    else:
        if len(value) != len(args):
            raise ProfileError(f"found {len(value)} values, expected {len(args)}", source, path)
        element_types = list(args)
    min_len = meta.get("min_len")
    if min_len is not None and len(value) < min_len:
        raise ProfileError(f"found {len(value)} values, expected at least {min_len}", source, path)
    return tuple(
        _build_value(et, v, meta, f"{path}[{i}]", source) for i, (et, v) in enumerate(zip(element_types, value, strict=True))
    )


def _build_mapping(tp: Any, value: Any, path: str, source: str | None) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise ProfileError(f"found {_describe(value)}, expected a mapping of names", source, path)
    key_type, value_type = get_args(tp)
    result = {}
    for key, item in value.items():
        if not isinstance(key, str):
            raise ProfileError(f"found key {_describe(key)}, expected a name (string)", source, path)
        result[key] = _build_value(value_type, item, {}, f"{path}.{key}" if path else key, source)
    return types.MappingProxyType(result)


def build(cls: type[T], data: Any, *, source: str | None = None, path: str = "") -> T:
    """Build the frozen dataclass ``cls`` from ``data``, validating everything.

    Parameters
    ----------
    cls : type
        A dataclass whose fields are declared with :func:`quantity` or plain defaults.
    data : mapping
        Parsed YAML. ``None`` is treated as an empty mapping.
    source : str, optional
        File name for messages.
    path : str
        Key path of ``data`` inside the file, for messages.

    Raises
    ------
    ProfileError
        Naming the file, the key path, what was found and what was expected.
    """
    if data is None:
        data = {}
    if not isinstance(data, Mapping):
        raise ProfileError(f"found {_describe(data)}, expected a mapping (key: value lines)", source, path or None)
    hints = get_type_hints(cls)
    fields = {f.name: f for f in dataclasses.fields(cls) if f.init and not f.metadata.get("internal")}
    unknown = [k for k in data if k not in fields]
    if unknown:
        key = unknown[0]
        close = [name for name in fields if name.split("_")[0] == str(key).split("_")[0]]
        hint = f" (did you mean {', '.join(close)}?)" if close else ""
        raise ProfileError(
            f"unknown key {key!r}{hint}; expected one of: {', '.join(fields)}",
            source,
            f"{path}.{key}" if path else str(key),
        )
    kwargs = {}
    for name, field in fields.items():
        key_path = f"{path}.{name}" if path else name
        if name in data:
            kwargs[name] = _build_value(hints[name], data[name], field.metadata, key_path, source)
        elif field.default is dataclasses.MISSING and field.default_factory is dataclasses.MISSING:
            raise ProfileError(f"missing required key; expected {_expected_value(hints[name], field.metadata)}", source, key_path)
    try:
        return cls(**kwargs)
    except ProfileError:
        raise
    except (ValueError, TypeError) as err:
        raise ProfileError(str(err), source, path or None) from err


def internal(default: Any = None, doc: str = "") -> Any:
    """Declare a field that the loader fills in and a YAML file may not set."""
    return dataclasses.field(default=default, metadata={"internal": True, "doc": doc})


def to_data(obj: Any) -> Any:
    """Turn a built configuration object back into plain YAML-ready data (SI values)."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {
            f.name: to_data(getattr(obj, f.name))
            for f in dataclasses.fields(obj)
            if not f.metadata.get("internal")
        }
    if isinstance(obj, Mapping):
        return {k: to_data(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_data(v) for v in obj]
    return obj
