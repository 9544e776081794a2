"""The files every identification writes: ``identified.yaml`` (a profile overlay) and ``identification.json``.

``identified.yaml`` has the shape of a profile and holds only the values the data determined,
under the profile's own top-level keys (``bearing.mu_max``, ``structure.story_stiffness_N_per_m``),
because the identified rig becomes the design model. Merged over a profile (mappings merge,
values replace: :func:`harness.profile.merge`), it gives the identified profile. Each value
carries a comment with its fit quality. It is written as text, so the comments stay beside
the values; it is read back with any YAML reader.

``identification.json`` holds everything: each parameter with its standard error, whether the
data determined it and why, the fit's error, the runs used (path and the SHA-256 of their
``signals.csv``), the settings, and the harness's version and git commit.

A result folder holds the results of one identification only (:func:`claim_result_folder`):
one that already holds an earlier identification's files is refused, as an existing run
folder is (:class:`~harness.recording.layout.RunFolderError`), unless ``--force``, which
removes them first, so no result of an earlier run is ever read or shown as this one's.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from harness.identification.run_signals import RunUsed
from harness.recording.layout import RunFolderError
from harness.recording.metadata import environment, write_json_atomic

OVERLAY_FILE = "identified.yaml"
RECORD_FILE = "identification.json"


def claim_result_folder(out_dir: Path, result_files: Iterable[str], force: bool) -> None:
    """Make ``out_dir`` this identification's own: refuse it if it holds earlier results, or with ``force`` remove them.

    Parameters
    ----------
    out_dir : Path
        DIR (it may not exist yet; it is not created here).
    result_files : iterable of str
        The names of the files the identification writes in DIR.
    force : bool
        ``--force``: remove those of them that are there instead of refusing.

    Raises
    ------
    RunFolderError
        Naming DIR and the earlier results in it, when ``force`` is False.
    """
    present = sorted({name for name in result_files if (out_dir / name).is_file()})
    if present and not force:
        raise RunFolderError(
            f"already holds the results of an earlier identification ({', '.join(present)}); expected a new result "
            "folder (another --out), or --force to replace them", str(out_dir),
        )
    for name in present:
        (out_dir / name).unlink()


@dataclass(frozen=True)
class OverlayValue:
    """One key of the overlay: its value and the comment beside it.

    Attributes
    ----------
    key : str
        The key inside its section (``mu_max``).
    value : float, tuple of float, or None
        ``None`` writes ``null`` (a key the overlay clears).
    comment : str
        Fit quality, one line.
    """

    key: str
    value: float | tuple[float, ...] | None
    comment: str


def _number(value: float) -> str:
    """A float as YAML reads it back to 6 significant digits (``1.0e-05``, never ``1e-05``, which YAML 1.1 takes for text)."""
    text = f"{value:.6g}"
    if "e" in text and "." not in text.split("e")[0]:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _yaml_value(value: float | tuple[float, ...] | None) -> str:
    if value is None:
        return "null"
    if isinstance(value, tuple):
        return "[" + ", ".join(_number(v) for v in value) + "]"
    return _number(value)


def overlay_text(header: Sequence[str], sections: Mapping[str, Sequence[OverlayValue]]) -> str:
    """The text of ``identified.yaml``: ``header`` as comment lines, then each section's keys with their comments.

    A section's name may be a dotted path (``rig.actuator.hydraulics.cylinder``): it is written
    nested, sharing the mappings it has in common with the sections before it. A section with
    no value is written as a comment saying so, not as an empty mapping; when a section nested
    in it has values, the comment says that only its own keys were not determined.
    """
    lines = [f"# {line}" if line else "#" for line in header]
    opened: list[str] = []
    for section, values in sections.items():
        if not values:
            nested = [inner for inner, held in sections.items() if held and inner.startswith(f"{section}.")]
            if nested:
                lines.append(f"# {section}: none of its own keys determined (identification.json says why); "
                             f"the values below, in {', '.join(nested)}, are")
            else:
                lines.append(f"# {section}: nothing determined (identification.json says why)")
            continue
        path = section.split(".")
        shared = 0
        while shared < min(len(opened), len(path)) and opened[shared] == path[shared]:
            shared += 1
        for depth in range(shared, len(path)):
            lines.append(f"{'  ' * depth}{path[depth]}:")
        opened = path
        indent = "  " * len(path)
        for item in values:
            lines.append(f"{indent}{item.key}: {_yaml_value(item.value)}   # {item.comment}")
    return "\n".join(lines) + "\n"


def write_overlay(out_dir: Path, header: Sequence[str], sections: Mapping[str, Sequence[OverlayValue]]) -> Path:
    """Write ``identified.yaml`` in ``out_dir``; returns its path."""
    path = out_dir / OVERLAY_FILE
    path.write_text(overlay_text(header, sections), encoding="utf-8")
    return path


def write_record(out_dir: Path, command: str, runs: Sequence[RunUsed], content: Mapping[str, Any]) -> Path:
    """Write ``identification.json``: the command, the harness's version, the runs used and ``content``.

    Non-finite numbers (an undetermined parameter's infinite standard error) are written as null
    (:mod:`harness.strict_json`).
    """
    env = environment()
    data = {
        "command": command,
        "harness_version": env["packages"].get("shaketable-harness"),
        "git_commit": env["git_commit"],
        "git_dirty": env["git_dirty"],
        "runs": [run.as_dict() for run in runs],
        **content,
    }
    path = out_dir / RECORD_FILE
    write_json_atomic(path, data)
    return path
