"""The checkout's own folders, found from this file: one place, so a module that moves cannot get them wrong."""

from __future__ import annotations

from pathlib import Path

#: The checkout (the folder holding ``harness/``, ``profiles/`` and ``logs/``).
PROJECT_ROOT = Path(__file__).resolve().parent.parent
#: The shipped profiles.
PROFILE_DIR = PROJECT_ROOT / "profiles"
#: The shipped study files of ``harness sweep``.
STUDY_DIR = PROFILE_DIR / "studies"
#: Where run folders go unless ``--log-dir`` says otherwise.
LOG_DIR = PROJECT_ROOT / "logs"


def shipped_file(text: str, folder: Path, *, existing_wins: bool = True) -> Path | None:
    """The shipped YAML file in ``folder`` that ``text`` names, if it names one and is not an existing file itself.

    A name may carry ``.yaml`` and the trailing folders of ``folder`` inside the checkout:
    for the profiles ``eight_story``, ``eight_story.yaml`` and ``profiles/eight_story.yaml``
    all name ``<package>/profiles/eight_story.yaml``; for the studies ``ida_friction``,
    ``studies/ida_friction.yaml`` and ``profiles/studies/ida_friction.yaml`` name
    ``<package>/profiles/studies/ida_friction.yaml``. So a shipped file is found by its name
    from any folder. Any other path is left alone.

    Parameters
    ----------
    text : str
        What the user typed.
    folder : Path
        A folder of the checkout (:data:`harness.paths.PROFILE_DIR`, :data:`harness.paths.STUDY_DIR`).
    existing_wins : bool
        Whether a ``text`` that is an existing file from the working directory is left alone (the
        command line); a study file, whose paths are relative to itself, says False.

    Returns
    -------
    Path or None
        The shipped file, or None (``text`` is an existing file, or names no shipped file).
    """
    given = Path(text).expanduser()
    inside = folder.relative_to(PROJECT_ROOT).parts
    prefixes = {inside[len(inside) - n:] for n in range(len(inside) + 1)}  # (), ("studies",), ("profiles", "studies")
    if (existing_wins and given.is_file()) or given.parts[:-1] not in prefixes:
        return None
    for candidate in (folder / given.name, folder / f"{given.name}.yaml"):
        if candidate.suffix in (".yaml", ".yml") and candidate.is_file():
            return candidate
    return None


def shipped_profile(text: str, *, existing_wins: bool = True) -> Path | None:
    """The shipped profile ``text`` names (:func:`shipped_file` in :data:`harness.paths.PROFILE_DIR`)."""
    return shipped_file(text, PROFILE_DIR, existing_wins=existing_wins)
