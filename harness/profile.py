"""Profiles: YAML files loaded into frozen, validated objects.

A profile describes a rig or a study: the building, the bearings, the record, the
table's limits, the controllers, and (for rigs) the CAN bus, the virtual rig, the
safety limits and the loop. Rules:

- unknown keys are errors; every physical quantity is SI or names its unit in its key,
  and a value may carry its own unit as a string (``"0.012 cm"``), converted on load;
- ``extends: other.yaml`` (path relative to this file) starts from another profile and
  overrides it key by key (mappings merge, everything else replaces), so an
  experiment profile can name its rig profile;
- ``variants: {name: {...overrides...}}`` are named overlays chosen with ``--variant``;
  every variant is validated on load;
- ``--set KEY.PATH=VALUE`` overrides go last, over a variant too. Safety settings they make
  weaker than the profile's own (file, extends, variant) are listed in
  ``Profile.safety_weakened`` (:mod:`harness.safety.weakening`); the command line refuses them
  without ``--allow-weaker-safety``;
- ``safety.force.max_force_N`` may not exceed what the DBC's ACTUATOR_CMD ``force`` signal
  carries, ``rig.actuator.force_limit_N``, or ``safety.force.actuator_rating_N`` when given,
  whatever the flag.

Any problem raises :class:`~harness.errors.ProfileError` naming the file, the key path,
what was found and what was expected.
"""

from __future__ import annotations

import copy
import dataclasses
import functools
import hashlib
import stat
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from harness.canbus.config import CanConfig
from harness.config.schema import build, internal, quantity, to_data
from harness.config.yamlload import MAX_YAML_CHARS, DuplicateKeyError, load_unique
from harness.control.config import ControlConfig, SimulationConfig
from harness.errors import ProfileError
from harness.loop.config import LoopConfig
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.motions import RecordConfig, TableLimits
from harness.paths import PROFILE_DIR
from harness.rig.config import RigConfig
from harness.rig.truth import RigTruth, resolve_truth
from harness.safety.config import SafetyConfig, check_config
from harness.safety.weakening import Weakening, weakenings

DEFAULT_PROFILE = PROFILE_DIR / "nceer_4dof.yaml"


@dataclass(frozen=True)
class Profile:
    """A whole validated profile."""

    name: str = quantity(doc="short name used in run-folder names")
    structure: BuildingConfig = quantity(doc="the building (SPEC 1)")
    bearing: BearingConfig = quantity(doc="the friction bearings (SPEC 2)")
    control: ControlConfig = quantity(doc="controller designs and sampling (SPEC 3)")
    description: str = ""
    record: RecordConfig = dataclasses.field(default_factory=RecordConfig)
    table: TableLimits | None = None
    simulation: SimulationConfig = dataclasses.field(default_factory=SimulationConfig)
    can: CanConfig = dataclasses.field(default_factory=CanConfig)
    safety: SafetyConfig = dataclasses.field(default_factory=SafetyConfig)
    loop: LoopConfig = dataclasses.field(default_factory=LoopConfig)
    rig: RigConfig = dataclasses.field(default_factory=RigConfig)
    variants: Mapping[str, Any] = dataclasses.field(default_factory=dict)
    source_path: str = internal("", "the file this profile was loaded from")
    variant: str = internal("", "the variant applied, if any")
    overlay_path: str = internal("", "the overlay file merged over the profile (--overlay), if any")
    overlay_sha256: str = internal("", "the SHA-256 of that file's bytes")
    safety_weakened: tuple[Weakening, ...] = internal(
        (), "safety settings --overlay or --set made weaker than the profile's own (harness/safety/weakening.py)"
    )

    def __post_init__(self) -> None:
        problems = check_config(self.safety)
        if problems:
            raise ValueError("inconsistent safety limits: " + "; ".join(problems))
        if self.can.loop_rate_hz != self.control.rate_hz:
            # The one rate (control.rate_hz) reaches the CAN section here, at every construction and
            # replace, so the command's and the sensors' rates cannot disagree with the loop's.
            object.__setattr__(self, "can", dataclasses.replace(self.can, loop_rate_hz=self.control.rate_hz))
        panel_period_s = 1.0 / self.can.estop_panel_rate_hz
        if self.safety.estop.panel_required and self.safety.estop.max_panel_age_s < 2.0 * panel_period_s:
            raise ValueError(
                f"safety.estop.max_panel_age_s ({self.safety.estop.max_panel_age_s:g} s) is shorter than two periods of "
                f"the panel heartbeat, 2 / can.estop_panel_rate_hz = {2.0 * panel_period_s:g} s: a healthy panel would "
                "trip estop_lost (docs/SAFETY.md, E-stop panel liveness)"
            )

    @property
    def base_dir(self) -> Path:
        """Directory of the profile file (relative paths in it are relative to this)."""
        return Path(self.source_path).parent if self.source_path else Path.cwd()

    def can_settings(self, interface: str | None = None, channel: str | None = None) -> CanConfig:
        """The ``can`` section with the command line's interface and channel (the rates follow ``control.rate_hz``)."""
        changes: dict = {key: value for key, value in (("interface", interface), ("channel", channel)) if value}
        return dataclasses.replace(self.can, **changes) if changes else self.can

    def rig_truth(self) -> RigTruth:
        """The virtual rig's true building and bearing (``rig.truth`` over the top-level sections) and how they differ.

        Only the virtual rig, its offline twin and their passive references use these; the
        controller, the friction estimator and the supervisor use ``structure`` and
        ``bearing`` (:mod:`harness.rig.truth`).
        """
        return resolve_truth(self.structure, self.bearing, self.rig.truth, self.rig.actuator.hydraulics)

    def resolved_data(self) -> dict:
        """The fully resolved profile as plain data (SI), for run folders and the rig process."""
        data = to_data(self)
        data.pop("variants", None)
        data["loaded_from"] = self.source_path
        if self.variant:
            data["variant"] = self.variant
        if self.overlay_path:
            data["overlay"] = self.overlay_record()
        return data

    def overlay_record(self) -> dict[str, str] | None:
        """The overlay for metadata.json: its file and SHA-256 (None without one)."""
        return {"path": self.overlay_path, "sha256": self.overlay_sha256} if self.overlay_path else None

    @classmethod
    def from_resolved(cls, data: Mapping[str, Any]) -> Profile:
        """The profile :meth:`resolved_data` wrote, validated again (``harness dry-run`` hands it to its rig).

        The safety acknowledgement is not carried: the command that resolved the profile
        has checked it already.
        """
        data = dict(data)
        source = str(data.pop("loaded_from", ""))
        variant = str(data.pop("variant", ""))
        overlay = data.pop("overlay", None) or {}
        data = _without_former_rate_keys(data, f"{source} (resolved)")
        profile = _build_checked(data, f"{source} (resolved)")
        return dataclasses.replace(profile, source_path=source, variant=variant,
                                   overlay_path=str(overlay.get("path", "")), overlay_sha256=str(overlay.get("sha256", "")))


def _file_kind(path: Path) -> str:
    """What ``path`` is when it is no regular file: "a directory", "a character device" ..., or "" if it does not exist."""
    try:
        mode = path.stat().st_mode
    except OSError:
        return ""
    kinds = ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
             (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"))
    return next((name for test, name in kinds if test(mode)), "not a regular file")


def _read_yaml(path: Path, what: str = "profile") -> dict:
    """The mapping of the YAML file ``path``, a ``what`` ("profile" or "overlay"); refused with a ProfileError naming it."""
    source = str(path)
    if not path.is_file():
        kind = _file_kind(path)
        state = f"is {kind}, not a file" if kind else f"{what} file not found"
        shipped = ""
        if what == "profile":
            shipped = " (shipped profiles: " + ", ".join(sorted(p.name for p in PROFILE_DIR.glob("*.yaml"))) + ")"
        raise ProfileError(f"{state}; expected an existing YAML file{shipped}", source)
    try:
        size = path.stat().st_size
        if size > MAX_YAML_CHARS:
            raise ProfileError(f"file is {size} bytes; expected a profile of at most {MAX_YAML_CHARS} bytes (MAX_YAML_CHARS)",
                               source)
        raw = path.read_bytes()
    except OSError as err:
        raise ProfileError(f"cannot read it ({err.strerror or err}); expected a readable YAML file", source) from err
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        raise ProfileError(f"not UTF-8 text (byte {err.start}); expected a YAML profile", source) from err
    try:
        data = load_unique(text)
    except DuplicateKeyError as err:
        raise ProfileError(err.describe(), source) from err
    except yaml.YAMLError as err:
        mark = getattr(err, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(err, "problem", None) or str(err).splitlines()[0]
        raise ProfileError(f"invalid YAML{where}: {problem}", source) from err
    if data is None:
        raise ProfileError("the file is empty; expected a profile mapping with name, structure, bearing, control", source)
    if not isinstance(data, dict):
        raise ProfileError(f"found a {type(data).__name__} at the top level; expected a mapping of sections", source)
    return data


def merge(base: Mapping, override: Mapping) -> dict:
    """Deep-merge ``override`` into a copy of ``base``: mappings merge, other values replace."""
    result = copy.deepcopy(dict(base))
    for key, value in override.items():
        if isinstance(value, Mapping) and isinstance(result.get(key), Mapping):
            result[key] = merge(result[key], value)
        else:
            result[key] = copy.deepcopy(value)
    return result


def _resolve_extends(path: Path, seen: tuple[Path, ...] = ()) -> dict:
    path = path.resolve()
    if path in seen:
        chain = " -> ".join(p.name for p in (*seen, path))
        raise ProfileError(f"profiles extend each other in a loop: {chain}", str(path))
    data = _read_yaml(path)
    parent = data.pop("extends", None)
    if parent is None:
        return data
    if not isinstance(parent, str):
        raise ProfileError(f"found {parent!r}; expected the path of another profile", str(path), "extends")
    return merge(_resolve_extends(path.parent / parent, (*seen, path)), data)


def _apply_variant(data: dict, variant: str, source: str) -> dict:
    variants = data.get("variants") or {}
    if not isinstance(variants, Mapping):
        raise ProfileError("expected a mapping of variant names to overrides", source, "variants")
    if variant not in variants:
        known = ", ".join(variants) or "none"
        raise ProfileError(f"unknown variant {variant!r}; this profile has: {known}", source, "variants")
    overlay = variants[variant]
    if not isinstance(overlay, Mapping):
        raise ProfileError("expected a mapping of overrides", source, f"variants.{variant}")
    return merge(data, overlay)


def parse_overrides(items: list[str] | tuple[str, ...]) -> dict:
    """``["safety.stroke.hard_limit_m=0.02", ...]`` -> a nested mapping (values parsed as YAML).

    Raises
    ------
    ProfileError
        For an item without ``=`` or with an empty key, a value that is not valid YAML or
        repeats a key inside it, and a key set twice (or set and also set inside, as
        ``safety.stroke=...`` with ``safety.stroke.hard_limit_m=...``): the later one would
        silently replace the earlier.
    """
    result: dict = {}
    given: dict[tuple[str, ...], str] = {}
    for item in items:
        key, sep, text = item.partition("=")
        if not sep or not key.strip() or any(not part.strip() for part in key.strip().split(".")):
            raise ProfileError(f"override {_shown(item)}: expected KEY.PATH=VALUE, e.g. safety.stroke.hard_limit_m=0.02", "--set")
        try:
            value = load_unique(text) if text.strip() else ""
        except DuplicateKeyError as err:
            raise ProfileError(f"override {_shown(item)}: in the value, {err.describe()}", "--set") from err
        except yaml.YAMLError as err:
            problem = getattr(err, "problem", None) or str(err).splitlines()[0]
            hint = "; expected a list as [v1, v2, ...], e.g. [0.6e6, 2.1e6, 1.5e6]" if text.lstrip().startswith("[") else ""
            raise ProfileError(f"override {_shown(item)}: the value is not valid YAML ({problem}){hint}", "--set") from err
        parts = tuple(part.strip() for part in key.strip().split("."))
        clash = next((earlier for path, earlier in given.items() if _overlaps(path, parts)), None)
        if clash is not None:
            raise ProfileError(
                f"override {_shown(item)} sets {'.'.join(parts)} again after {_shown(clash)}; expected each key once "
                "(the later value would silently replace the earlier)", "--set",
            )
        given[parts] = item
        node = result
        for part in parts[:-1]:
            node = node.setdefault(part, {})
        node[parts[-1]] = value
    return result


def _shown(item: str) -> str:
    """An override as a message quotes it: ``repr``, cut to 80 characters before it is built (a value may be megabytes)."""
    return repr(item) if len(item) <= 80 else repr(item[:77]) + "..."


def _overlaps(a: tuple[str, ...], b: tuple[str, ...]) -> bool:
    """True if one key path is the other or lies inside it."""
    n = min(len(a), len(b))
    return a[:n] == b[:n]


def load_profile(
    path: str | Path | None = None, variant: str | None = None, overrides: list[str] | tuple[str, ...] = (),
    overlay: str | Path | None = None,
) -> Profile:
    """Load, merge and validate a profile.

    Parameters
    ----------
    path : str or Path, optional
        The YAML file; default ``profiles/nceer_4dof.yaml``.
    variant : str, optional
        Name of an entry of ``variants`` to apply.
    overrides : sequence of str
        ``KEY.PATH=VALUE`` items applied last, over the variant and the overlay too (the command
        line's ``--set``); validated like the file.
    overlay : str or Path, optional
        A YAML file with the same keys as a profile (e.g. the ``identified.yaml`` of ``harness
        identify``), merged over the profile after the variant and before ``overrides`` (the
        command line's ``--overlay``); validated like the file.

    Returns
    -------
    Profile
        With ``safety_weakened``: the safety settings the overlay and the overrides made weaker
        than the profile's own values (file, extends and variant), for the caller to refuse or
        record; and the overlay's path and SHA-256.

    Raises
    ------
    ProfileError
        For anything invalid, including a ``safety.force.max_force_N`` beyond the DBC's
        ACTUATOR_CMD force range or an actuator rating.
    ProtocolError
        If the DBC (``can.dbc_path``) cannot be read.
    """
    file = Path(path) if path is not None else DEFAULT_PROFILE
    source = str(file)
    data = _resolve_extends(file)
    layer, overlay_sha256 = _read_overlay(Path(overlay)) if overlay is not None else ({}, "")
    on_top = merge(layer, parse_overrides(overrides)) if overrides else layer
    own = _own_safety(data, variant, source) if on_top else None
    if overlay is not None:
        source = f"{source} (with --overlay {overlay})"
    if overrides:
        source = f"{source} (with --set {' '.join(overrides)})"
    profile = _build_checked(merge(data, on_top), source)
    for name in profile.variants:  # every variant must give a valid profile
        if name != variant:
            _build_checked(merge(_apply_variant(data, name, source), on_top), f"{source} (variant {name})")
    if variant:  # the overlay and --set go over the variant
        profile = _build_checked(merge(_apply_variant(data, variant, source), on_top), f"{source} (variant {variant})")
    weakened = weakenings(own, profile.safety) if own is not None else ()
    return dataclasses.replace(
        profile, source_path=str(file.resolve()), variant=variant or "", safety_weakened=weakened,
        overlay_path=str(Path(overlay).resolve()) if overlay is not None else "", overlay_sha256=overlay_sha256,
    )


def _read_overlay(path: Path) -> tuple[dict, str]:
    """An overlay's keys and the SHA-256 of its bytes; refuses what only a profile may hold."""
    data = _read_yaml(path, "overlay")
    for key in ("extends", "variants"):
        if key in data:
            raise ProfileError(f"an overlay holds values only; expected no {key!r} (put it in the profile)", str(path), key)
    return data, hashlib.sha256(path.read_bytes()).hexdigest()


def _own_safety(data: dict, variant: str | None, source: str) -> SafetyConfig:
    """The profile's own safety section: its file (with what it extends) and the variant, before ``--set``.

    A variant is written in the profile's file, so it is the profile's own choice; only the
    command line's ``--set`` is compared with this (:mod:`harness.safety.weakening`).
    """
    chosen = _apply_variant(data, variant, source) if variant else data
    return build(SafetyConfig, chosen.get("safety"), source=source, path="safety")


#: Keys that held copies of the loop rate before ``control.rate_hz`` became the one source (a run
#: folder recorded before then carries them in its resolved profile).
FORMER_RATE_KEYS = (("loop", "rate_hz"), ("can", "command_rate_hz"))


def _refuse_former_rate_keys(data: Mapping[str, Any], source: str) -> None:
    """Refuse ``loop.rate_hz`` and ``can.command_rate_hz`` in a profile with what to write instead."""
    for section, key in FORMER_RATE_KEYS:
        if isinstance(data.get(section), Mapping) and key in data[section]:
            raise ProfileError(
                f"{section}.{key} is no longer a key: the profile has one rate, control.rate_hz, at which the "
                "controller samples, the loop ticks and the actuator command goes; remove this key and set "
                "control.rate_hz (or pass --rate)", source, f"{section}.{key}",
            )


def _without_former_rate_keys(data: dict, source: str) -> dict:
    """A recorded run's resolved profile without the rate copies it may carry (they had to agree with ``control.rate_hz``).

    A sensor rate equal to the loop's becomes none (once per tick), as the profile now says it.
    A copy that disagrees is refused: no profile could have been recorded with it.
    """
    rate_hz = (data.get("control") or {}).get("rate_hz")
    data = dict(data)
    for section, key in FORMER_RATE_KEYS:
        part = data.get(section)
        if not isinstance(part, Mapping) or key not in part:
            continue
        if part[key] != rate_hz:
            raise ProfileError(f"found {part[key]!r} Hz, expected control.rate_hz ({rate_hz!r} Hz), which it copied",
                               source, f"{section}.{key}")
        data[section] = {name: value for name, value in part.items() if name != key}
        if section == "can" and data[section].get("sensor_rate_hz") == rate_hz:
            data[section]["sensor_rate_hz"] = None
    return data


def _build_checked(data: dict, source: str) -> Profile:
    """Build a profile; refuse a ``rig.truth`` that makes an invalid building or bearing, and a force
    limit its protocol or its actuator cannot carry."""
    _refuse_former_rate_keys(data, source)
    profile = build(Profile, data, source=source)
    try:
        profile.rig_truth()
    except ProfileError as err:
        raise ProfileError(err.detail, source, err.key_path) from err
    max_force_N = profile.safety.force.max_force_N
    for ceiling_N, what in _force_ceilings(profile):
        if max_force_N > ceiling_N:
            raise ProfileError(f"found {max_force_N:g} N, expected at most {ceiling_N:g} N ({what})",
                               source, "safety.force.max_force_N")
    return profile


def _force_ceilings(profile: Profile) -> list[tuple[float, str]]:
    """(largest allowed max_force_N in N, why) for the protocol and each actuator rating the profile declares."""
    dbc = profile.can.dbc_path or "drivers/protocol/rig.dbc"
    ceilings = [
        (command_force_limit_N(profile.can.dbc_path), f"the range of the ACTUATOR_CMD force signal of {dbc}"),
        (profile.rig.actuator.force_limit_N, "rig.actuator.force_limit_N, the virtual rig actuator's rating"),
    ]
    rating_N = profile.safety.force.actuator_rating_N
    if rating_N is not None:
        ceilings.append((rating_N, "safety.force.actuator_rating_N, the rig actuator's rating"))
    return ceilings


@functools.lru_cache(maxsize=8)
def command_force_limit_N(dbc_path: str = "") -> float:
    """Largest |force| (N) the ACTUATOR_CMD ``force`` signal of the DBC carries, both signs.

    Parameters
    ----------
    dbc_path : str
        The DBC (``can.dbc_path``); empty means the packaged ``drivers/protocol/rig.dbc``.

    Raises
    ------
    ProtocolError
        If the DBC cannot be read or has no such message or signal.
    """
    from drivers.protocol.codec import load_protocol

    codec = load_protocol(dbc_path or None)["ACTUATOR_CMD"]
    signal = codec.signals[codec.index("force")]
    return min(-signal.minimum, signal.maximum)
