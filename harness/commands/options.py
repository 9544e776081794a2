"""Argument types and option groups shared by the commands, and the profile as a command loads it."""

from __future__ import annotations

import argparse
import textwrap
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from harness.config import input_limits as limits
from harness.paths import shipped_file, shipped_profile

#: Exit statuses of the commands that move (or would move) a table: run, dry-run, rig.
EXIT_STATUS = """\
exit status:
  0  completed            3  tripped safely (force zeroed, drive disabled), or
  1  internal error (bug)     the record was lost: stopped safely (repeat the test)
  2  bad input or refused configuration, before this command moved anything
     (a table an external rig already runs is refused, and said so)
  4  stopped early (safe stop) by the operator, or by a check (e.g. the table
     not playing the told record); by the operator before anything moved
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


# Ranges of the numeric options; harness/config/input_limits.py gives the reason for each bound.
#: ``--reset-drive`` of ``harness run`` and ``harness dry-run --external-rig``.
RESET_DRIVE_HELP = (
    "before arming, send the operator's reset of the drive's latched fault (a watchdog fault after the previous run "
    "disconnected, or a released E-stop); refused, exit 2, for any other fault; recorded in the run's events"
)

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


#: ``--force`` of a command writing ``--json``.
JSON_FORCE_HELP = "overwrite an existing --json file (without it an existing file is refused, exit 2)"


def check_json_target(text: str | None, force: bool) -> None:
    """Refuse a ``--json`` file that exists, unless ``force``; and any file in a run folder, whatever ``force``.

    A run folder (a folder holding ``metadata.json``) is a record: a JSON document written over
    its ``metadata.json`` would leave a folder no command can read.

    Raises
    ------
    ProfileError
        Naming ``--json``, the file and what was expected (exit status 2, before the command computes anything).
    """
    from harness.errors import ProfileError
    from harness.recording.layout import METADATA_FILE

    if text is None or text == STDOUT:
        return
    path = Path(text).expanduser()
    if (path.parent / METADATA_FILE).is_file():
        raise ProfileError(f"{text} is in the run folder {path.parent}, expected a file outside any run folder (a run's "
                           "files are its record and are never overwritten)", key_path="--json")
    if path.exists() and not force:
        raise ProfileError(f"{text} exists, expected a new file (or --force to overwrite it)", key_path="--json")


def output_dir(text: str) -> str:
    """An argparse ``type=`` for a directory the command writes into (created if missing): writable, not a file.

    Writability is tried (:func:`harness.recording.writable.directory_problem`), so ``--log-dir /proc/1``
    is refused here, before a bus is opened or a rig started, and not by the run folder's
    ``mkdir`` once the run has begun.
    """
    from harness.recording.writable import directory_problem

    if not text.strip():
        raise argparse.ArgumentTypeError("found an empty path, expected a directory")
    problem = directory_problem(text)
    if problem is not None:
        raise argparse.ArgumentTypeError(problem)
    return text


def add_record_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("record (overrides the profile's record section)")
    group.add_argument("--record", type=non_empty, metavar="NAME|PATH", help="record name or file (default: the profile's)")
    group.add_argument("--records-dir", type=non_empty, metavar="DIR", help="where named records are found")
    group.add_argument("--pga", type=number_in(PGA), metavar="G",
                       help=f"scale to this peak table acceleration (g), {PGA.describe()}")
    group.add_argument("--time-scale", type=number_in(TIME_SCALE), metavar="F",
                       help=f"compress time by F (2 = twice the frequency), {TIME_SCALE.describe()}")
    group.add_argument("--duration", type=number_in(DURATION), metavar="S",
                       help=f"run length (s), {DURATION.describe()}{DURATION_HELP}")


def add_bus_options(parser: argparse.ArgumentParser) -> None:
    group = parser.add_argument_group("CAN bus (overrides the profile's can section)")
    group.add_argument("--interface", type=non_empty, metavar="I",
                       help="python-can interface: virtual, socketcan, pcan, kvaser, ...")
    group.add_argument("--channel", type=non_empty, metavar="C", help="channel, e.g. vcan0, can0, PCAN_USBBUS1")


def add_overrides(parser: argparse.ArgumentParser, example: str) -> None:
    """``--variant``, ``--overlay`` and ``--set``: every command that loads a profile takes them, validated like the file."""
    parser.add_argument("--variant", type=non_empty, help="apply a named variant of the profile (e.g. a_mu_0.5)")
    parser.add_argument(
        "--overlay", type=non_empty, metavar="FILE",
        help="merge a YAML file with the profile's keys over it, after --variant and before --set (e.g. the "
        "identified.yaml of `harness identify`); validated like the profile, recorded with its SHA-256 in metadata.json",
    )
    parser.add_argument(
        "--set", dest="overrides", action="append", default=[], metavar="KEY.PATH=VALUE",
        help=f"override a profile value, validated like the file, e.g. --set {example} (repeatable)",
    )


#: ``--force`` of a command writing a result folder (harness/identification/outputs.py, ``claim_result_folder``).
RESULT_FORCE_HELP = ("replace the results an earlier identification left in DIR (they are removed first, so none is mixed "
                     "with this run's); without it such a DIR is refused, exit 2")


def add_result_folder(parser: argparse.ArgumentParser, outputs: str) -> None:
    """``--out DIR`` and ``--force``: the result folder of an identification, writing ``outputs`` to DIR."""
    parser.add_argument("--out", required=True, type=output_dir, metavar="DIR",
                        help=f"where {outputs} go (created if missing)")
    parser.add_argument("--force", action="store_true", help=RESULT_FORCE_HELP)


def add_run_folders(parser: argparse.ArgumentParser, outputs: str) -> None:
    """``RUN [RUN ...]``, ``--out DIR`` and ``--force``: an identification from run folders, writing ``outputs`` to DIR."""
    parser.add_argument("runs", nargs="+", metavar="RUN",
                        help="run folders (each holding metadata.json; each once, none whose outcome is incomplete)")
    add_result_folder(parser, outputs)


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


#: What --rate of a loop command (run, dry-run) must also meet, for --help: the bounds harness/runs/loop_rate.py derives.
LOOP_RATE_HELP = (
    f"; and at least {limits.STALL_BUDGET_PERIODS:g} / safety.run.max_stall_s, {limits.WATCHDOG_PERIODS:g} / "
    "rig.drive.watchdog_timeout_s and 1 / safety.sensors.max_sensor_age_s (100 Hz for the shipped profiles), "
    "in lockstep too"
)
#: What --duration must also meet, for --help: the record loader's bound (all commands) and :func:`check_run_length`.
RECORD_DURATION_HELP = f"; and at least {limits.MIN_RUN_SAMPLES} samples of the record"
DURATION_HELP = f"{RECORD_DURATION_HELP} and {limits.MIN_RUN_SAMPLES} periods of the control rate"


def check_run_length(profile, args: argparse.Namespace) -> None:
    """Refuse a run or simulation shorter than :data:`~harness.config.input_limits.MIN_RUN_SAMPLES` control periods.

    The record's own lower bound (as many samples of the record) is checked where the record is
    loaded (``harness.motions.loading``). A profile without ``record.duration_s`` runs the whole
    record, which has at least that many samples.

    Parameters
    ----------
    profile : Profile
        The profile the command loaded.
    args : argparse.Namespace
        Its options: ``duration`` and ``rate`` win over the profile's ``record.duration_s`` and
        ``control.rate_hz`` when given.

    Raises
    ------
    ProfileError
        Naming ``--duration`` (or ``record.duration_s``), the length found and the least accepted.
    """
    from harness.errors import ProfileError
    from harness.runs.loop_rate import given_as

    given = getattr(args, "duration", None)
    duration_s = given if given is not None else profile.record.duration_s
    if duration_s is None:
        return
    rate_hz = getattr(args, "rate", None) or profile.control.rate_hz
    shortest_s = limits.MIN_RUN_SAMPLES / rate_hz
    if duration_s < shortest_s * (1 - 1e-9):
        source, key = given_as("--duration", given is not None, profile, "record.duration_s")
        raise ProfileError(
            f"found {duration_s:g} s, expected at least {shortest_s:g} s: {limits.MIN_RUN_SAMPLES} periods of the "
            f"{rate_hz:g} Hz control rate (a shorter run has too few samples for its peaks to mean anything)", source, key,
        )


def study_options(args: argparse.Namespace, **extra):
    from harness.runs.options import StudyOptions

    return StudyOptions(
        record=args.record, records_dir=args.records_dir, pga_g=args.pga, time_scale=args.time_scale,
        duration_s=args.duration, **extra,
    )


def load_acknowledged(args: argparse.Namespace, console: Console | None = None):
    """The profile of a command with ``--set``, refused if it weakens safety without ``--allow-weaker-safety``.

    Parameters
    ----------
    args : argparse.Namespace
        With ``profile``, ``variant``, ``overlay``, ``overrides`` and ``allow_weaker_safety``.
    console : Console, optional
        Where an accepted weakening is announced (in red) before anything starts.

    Raises
    ------
    ProfileError
        Listing each weakened key with the profile's value and the new one (exit status 2).
    """
    from harness.profile import load_profile
    from harness.safety.weakening import require_acknowledged, summary

    profile = load_profile(args.profile, variant=args.variant, overrides=args.overrides, overlay=args.overlay)
    require_acknowledged(profile.safety_weakened, args.allow_weaker_safety, profile.source_path)
    if profile.safety_weakened and console is not None:
        console.print(f"[bold red]{escape(summary(profile.safety_weakened))}[/]", highlight=False)
    return profile
