"""Labels that tell compared runs apart: made from what differs between them.

Every run folder says what it was run with: its kind, controller, record (name, PGA, time
scale), variant, sampling, and its resolved profile. :func:`run_facts` reads those facts,
one short text each; :func:`distinct_labels` keeps, for a set of runs, only the facts that
differ between them (``"FSF-I el_centro"`` against ``"OF-I el_centro"``), adds the
profile settings that differ (a ``--set``), and makes every label unique (the folder's
name where nothing else tells two runs apart). A label the user chose (``--label``, or a
``label`` in the metadata) wins. :func:`common_facts` is what the runs share, for titles.

The labels are used in the report's tables, legends, CSV headers and file names.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Mapping, Sequence
from typing import Any

from harness.recording.reader import RunData

#: Fact keys in label order.
FACT_ORDER = (
    "kind", "controller", "record", "pga", "time_scale", "duration", "variant", "stiffness", "rate", "delay",
    "friction", "lockstep", "profile",
)
#: Facts shown for a run alone (nothing to tell it apart from).
SINGLE_RUN_FACTS = ("kind", "controller", "record")
#: Profile keys (dotted) already covered by a fact, or that never tell runs apart.
_COVERED_PREFIXES = (
    "name", "description", "loaded_from", "variant", "record.", "control.controller", "control.rate_hz", "loop.rate_hz",
    "can.", "control.transport_delay_s", "control.friction", "control.design_stiffness_scale", "structure.assumptions",
)
#: Facts of the controller's sampling: a passive run (no controller) has none of them.
CONTROLLER_FACTS = ("delay", "friction", "stiffness")
#: Most differing profile settings spelt out in a label; more are counted.
MAX_SETTINGS = 2
_KIND_TEXT = {"simulation": "sim", "dry-run": "dry run", "run": "table run"}
#: Labels the harness itself wrote into simulation folders before labels were computed here.
_OLD_AUTO_LABEL = re.compile(r"^\S+ simulate (passive|controlled)( \(rig effects\))?$")


def _number(value: Any) -> float | None:
    return float(value) if isinstance(value, (int, float)) and not isinstance(value, bool) else None


def _record_facts(record: Any) -> dict[str, str]:
    if isinstance(record, str):
        return {"record": record}
    if not isinstance(record, Mapping):
        return {}
    facts = {"record": str(record.get("name", ""))}
    pga, scale, duration = (_number(record.get(key)) for key in ("pga_g", "time_scale", "duration_s"))
    if pga is not None:
        facts["pga"] = f"{pga:.3g} g"
    if scale is not None:
        facts["time_scale"] = f"time/{scale:g}"
    if duration is not None:
        facts["duration"] = f"{duration:g} s"
    return facts


def _sampling(run: RunData) -> Mapping[str, Any]:
    """The sampling a simulation recorded, else the one the run's profile says (runs and dry runs)."""
    found = run.metadata.get("sampling")
    if isinstance(found, Mapping):
        return found
    control = run.profile.get("control")
    control = control if isinstance(control, Mapping) else {}
    return {"rate_hz": run.metadata.get("rate_hz", control.get("rate_hz")), "transport_delay_s": control.get("transport_delay_s"),
            "friction_source": control.get("friction"), "design_stiffness_scale": control.get("design_stiffness_scale")}


def _sampling_facts(run: RunData) -> dict[str, str]:
    metadata = run.metadata
    sampling = _sampling(run)
    facts = {}
    rate = _number(sampling.get("rate_hz"))
    if rate is not None:
        facts["rate"] = f"{rate:g} Hz"
    delay = _number(sampling.get("transport_delay_s"))
    if delay is not None:
        facts["delay"] = f"delay {delay * 1e3:g} ms"
    if sampling.get("friction_source"):
        facts["friction"] = f"friction {sampling['friction_source']}"
    stiffness = _number(sampling.get("design_stiffness_scale"))
    if stiffness is not None:
        facts["stiffness"] = f"design k x{stiffness:g}"
    if isinstance(metadata.get("lockstep"), bool):
        facts["lockstep"] = "lockstep" if metadata["lockstep"] else "real time"
    return facts


def _kind(run: RunData) -> str:
    """``sim``, ``rig twin`` (a controlled case simulated through the rig's models), ``dry run``, ``table run``."""
    sampling = run.metadata.get("sampling")
    if run.kind == "simulation" and not run.is_passive and isinstance(sampling, Mapping) and sampling.get("rig_effects"):
        return "rig twin"
    return _KIND_TEXT.get(run.kind, run.kind)


def run_facts(run: RunData) -> dict[str, str]:
    """What one run was run with, one short text per fact (see :data:`FACT_ORDER`); absent facts are left out.

    Parameters
    ----------
    run : RunData

    Returns
    -------
    dict of str to str
        E.g. ``{"kind": "sim", "controller": "FSF-I", "record": "el_centro", "pga": "0.3 g", ...}``.
    """
    metadata = run.metadata
    controller = "passive" if run.is_passive else str(metadata.get("controller") or "")
    facts = {"kind": _kind(run), "controller": controller}
    facts |= _record_facts(metadata.get("record"))
    sampling = _sampling_facts(run)
    facts |= {key: value for key, value in sampling.items() if not (run.is_passive and key in CONTROLLER_FACTS)}
    facts["variant"] = f"variant {run.profile['variant']}" if run.profile.get("variant") else "no variant"
    facts["profile"] = str(metadata.get("profile_name") or run.profile.get("name") or "")
    return {key: value for key, value in facts.items() if value}


def _flatten(data: Any, prefix: str = "") -> dict[str, Any]:
    """Dotted key -> leaf value of nested mappings (lists become tuples)."""
    if isinstance(data, Mapping):
        flat: dict[str, Any] = {}
        for key, value in data.items():
            flat |= _flatten(value, f"{prefix}{key}.")
        return flat
    return {prefix[:-1]: tuple(data) if isinstance(data, list) else data}


def _covered(key: str) -> bool:
    return any(key == prefix or (prefix.endswith(".") and key.startswith(prefix)) for prefix in _COVERED_PREFIXES)


def _setting_text(key: str, value: Any) -> str:
    shown = "-" if value is None else (f"{value:g}" if isinstance(value, float) else str(value))
    return f"{key.rsplit('.', 1)[-1]}={shown}"


def settings_facts(runs: Sequence[RunData]) -> list[str]:
    """Per run, the profile settings (``--set``) that differ between runs of one profile and variant.

    Returns ``""`` for every run when the profiles or variants differ (the profile or the variant
    then tells them apart) or when the runs' profiles are not recorded.
    """
    names = {(run.profile.get("name"), run.profile.get("variant")) for run in runs}
    if len(runs) < 2 or len(names) != 1 or not all(run.profile for run in runs):
        return [""] * len(runs)
    flat = [_flatten(run.profile) for run in runs]
    keys = sorted({key for leaves in flat for key in leaves if not _covered(key)})
    differing = [key for key in keys if len({repr(leaves.get(key)) for leaves in flat}) > 1]
    texts = []
    for leaves in flat:
        parts = [_setting_text(key, leaves.get(key)) for key in differing[:MAX_SETTINGS]]
        if len(differing) > MAX_SETTINGS:
            parts.append(f"+{len(differing) - MAX_SETTINGS} settings")
        texts.append(" ".join(parts))
    return texts


def user_label(run: RunData) -> str | None:
    """The label a user gave the run (``metadata["label"]``), None if none or one the harness made up."""
    label = run.metadata.get("label")
    if not isinstance(label, str) or not label.strip() or _OLD_AUTO_LABEL.match(label):
        return None
    return label.strip()


def _differing_keys(facts: Sequence[Mapping[str, str]]) -> list[str]:
    """Facts with different values among the runs that record them (a fact only one run records tells nothing)."""
    keys = []
    for key in FACT_ORDER:
        values = [f[key] for f in facts if key in f]
        if len(values) > 1 and len(set(values)) > 1:
            keys.append(key)
    return keys


def _disambiguator(run: RunData) -> str:
    """What tells a run apart when no fact does: its set's folder for a case, else its folder's name."""
    return run.path.parent.name if run.case is not None else run.path.name


def _unique(labels: list[str], runs: Sequence[RunData]) -> list[str]:
    """Append the folder (then a number) to labels that occur more than once."""
    result = list(labels)
    for label in set(labels):
        clashing = [i for i, text in enumerate(labels) if text == label]
        if len(clashing) > 1:
            for i in clashing:
                result[i] = f"{label} ({_disambiguator(runs[i])})"
    for label in set(result):
        clashing = [i for i, text in enumerate(result) if text == label]
        if len(clashing) > 1:
            for number, i in enumerate(clashing, start=1):
                result[i] = f"{label} #{number}"
    return result


def distinct_labels(runs: Sequence[RunData], given: Sequence[str | None] | None = None) -> list[str]:
    """One unique label per run, made from what differs between the runs.

    Parameters
    ----------
    runs : sequence of RunData
    given : sequence of (str or None), optional
        A label per run chosen by the user (``harness report --label``); None keeps the
        run's own (``metadata["label"]``) or makes one.

    Returns
    -------
    list of str
        Unique labels, in the order of ``runs``.
    """
    given = list(given) if given is not None else [None] * len(runs)
    facts = [run_facts(run) for run in runs]
    keys = _differing_keys(facts) if len(runs) > 1 else list(SINGLE_RUN_FACTS)
    if not keys:
        keys = ["kind", "controller"]
    settings = settings_facts(runs)
    labels = []
    for run, fact, setting, chosen in zip(runs, facts, settings, given, strict=True):
        made = " ".join(filter(None, [*(fact.get(key, "") for key in keys), setting]))
        labels.append(chosen or user_label(run) or made or run.path.name)
    return _unique(labels, runs)


def common_facts(runs: Sequence[RunData]) -> str:
    """What every run shares (profile, record, PGA, ...), as one line for a title; "" if nothing."""
    if not runs:
        return ""
    facts = [run_facts(run) for run in runs]
    shared = [facts[0][key] for key in ("profile", "kind", "controller", "record", "pga", "time_scale", "variant")
              if key in facts[0] and all(f.get(key) == facts[0][key] for f in facts[1:])]
    return ", ".join(text for text in shared if text != "no variant")


def with_labels(runs: Sequence[RunData], given: Sequence[str | None] | None = None) -> list[RunData]:
    """Copies of ``runs`` whose :attr:`RunData.label` is their :func:`distinct_labels` label."""
    labels = distinct_labels(runs, given)
    return [dataclasses.replace(run, metadata={**run.metadata, "label": label}) for run, label in zip(runs, labels, strict=True)]


def file_slug(text: str, limit: int = 60) -> str:
    """``text`` as a file-name part: lower case, letters and digits, single underscores, at most ``limit`` characters."""
    slug = re.sub(r"[^0-9a-z]+", "_", text.lower()).strip("_")
    return slug[:limit].rstrip("_") or "table"
