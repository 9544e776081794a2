"""The checkout's folders: run folders land in ``logs/`` beside ``harness/``, wherever the module that uses them sits."""

from __future__ import annotations

from harness.paths import LOG_DIR, PROFILE_DIR, PROJECT_ROOT
from tests.conftest import REPO


def test_the_folders_are_the_checkouts_own():
    assert PROJECT_ROOT == REPO
    assert LOG_DIR == REPO / "logs"  # a module moved into harness/runs/ once wrote them into the package
    assert (PROFILE_DIR / "nceer_4dof.yaml").is_file()
    assert (LOG_DIR / "README.md").is_file()
