"""Argument types and option groups shared by the commands, and the profile as a command loads it."""

from __future__ import annotations

import argparse
import math
import textwrap
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from harness.config import (
    input_limits as limits,  #: Exit statuses of the commands that move (or would move) a table: run, dry-run, rig.
)

EXIT_STATUS = """\
exit status:
  0  completed            3  tripped safely (force zeroed, drive disabled), or
  1  internal error (bug)     completed but the record was lost (repeat the test)
  2  bad input or refused configuration, before this command moved anything
     (a table an external rig already runs is refused, and said so)
  4  stopped early (safe stop) by the operator, or by a check (e.g. the table
     not playing the told record)
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


#: What --rate of a loop command (run, dry-run) must also meet, for --help: the bounds :func:`check_loop_rate` derives.
LOOP_RATE_HELP = (
    f"; and at least {limits.STALL_BUDGET_PERIODS:g} / safety.run.max_stall_s, {limits.WATCHDOG_PERIODS:g} / "
    "rig.drive.watchdog_timeout_s and 1 / safety.sensors.max_sensor_age_s (100 Hz for the shipped profiles), "
    "in lockstep too"
)
#: What --duration must also meet, for --help: the record loader's bound (all commands) and :func:`check_run_length`.
RECORD_DURATION_HELP = f"; and at least {limits.MIN_RUN_SAMPLES} samples of the record"
DURATION_HELP = f"{RECORD_DURATION_HELP} and {limits.MIN_RUN_SAMPLES} periods of the control rate"


def _given_as(option: str, given: bool, profile, key: str) -> tuple[str, str | None]:
    """(source, key path) of a :class:`ProfileError` about a value: the option if it was given, else the profile's key."""
    return (option, None) if given else (profile.source_path, key)


def check_loop_rate(profile, rate_given: bool, *, virtual_rig: bool) -> None:
    """Refuse a loop rate at which a run or a dry run could not arm, or not hold the loop, before anything starts.

    The range of ``--rate`` says what the parser accepts; a loop also needs its period short
    enough for what the profile's safety settings expect of it (harness/config/input_limits.py
    derives each):

    - :data:`~harness.config.input_limits.STALL_BUDGET_PERIODS` periods within ``safety.run.max_stall_s``;
    - :data:`~harness.config.input_limits.WATCHDOG_PERIODS` periods within ``rig.drive.watchdog_timeout_s``;
    - the sensor frames' period (``can.sensor_rate_hz``, which ``--rate`` sets) within
      ``safety.sensors.max_sensor_age_s``: a sample is up to a period old when a tick reads it;
    - for the virtual rig of a dry run, a whole number of ``rig.physics_substep_s`` per period.

    A lockstep dry run is held to the same bounds: it rehearses the real-time loop at the
    same rate, so a rate that loop cannot hold would rehearse nothing (and far below them the
    rig's step of period / ``physics_substep_s`` sub-steps outgrows ``loop.lockstep_timeout_s``:
    ``--rate 0.001`` asked for two million a step, and the dry run could not arm).

    Parameters
    ----------
    profile : Profile
        Resolved: ``--rate`` already folded in (``resolve_profile``).
    rate_given : bool
        True if ``--rate`` set the rate (the message then names it; else ``loop.rate_hz``).
    virtual_rig : bool
        True for a dry run.

    Raises
    ------
    ProfileError
        Naming ``--rate`` (or ``loop.rate_hz``), the rate found, the least rate accepted and why.
    """
    from harness.errors import ProfileError

    rate_hz = profile.loop.rate_hz
    period_s = 1.0 / rate_hz
    source, key = _given_as("--rate", rate_given, profile, "loop.rate_hz")
    bounds = (
        ("safety.run.max_stall_s", profile.safety.run.max_stall_s, limits.STALL_BUDGET_PERIODS,
         "the shortest stall, one missed deadline, is two periods between ticks"),
        ("rig.drive.watchdog_timeout_s", profile.rig.drive.watchdog_timeout_s, limits.WATCHDOG_PERIODS,
         "the drive disables itself when no command reaches it for that long"),
    )
    too_slow = [(name, value, periods, why) for name, value, periods, why in bounds if period_s * periods > value * (1 + 1e-9)]
    if too_slow:
        least_hz = max(periods / value for _, value, periods, _ in bounds)
        reasons = "; ".join(f"{periods:g} periods must fit in {name} ({value * 1e3:g} ms: {why})"
                            for name, value, periods, why in too_slow)
        raise ProfileError(
            f"found {rate_hz:g} Hz (a period of {period_s * 1e3:g} ms), expected at least {least_hz:g} Hz: {reasons} "
            "(docs/SAFETY.md, Stall budget; lockstep too is held to this, as it rehearses the real-time loop)", source, key,
        )
    sensor_period_s = 1.0 / profile.can.sensor_rate_hz
    age_s = profile.safety.sensors.max_sensor_age_s
    if sensor_period_s > age_s * (1 + 1e-9):
        source, key = _given_as("--rate", rate_given, profile, "can.sensor_rate_hz")
        raise ProfileError(
            f"found sensor frames every {sensor_period_s * 1e3:g} ms ({profile.can.sensor_rate_hz:g} Hz), expected at "
            f"least {1.0 / age_s:g} Hz: a sample is up to a period old when a tick reads it, and "
            f"safety.sensors.max_sensor_age_s is {age_s * 1e3:g} ms", source, key,
        )
    if virtual_rig:
        _check_rig_substeps(profile, period_s, source, key)


def _check_rig_substeps(profile, period_s: float, source: str, key: str | None) -> None:
    """The virtual rig steps whole physics sub-steps per loop period (else its process exits once the run began)."""
    from harness.errors import ProfileError

    substep_s = profile.rig.physics_substep_s
    steps = round(period_s / substep_s)
    if steps >= 1 and abs(steps * substep_s - period_s) <= 1e-9 * period_s:
        return
    fewer = max(1, math.floor(period_s / substep_s))
    nearby = sorted({1.0 / (n * substep_s) for n in (fewer, fewer + 1)}, reverse=True)
    raise ProfileError(
        f"found {profile.loop.rate_hz:g} Hz: its period of {period_s * 1e3:g} ms is not a whole number of the virtual "
        f"rig's physics sub-steps (rig.physics_substep_s = {substep_s * 1e3:g} ms); expected a rate such as "
        + " or ".join(f"{rate:g} Hz" for rate in nearby), source, key,
    )


def check_run_length(profile, args: argparse.Namespace) -> None:
    """Refuse a run or simulation shorter than :data:`~harness.config.input_limits.MIN_RUN_SAMPLES` control periods.

    The record's own lower bound (as many samples of the record) is checked where the record is
    loaded (``harness.motions.config``). A profile without ``record.duration_s`` runs the whole
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

    given = getattr(args, "duration", None)
    duration_s = given if given is not None else profile.record.duration_s
    if duration_s is None:
        return
    rate_hz = getattr(args, "rate", None) or profile.control.rate_hz
    shortest_s = limits.MIN_RUN_SAMPLES / rate_hz
    if duration_s < shortest_s * (1 - 1e-9):
        source, key = _given_as("--duration", given is not None, profile, "record.duration_s")
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
