"""Every example command in the README and in each command's --help, checked against its documented outcome.

The examples are read from the text a user reads: the README's fenced ``sh`` blocks and the
"example(s):" section of each command's ``--help`` (rendered from the parser). The commands of
one block run in order in one scratch folder, so a ``harness simulate ... --out study/`` makes
the folder the next ``harness report study/`` reads, as the docs chain them. The records are
the ones beside the checkout: ``../shared/data/ground_motions`` in an example, and
``$HARNESS_RECORDS_DIR`` only where the README has exported it (an ``export`` line in that block
or an earlier one, run from the checkout's root; the examples of ``--help`` come after the whole
README): nothing else is set, so an example that names a record the reader has not been told how
to find fails here as it fails for a new user.

Running every example in full would take many minutes, so each gets the cheapest check that
still fails when the example is refused (:func:`check_for`):

``run``
    As written, in this process: ``simulate``, ``report``, ``records`` (seconds each), and a dry
    run documented to trip ("watch it trip"), which must end tripped (exit status 3); the trip
    ends it early.
``plan``
    A sweep with ``--plan``: every case expanded and every value checked on the profile, and
    the cases counted; running the cases is ``tests/integration/test_sweep.py``'s job.
``resolve``
    ``dry-run``, ``rig``, ``identify actuator``: the command itself runs up to the moment it
    would open the CAN bus (options parsed, the profile loaded with ``--set`` and ``--variant``
    and refused where the command refuses it, the record processed and checked against the
    table, the controller built for the rig, an excitation checked against the force limits),
    and stops there: opening the bus is replaced by :class:`ReachedTheBus`, and the virtual
    rig's process is not started.
``parse``
    The options parsed and validated, and the profile loaded when it is a file here, for an
    example that needs what a test machine does not have; the reason says what.
"""

from __future__ import annotations

import argparse
import re
import shlex
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import build_parser, main
from harness.commands.options import load_acknowledged
from harness.motions.catalog import ENV_RECORDS_DIR
from tests.conftest import REPO, SHARED_RECORDS

README = REPO / "README.md"
#: How the docs name the records folder beside the checkout.
DOCUMENTED_RECORDS = "../shared/data/ground_motions"
#: Words of an example's comment that document a trip as its outcome.
TRIP = re.compile(r"\btrip\b")
#: Names of records that only the shared data holds (the synthetic ones need nothing).
REAL_RECORDS = re.compile(r"el_centro|hachinohe|pacoima|ground_motions|profiles/studies/")
#: Commands that open a CAN bus, checked up to it (``resolve``).
BUS_COMMANDS = ("dry-run", "rig", "identify")
#: Commands cheap enough to run as written.
OFFLINE_COMMANDS = ("simulate", "report", "records", "replay")


class ReachedTheBus(Exception):
    """Raised where the command would open the CAN bus: everything before it was resolved and accepted."""


@dataclass
class Example:
    """One documented command: its words, its comment and where it is written."""

    argv: list[str]
    comment: str
    where: str

    @property
    def text(self) -> str:
        return shlex.join(["harness", *self.argv])


@dataclass
class Block:
    """Examples written together (a README code block, one command's --help), run in order in one folder.

    ``environment``: the variables the README has exported by the end of this block, as written.
    """

    name: str
    examples: list[Example] = field(default_factory=list)
    other_lines: list[str] = field(default_factory=list)
    environment: dict[str, str] = field(default_factory=dict)


#: ``export NAME=VALUE`` in a README block: the reader sets it in their shell, from the checkout's root.
EXPORT = re.compile(r"^export\s+([A-Z_][A-Z0-9_]*)=(\S+)")


@dataclass(frozen=True)
class Check:
    kind: str  # "run", "plan", "resolve" or "parse"
    reason: str
    status: int = exit_codes.OK


# ------------------------------------------------------------------ reading the docs


def _split_comment(line: str) -> tuple[str, str]:
    """The command and its trailing comment (``# ...`` in the README, ``  (...)`` in --help)."""
    match = re.search(r"\s#\s*(.*)$", line) or re.search(r"\s{2,}(\(.*)$", line)
    return (line[:match.start()], match.group(1)) if match else (line, "")


def _example(line: str, where: str) -> Example:
    command, comment = _split_comment(line.strip())
    words = shlex.split(command)
    if words and words[-1] == "&":  # started in the background in a two-terminal recipe
        words.pop()
    assert words[0] == "harness", line
    return Example(words[1:], comment, where)


def readme_blocks() -> list[Block]:
    """The README's ``sh`` blocks: each line (backslash continuations joined) a command."""
    blocks = []
    text = README.read_text(encoding="utf-8")
    exported: dict[str, str] = {}
    for number, match in enumerate(re.finditer(r"^```sh\n(.*?)^```", text, re.M | re.S)):
        line_no = text.count("\n", 0, match.start()) + 1
        block = Block(f"README.md:{line_no}")
        for line in match.group(1).replace("\\\n", " ").splitlines():
            if not line.strip():
                continue
            if line.lstrip().startswith("harness "):
                block.examples.append(_example(line, f"{block.name} (block {number})"))
            else:
                block.other_lines.append(line.strip())
                export = EXPORT.match(_split_comment(line.strip())[0])
                if export:
                    exported[export.group(1)] = export.group(2)
        block.environment = dict(exported)
        blocks.append(block)
    return blocks


def readme_environment() -> dict[str, str]:
    """Everything the README exports, in the end (what a reader's shell has when reading ``--help``)."""
    blocks = readme_blocks()
    return blocks[-1].environment if blocks else {}


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _command_parsers() -> Iterator[tuple[str, argparse.ArgumentParser]]:
    for name, parser in _subparsers(build_parser()).items():
        yield name, parser
        for kind, sub in _subparsers(parser).items():
            yield f"{name} {kind}", sub


def help_blocks() -> list[Block]:
    """The "example(s):" section of each command's --help, as the user reads it (after the README)."""
    blocks = []
    environment = readme_environment()
    for name, parser in _command_parsers():
        block = Block(f"harness {name} --help", environment=dict(environment))
        lines = parser.format_help().splitlines()
        starts = [i for i, line in enumerate(lines) if re.fullmatch(r"examples?:", line.strip())]
        assert starts, f"{block.name} has no example (README: every command has --help with an example)"
        for line in lines[starts[0] + 1:]:
            if not line.strip():
                break
            if line.strip().startswith("harness "):
                block.examples.append(_example(line, block.name))
            elif block.examples:  # a line describing the example above it
                block.examples[-1].comment += " " + line.strip()
        blocks.append(block)
    return blocks


# ------------------------------------------------------------------ deciding the check


def _placeholder(args: argparse.Namespace, example: Example) -> str:
    """Why the example names something the reader supplies ("" if it does not)."""
    if re.search(r"<[^>]+>", " ".join(example.argv)):
        return f"{example.text}: a <placeholder> the reader fills in"
    for attribute in ("profile", "study"):
        value = getattr(args, attribute, None)
        if value is not None and not Path(value).is_file() and not (REPO / value).is_file():
            return f"{attribute} {value} is the reader's own file, not shipped"  # a shipped one must be found
    return ""


def check_for(example: Example, args: argparse.Namespace, records: bool, after_records: bool = False) -> Check:
    """The check of one parsed example (see the module docstring).

    ``after_records``: an earlier example of its block names a real record, so without the records
    this one would read what that one could not make (``harness report study/`` after ``simulate ... --out study/``).
    """
    command = example.argv[0]
    placeholder = _placeholder(args, example)
    if placeholder:
        return Check("parse", placeholder)
    if command == "run":
        return Check("parse", "drives a real rig on a real CAN channel")
    channel = str(getattr(args, "channel", "") or "")
    if getattr(args, "interface", None) == "socketcan" and not channel.startswith("vcan"):
        return Check("parse", f"needs real CAN hardware on {channel}")
    if command == "sweep":
        if args.scheduler or args.local_cluster:
            return Check("parse", "needs a Dask cluster")
        if args.summarize:
            return Check("parse", "summarizes the results of a sweep run before (192 cases: minutes)")
    if not records and REAL_RECORDS.search(example.text):
        return Check("parse", f"the real records are not in {SHARED_RECORDS}")
    if not records and after_records:
        return Check("parse", f"follows an example of its block that needs the real records, not in {SHARED_RECORDS}")
    if command == "sweep":
        return Check("plan", "expands and checks every case; running them is test_sweep.py's job")
    if command in BUS_COMMANDS:
        if TRIP.search(example.comment):
            return Check("run", "documented to trip: it must end tripped", exit_codes.TRIPPED)
        return Check("resolve", "checked up to opening the CAN bus")
    assert command in OFFLINE_COMMANDS, f"{example.where}: no check decided for {example.text}"
    return Check("run", "offline: seconds")


# ------------------------------------------------------------------ running the checks


@contextmanager
def _no_rig_process(profile, can, lockstep, motion, external_rig=False):
    from harness.runs.dry_run import RigCoordinator

    yield RigCoordinator(lockstep, 1.0 / profile.control.rate_hz)


def _reach_the_bus(*_args, **_kwargs):
    raise ReachedTheBus


def _resolve(monkeypatch: pytest.MonkeyPatch, argv: list[str]) -> int | None:
    """Run the command with the bus replaced by :class:`ReachedTheBus`; None when it got there."""
    with monkeypatch.context() as patch:
        patch.setattr("harness.runs.session.open_harness", _reach_the_bus)
        patch.setattr("harness.runs.rig_service.open_rig", _reach_the_bus)
        patch.setattr("harness.runs.dry_run.serving_virtual_rig", _no_rig_process)
        patch.setattr("harness.runs.identify.serving_virtual_rig", _no_rig_process)
        try:
            return main(argv)
        except ReachedTheBus:
            return None


def _parse(argv: list[str]) -> argparse.Namespace:
    try:
        return build_parser().parse_args(argv)
    except SystemExit as refused:
        raise AssertionError(f"refused by the option parser (exit status {refused.code})") from None


def _with_records(argv: list[str]) -> list[str]:
    return [word.replace(DOCUMENTED_RECORDS, str(SHARED_RECORDS)) for word in argv]


def _exported(value: str) -> str:
    """An exported value as the reader's shell has it: ``$PWD`` is the checkout's root, where they run it."""
    return value.replace("$PWD", str(REPO)).replace("${PWD}", str(REPO))


def _check(example: Example, monkeypatch: pytest.MonkeyPatch, folder: Path, capsys, after_records: bool = False) -> str:
    """Check one example; a line for the log. Raises AssertionError naming the example when it fails."""
    records = (SHARED_RECORDS / "elcentro_1940_NS.csv").is_file()
    argv = _with_records(example.argv)
    try:
        args = _parse(argv)
        check = check_for(example, args, records, after_records)
        if getattr(args, "profile", None) and Path(args.profile).is_file() and hasattr(args, "allow_weaker_safety"):
            load_acknowledged(args)  # --set and --variant as the command loads them
        if check.kind == "parse":
            return f"parsed   {example.text}: {check.reason}"
        if check.kind == "plan":
            status = main([*argv, "--plan", "--out", tempfile.mkdtemp(prefix="sweep-results-", dir=folder)])
        elif check.kind == "resolve":
            status = _resolve(monkeypatch, argv)
            assert status is None, f"stopped with exit status {status} before opening the bus"
            return f"resolved {example.text}: {check.reason}"
        else:
            extra = ["--log-dir", str(folder / "logs")] if argv[0] in BUS_COMMANDS else []
            status = main([*argv, *extra])
        assert status == check.status, f"exit status {status}, documented {check.status} ({check.reason})"
        return f"ran      {example.text}: exit status {status}"
    except Exception as failure:
        captured = capsys.readouterr()
        raise AssertionError(f"{example.where}: {example.text}\n  {failure}\n{captured.out[-3000:]}{captured.err[-3000:]}") \
            from failure
    finally:
        capsys.readouterr()


BLOCKS = readme_blocks() + help_blocks()


@pytest.mark.parametrize("block", BLOCKS, ids=[block.name for block in BLOCKS])
def test_every_documented_example_does_what_its_docs_say(block: Block, tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)  # outputs (study/, out.json, frf/) land here; profiles are found by name
    monkeypatch.delenv(ENV_RECORDS_DIR, raising=False)  # only what the README told the reader to set
    for name, value in block.environment.items():
        monkeypatch.setenv(name, _exported(value))
    makefile = (REPO / "Makefile").read_text()
    for line in block.other_lines:
        words = line.split()
        if words[0] == "make":  # the quick start: the targets must exist (they run the dry run and every test)
            assert re.search(rf"^{re.escape(words[1])}:", makefile, re.M), f"{block.name}: no Makefile target {line}"
        elif words[0] == "export":  # applied above, to this block and every later one
            assert EXPORT.match(line), f"{block.name}: an export the test does not read: {line!r}"
        else:
            assert words[0] == "sudo", f"{block.name}: no check decided for {line!r}"  # kernel set-up (root)
    named = [bool(REAL_RECORDS.search(example.text)) for example in block.examples]
    log = [_check(example, monkeypatch, tmp_path, capsys, any(named[:k])) for k, example in enumerate(block.examples)]
    print("\n".join(log))
    assert block.examples or block.other_lines


def test_the_examples_are_found() -> None:
    """The reader of the docs finds what the test checks: a changed format must not empty the test."""
    found = {example.argv[0] for block in BLOCKS for example in block.examples}
    assert {"dry-run", "rig", "run", "identify", "simulate", "sweep", "report", "records"} <= found
    assert sum(len(block.examples) for block in BLOCKS) >= 40
    trips = [example for block in BLOCKS for example in block.examples if TRIP.search(example.comment)]
    assert trips and all(check_for(e, _parse(_with_records(e.argv)), True).status == exit_codes.TRIPPED for e in trips)
    # the README says once where the records are, and it names the folder the tests read them from
    told = readme_environment().get(ENV_RECORDS_DIR)
    assert told and Path(_exported(told)).resolve() == SHARED_RECORDS.resolve()
    first_record = next(b for b in readme_blocks() if any(REAL_RECORDS.search(e.text) for e in b.examples))
    assert ENV_RECORDS_DIR in first_record.environment, f"{first_record.name} names a record before the README says where"


#: A ``--set`` written in running text or an option's help: ``--set KEY.PATH=VALUE`` with a real key.
INLINE_SET = re.compile(r"--set\s+'?([a-z_]+(?:\.\w+)+=(?:\[[^\]]*\]|[^\s`')]+))")


def test_every_set_the_docs_mention_is_accepted_on_the_default_profile() -> None:
    """``--set`` values in the README's prose and in the options' help are examples too (``e.g. --set ...``).

    The examples' own ``--set`` values are checked with their commands above (several together).
    """
    from harness.profile import load_profile
    from harness.safety.weakening import require_acknowledged

    prose = re.sub(r"^```sh\n.*?^```", "", README.read_text(encoding="utf-8"), flags=re.M | re.S)  # blocks: run above
    texts = {"README.md": prose}
    texts.update({f"harness {name} --help, options": " ".join(str(action.help) for action in parser._actions)
                  for name, parser in _command_parsers()})
    found = 0
    for where, text in texts.items():
        for override in INLINE_SET.findall(text):
            found += 1
            try:
                profile = load_profile(None, overrides=[override])
                require_acknowledged(profile.safety_weakened, False, profile.source_path)
            except Exception as refused:
                raise AssertionError(f"{where}: --set {override} is refused: {refused}") from refused
    assert found >= 5


#: Options whose value is a file or folder the example writes.
OUTPUT_OPTIONS = ("--out", "--report", "--json")


def test_what_the_examples_write_in_the_checkout_is_ignored_by_git() -> None:
    """Run from the checkout, as the README's are, an example's results must not show up as changes to commit."""
    import shutil
    import subprocess

    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("not a git checkout")
    written = sorted({example.argv[i + 1] for block in BLOCKS for example in block.examples
                      for i, word in enumerate(example.argv[:-1]) if word in OUTPUT_OPTIONS and example.argv[i + 1] != "-"})
    assert {"frf/", "ident/bearing", "ident/structure", "study/"} <= set(written)
    paths = [f"{path.rstrip('/')}/identified.yaml" if not path.endswith(".json") else path for path in written
             if not Path(path).is_absolute() and not path.startswith(("..", "<"))]
    found = subprocess.run(["git", "check-ignore", "--no-index", *paths], cwd=REPO, capture_output=True, text=True)
    ignored = set(found.stdout.split())
    assert not [path for path in paths if path not in ignored], "not git-ignored: " + ", ".join(
        path for path in paths if path not in ignored)
