"""Argument types and option groups shared by the commands, and the profile as a command loads it."""

from __future__ import annotations

import argparse
import textwrap
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from harness import input_limits as limits

#: Exit statuses of the commands that move (or would move) a table: run, dry-run, rig.
EXIT_STATUS = """\
exit status:
  0  completed            3  tripped safely (force zeroed, drive disabled), or
  1  internal error (bug)     completed but the record was lost (repeat the test)
  2  bad input or refused configuration, before anything moved
  4  stopped early by the operator (safe stop)
"""

#: Exit statuses of the offline commands (simulate, report, records): nothing moves, nothing trips.
OFFLINE_EXIT_STATUS = """\
exit status:
  0  completed
  1  internal error (bug)
  2  bad input or refused configuration (e.g. a record the table cannot follow)
"""

RECORDS_HELP = """\
records: a NAME (el_centro, el_centro_classic, hachinohe, pacoima, synthetic,
synthetic:SEED) is looked up in --records-dir, else $HARNESS_RECORDS_DIR, else the
profile's record.records_dir; a PATH (.AT2, .csv, .txt) is read directly.
"""

PROFILES_HELP = """\
profiles: a PATH to a YAML file, or the NAME of a shipped profile (nceer_4dof,
eight_story), found from any folder (profiles/NAME.yaml also works outside the checkout).
"""

#: The epilog of run, dry-run, rig and the top-level command.
EPILOG = f"{EXIT_STATUS}\n{RECORDS_HELP}\n{PROFILES_HELP}"
#: The epilog of simulate and records: offline exit statuses, records and profiles.
SIMULATE_EPILOG = f"{OFFLINE_EXIT_STATUS}\n{RECORDS_HELP}\n{PROFILES_HELP}"
#: The epilog of report: offline exit statuses only.
OFFLINE_EPILOG = OFFLINE_EXIT_STATUS


def wrap(text: str) -> str:
    """Wrap a description to the terminal's usual width (the formatter keeps it as given)."""
    return textwrap.fill(text, width=78)


# Ranges of the numeric options; harness/input_limits.py gives the reason for each bound.
RATE = limits.NumberRange(0.0, limits.MAX_RATE_HZ, "Hz")


PGA = limits.NumberRange(0.0, limits.MAX_PGA_G, "g")


TIME_SCALE = limits.NumberRange(limits.MIN_TIME_SCALE, limits.MAX_TIME_SCALE, low_open=False)


DURATION = limits.NumberRange(0.0, limits.MAX_DURATION_S, "s")


DELAY = limits.NumberRange(0.0, limits.MAX_DELAY_S, "s", low_open=False)


STIFFNESS_SCALE = limits.NumberRange(limits.MIN_STIFFNESS_SCALE, limits.MAX_STIFFNESS_SCALE, low_open=False)


SEED = limits.NumberRange(0, limits.MAX_SEED, low_open=False, integer=True)


PID = limits.NumberRange(1, limits.MAX_PID, low_open=False, integer=True)


def number_in(allowed: limits.NumberRange) -> Callable[[str], float | int]:
    """An argparse ``type=`` that parses a number and refuses it outside ``allowed``.

    argparse then exits with status 2 and ``argument --rate: found -500 Hz, expected a number
    of Hz in (0, 5000]``.
    """

    def parse(text: str) -> float | int:
        try:
            return allowed.check(text)
        except ValueError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    return parse


def non_empty(text: str) -> str:
    """An argparse ``type=`` for a name or path that must not be blank (``--record ""`` is a mistake)."""
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty value, expected a name or a path")
    return text


def shipped_file(text: str, folder: Path) -> Path | None:
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

    Returns
    -------
    Path or None
        The shipped file, or None (``text`` is an existing file, or names no shipped file).
    """
    from harness.paths import PROJECT_ROOT

    given = Path(text).expanduser()
    inside = folder.relative_to(PROJECT_ROOT).parts
    prefixes = {inside[len(inside) - n:] for n in range(len(inside) + 1)}  # (), ("studies",), ("profiles", "studies")
    if given.is_file() or given.parts[:-1] not in prefixes:
        return None
    for candidate in (folder / given.name, folder / f"{given.name}.yaml"):
        if candidate.suffix in (".yaml", ".yml") and candidate.is_file():
            return candidate
    return None


def shipped_profile(text: str) -> Path | None:
    """The shipped profile ``text`` names (:func:`shipped_file` in :data:`harness.paths.PROFILE_DIR`)."""
    from harness.paths import PROFILE_DIR

    return shipped_file(text, PROFILE_DIR)


def study_path(text: str) -> str:
    """An argparse ``type=`` for a study: a YAML file, or the name of a shipped study (``profiles/studies/``).

    Found like a profile (:func:`shipped_file`): ``ida_friction`` and
    ``profiles/studies/ida_friction.yaml`` name the shipped study from any folder.
    """
    from harness.paths import STUDY_DIR

    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty value, expected a study file or the name of a shipped study")
    shipped = shipped_file(text, STUDY_DIR)
    return str(shipped) if shipped is not None else text


def profile_path(text: str) -> str:
    """An argparse ``type=`` for a profile: a YAML file, or the name of a shipped profile (:func:`shipped_profile`).

    A path that exists is kept as typed; a name of a shipped profile becomes its file; anything
    else is kept, and loading it then says what was expected and lists the shipped profiles.
    """
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty value, expected a profile file or the name of a shipped profile")
    shipped = shipped_profile(text)
    return str(shipped) if shipped is not None else text


def output_file(text: str) -> str:
    """An argparse ``type=`` for a file the command writes: not a directory, in an existing directory."""
    path = Path(text).expanduser()
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty path, expected a file name to write")
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a directory, expected a file name to write")
    if not path.parent.is_dir():
        raise argparse.ArgumentTypeError(f"{text}: its directory {path.parent} does not exist, expected an existing directory")
    return text


#: ``--json -``: the JSON document goes to standard output.
STDOUT = "-"


def json_file(text: str) -> str:
    """An argparse ``type=`` for ``--json``: a file to write (:func:`output_file`), or ``-`` for standard output."""
    return text if text == STDOUT else output_file(text)


def output_dir(text: str) -> str:
    """An argparse ``type=`` for a directory the command writes into (created if missing): not a file."""
    path = Path(text).expanduser()
    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty path, expected a directory")
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file, expected a directory (existing or to be created)")
    return text


def add_record_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("record (overrides the profile's record section)")
    group.add_argument("--record", type=non_empty, metavar="NAME|PATH", help="record name or file (default: the profile's)")
    group.add_argument("--records-dir", type=non_empty, metavar="DIR", help="where named records are found")
    group.add_argument("--pga", type=number_in(PGA), metavar="G",
                       help=f"scale to this peak table acceleration (g), {PGA.describe()}")
    group.add_argument("--time-scale", type=number_in(TIME_SCALE), metavar="F",
                       help=f"compress time by F (2 = twice the frequency), {TIME_SCALE.describe()}")
    group.add_argument("--duration", type=number_in(DURATION), metavar="S", help=f"run length (s), {DURATION.describe()}")


def add_bus_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("CAN bus (overrides the profile's can section)")
    group.add_argument("--interface", type=non_empty, metavar="I",
                       help="python-can interface: virtual, socketcan, pcan, kvaser, ...")
    group.add_argument("--channel", type=non_empty, metavar="C", help="channel, e.g. vcan0, can0, PCAN_USBBUS1")


def add_overrides(parser: argparse.ArgumentParser, example: str) -> None:
    """``--variant`` and ``--set``: every command that loads a profile takes both, validated like the file."""
    parser.add_argument("--variant", type=non_empty, help="apply a named variant of the profile (e.g. a_mu_0.5)")
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
        help=f"override a profile value, validated like the file, e.g. --set {example} (repeatable)",
    )


def add_profile_argument(parser: argparse.ArgumentParser, default_help: str) -> None:
    """The optional positional PROFILE: a YAML file or the name of a shipped profile (:func:`profile_path`)."""
    parser.add_argument("profile", nargs="?", type=profile_path, metavar="PROFILE",
                        help=f"{default_help}; a file or a shipped profile's name (nceer_4dof, eight_story)")


def add_profile_options(parser: argparse.ArgumentParser, default_help: str) -> None:
    add_profile_argument(parser, default_help)
    add_overrides(parser, "safety.force.max_force_N=8000")
    parser.add_argument(
        "--allow-weaker-safety", action="store_true",
        help="accept --set values that weaken the profile's own safety settings; each is recorded in metadata.json, "
        "on the live console and in the outcome (docs/SAFETY.md). Without it such a run is refused",
    )


def study_options(args: argparse.Namespace, **extra):
    from harness.runs.simulate import StudyOptions

    return StudyOptions(
        record=args.record, records_dir=args.records_dir, pga_g=args.pga, time_scale=args.time_scale,
        duration_s=args.duration, **extra,
    )


def load_acknowledged(args: argparse.Namespace, console: Console | None = None):
    """The profile of a command with ``--set``, refused if it weakens safety without ``--allow-weaker-safety``.

    Parameters
    ----------
    args : argparse.Namespace
        With ``profile``, ``variant``, ``overrides`` and ``allow_weaker_safety``.
    console : Console, optional
        Where an accepted weakening is announced (in red) before anything starts.

    Raises
    ------
    ProfileError
        Listing each weakened key with the profile's value and the new one (exit status 2).
    """
    from harness.profile import load_profile
    from harness.safety.weakening import require_acknowledged, summary

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides)
    require_acknowledged(profile.safety_weakened, args.allow_weaker_safety, profile.source_path)
    if profile.safety_weakened and console is not None:
        console.print(f"[bold red]{escape(summary(profile.safety_weakened))}[/]", highlight=False)
    return profile
