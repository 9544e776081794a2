"""docs/SAFETY.md stays true: a row per check, rows as the code documents them (harness/safety/checks_doc.py), tests exist."""

from __future__ import annotations

import ast
import re
from functools import cache

import pytest

from harness.control.factory import build_controller_for_rig
from harness.errors import ProfileError
from harness.profile import load_profile
from harness.safety import SAFETY_TABLE
from harness.safety.checks import CHECK_NAMES
from tests.conftest import PROFILES, REPO

DOC = REPO / "docs" / "SAFETY.md"
REFERENCE = re.compile(r"`(tests/[\w/]+\.py)::(\w+)`")


def _rows() -> list[list[str]]:
    rows = []
    for line in DOC.read_text().splitlines():
        if line.startswith("| ") and not line.startswith("|---"):
            rows.append([cell.strip() for cell in re.split(r"(?<!\\)\|", line.strip().strip("|"))])
    return rows


def _check_rows() -> dict[str, list[str]]:
    return {row[0].strip("`"): row for row in _rows() if row[0].startswith("`") and row[0].strip("`") in CHECK_NAMES}


@cache
def _test_names(path: str) -> frozenset[str]:
    tree = ast.parse((REPO / path).read_text())
    return frozenset(node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)))


def test_every_check_of_the_code_has_a_row():
    rows = _check_rows()
    missing = [name for name in CHECK_NAMES if name not in rows]
    assert not missing, f"checks without a row in docs/SAFETY.md: {missing}"


def test_rows_agree_with_what_the_code_documents():
    rows = _check_rows()
    for record in SAFETY_TABLE:
        detects, bound, action, reset = (cell.replace("\\|", "|") for cell in rows[record.name][1:5])
        assert (detects, bound, action, reset) == (record.detects, record.bound, record.action, record.reset), record.name


def test_every_row_names_a_test_and_every_named_test_exists():
    references = 0
    for row in _rows():
        if row[0] in ("check", "fault", "problem", "direction", "property"):  # header rows
            continue
        found = REFERENCE.findall(row[-1])
        assert found, f"row {row[0]!r} names no test"
        for path, name in found:
            assert (REPO / path).is_file(), f"{row[0]}: {path} does not exist"
            assert name in _test_names(path), f"{row[0]}: {path} has no test {name}"
            references += 1
    assert references > 50


def test_inconsistent_limits_are_refused_at_load():
    with pytest.raises(ProfileError, match="soft_limit_m"):
        load_profile(PROFILES / "nceer_4dof.yaml", overrides=["safety.stroke.soft_limit_m=0.3"])


def test_full_state_controller_is_refused_on_a_rig():
    profile = load_profile(PROFILES / "eight_story.yaml")
    with pytest.raises(ProfileError, match="full state"):
        build_controller_for_rig(profile, "FSF-I")
