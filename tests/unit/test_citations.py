"""Every file the project cites exists in the project: docs, READMEs, and the code's docstrings and comments.

What counts as a cited path (:func:`cited_paths`), in the text of README.md, docs/*.md,
drivers/protocol/PROTOCOL.md, benchmarks/README.md, logs/README.md, the Makefile, pyproject.toml, and
the docstrings and comments of every module under harness/, drivers/, tests/, benchmarks/ and
scripts/ (string literals that are not docstrings are code, not citations):

- a token of two or more ``/``-separated parts (``harness/loop/tick.py``, ``tests/unit/``) whose first
  part is a top-level folder of the project (:data:`TOP_LEVEL`) or ``.``/``..``;
- a token of two or more parts ending in a source or document suffix (:data:`SUFFIXES`), which
  may be written relative to the citing file's folder;
- a document's bare name in capitals, such as ``SAFETY.md``.

It must exist, read from the repository's root or from the citing file's folder (a bare
document name also from docs/). Left out: URLs; templated names (``logs/<run>/``, ``{name}``,
a placeholder in capitals such as ``DIR/`` or ``commands/NAME.py``); the run folders the
harness writes under logs/ (only logs/README.md is in the repository); ``../shared/...``, the
data beside the checkout that the project must not contain; and the few entries of
:data:`NOT_FILES_OF_THE_PROJECT`, each with its reason.
"""

from __future__ import annotations

import ast
import io
import re
import tokenize
from collections.abc import Iterator
from pathlib import Path

from tests.conftest import REPO

#: Top-level folders of the project: a token starting with one of them is a path.
TOP_LEVEL = ("harness", "drivers", "tests", "docs", "benchmarks", "scripts", "profiles", "logs", ".ci")
#: Suffixes that make a token of two or more parts a path wherever it starts.
SUFFIXES = (".py", ".md", ".yaml", ".dbc", ".json", ".toml")
#: Tokens that look like paths of the project and are not, each with the reason.
NOT_FILES_OF_THE_PROJECT = {
    "../eight_story.yaml": "a study file's own `profile:` value, relative to profiles/studies/ (README, harness/sweep/study.py)",
    "studies/ida_friction.yaml": "a shipped study as a user may name it, relative to profiles/ (harness/commands/options.py)",
    "results/sweep.json": "a file inside a sweep's output folder, written by the sweep",
    "profiles/my_rig.yaml": "the user's own profile in an example command (README)",
}
#: Documents cited in the text and not the code: the Markdown files, and the two build files' comments and paths.
DOCUMENTS = ("README.md", "drivers/protocol/PROTOCOL.md", "benchmarks/README.md", "logs/README.md", "Makefile", "pyproject.toml")
PACKAGES = ("harness", "drivers", "tests", "benchmarks", "scripts")

_URL = re.compile(r"\w+://\S+")
_PATH = re.compile(r"(?<![\w./~:@$<>{})\\-])((?:\.{1,2}/)*[\w.-]+(?:/[\w.-]+)+/?|[A-Z][A-Z0-9_]*\.md)(?![\w<{*(])")
_DOCUMENT = re.compile(r"[A-Z][A-Z0-9_]*\.md")
_PLACEHOLDER = re.compile(r"[A-Z][A-Z0-9_]+(\.\w+)?")


def cited_paths(text: str) -> Iterator[str]:
    """The tokens of ``text`` that cite a file or folder of the project (see the module), in order."""
    for match in _PATH.finditer(_URL.sub(" ", text)):
        token = match.group(1).rstrip(".,-")
        parts = token.rstrip("/").split("/")
        if any(_PLACEHOLDER.fullmatch(part) and not _DOCUMENT.fullmatch(part) for part in parts):
            continue  # DIR/summary.txt, harness/commands/NAME.py
        if len(parts) == 1:
            if _DOCUMENT.fullmatch(token):
                yield token  # a document's name in capitals
        elif parts[0] in (".", "..") or parts[0] in TOP_LEVEL or token.rstrip("/").endswith(SUFFIXES):
            yield token


def _left_out(token: str) -> bool:
    path = token.rstrip("/")
    if token.startswith("../") and path.lstrip("./").split("/")[0] == "shared":
        return True  # the records and the spec beside the checkout
    if path.startswith("logs/") and path not in ("logs/README.md", "logs/.gitkeep"):
        return True  # a run folder the harness writes
    return token in NOT_FILES_OF_THE_PROJECT


def _exists(token: str, folder: Path) -> bool:
    path = token.rstrip("/")
    places = [REPO, folder] + ([REPO / "docs"] if "/" not in path else [])
    for place in places:
        target = (place / path).resolve()
        if target.is_relative_to(REPO) and target.exists():
            return True
    return False


def code_texts(source: str) -> Iterator[str]:
    """The docstrings (module, classes, functions) and the comments of a Python source."""
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            docstring = ast.get_docstring(node, clean=False)
            if docstring:
                yield docstring
    for token in tokenize.generate_tokens(io.StringIO(source).readline):
        if token.type == tokenize.COMMENT:
            yield token.string


def _citing_files() -> list[Path]:
    documents = [REPO / name for name in DOCUMENTS] + sorted((REPO / "docs").glob("*.md"))
    return documents + [path for package in PACKAGES for path in sorted((REPO / package).rglob("*.py"))]


def missing_citations() -> dict[str, list[str]]:
    """Per citing file (relative to the repository), the cited paths that do not exist."""
    missing: dict[str, list[str]] = {}
    for path in _citing_files():
        text = path.read_text(encoding="utf-8")
        texts = code_texts(text) if path.suffix == ".py" else [text]
        for chunk in texts:
            for token in cited_paths(chunk):
                if not _left_out(token) and not _exists(token, path.parent):
                    missing.setdefault(str(path.relative_to(REPO)), []).append(token)
    return missing


def test_every_cited_path_exists() -> None:
    missing = missing_citations()
    assert not missing, "cited paths that do not exist:\n" + "\n".join(
        f"  {source}: {', '.join(sorted(set(tokens)))}" for source, tokens in sorted(missing.items())
    )


def test_the_rule_finds_paths_and_leaves_out_what_is_not_one() -> None:
    text = (
        "See harness/loop/tick.py, `docs/SAFETY.md`. and rig/table.py; DESIGN.md too; also the folder tests/unit/. "
        "Not: https://example.org/a/b.py, logs/<run>/signals.csv, {folder}/x.py, $(BIN)/python, "
        "harness.loop.tick, a/b, and/or, summary.md, DIR/summary.txt, harness/commands/NAME.py."
    )
    assert list(cited_paths(text)) == ["harness/loop/tick.py", "docs/SAFETY.md", "rig/table.py", "DESIGN.md", "tests/unit/"]


def test_a_missing_file_is_reported_and_an_existing_one_is_not(tmp_path: Path) -> None:
    assert _exists("harness/loop/tick.py", tmp_path) and _exists("SAFETY.md", tmp_path)
    assert _exists("loop/tick.py", REPO / "harness")  # relative to the citing file's folder
    assert not _exists("DESIGN_NOTES_THAT_DO_NOT_EXIST.md", tmp_path)
    assert not _exists("harness/loop/no_such_module.py", tmp_path)
    assert not _exists("../../etc/passwd", REPO / "docs"), "outside the repository is never found"
    assert _left_out("../shared/data/ground_motions/") and _left_out("logs/2026-11-22T03-10-05_x/signals.csv")
    assert not _left_out("logs/README.md") and not _left_out("harness/x.py")


def test_code_texts_are_docstrings_and_comments_not_strings() -> None:
    source = '"""Module: docs/A.md."""\nX = "docs/B.md"  # docs/C.md\ndef f():\n    """docs/D.md"""\n'
    assert sorted(code_texts(source)) == ["# docs/C.md", "Module: docs/A.md.", "docs/D.md"]
