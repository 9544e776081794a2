"""A log directory that cannot take run folders is refused before anything starts, and the probe leaves nothing behind."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.recording import RunFolder, RunFolderError
from harness.recording.runfolder import check_log_dir
from harness.recording.writable import directory_problem
from harness.signals.columns import canonical_columns

HAS_PROC = Path("/proc/self").is_dir() and Path("/sys/kernel").is_dir()


def test_a_folder_still_to_be_made_is_writable_and_nothing_is_left_behind(tmp_path):
    (tmp_path / "kept").write_text("x")
    before = sorted(p.name for p in tmp_path.iterdir())
    assert directory_problem(tmp_path / "new" / "deeper") is None
    assert directory_problem(tmp_path) is None
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # no probe folder, and "new" was not made


def test_a_file_and_a_path_below_a_file_are_refused(tmp_path):
    file = tmp_path / "file.txt"
    file.write_text("x")
    assert directory_problem(file) == f"{file} is a file, expected a directory (existing or to be created)"
    assert directory_problem(file / "sub") == f"{file / 'sub'} is below {file}, which is a file, expected a directory " \
        "(existing or to be created)"


@pytest.mark.skipif(not HAS_PROC, reason="needs Linux's /proc and /sys")
@pytest.mark.parametrize("path", ["/proc/self/x", "/proc/1", "/sys/kernel"])
def test_kernel_folders_are_refused_even_for_root(path):
    """Root passes every access() test; these still refuse a new entry, so the probe must try one."""
    problem = directory_problem(path)
    assert problem is not None and problem.startswith(f"{path}: cannot create a folder there")
    assert problem.endswith("expected a writable directory")


def test_check_log_dir_and_run_folder_creation_raise_the_harness_error(tmp_path):
    blocker = tmp_path / "file.txt"
    blocker.write_text("x")
    with pytest.raises(RunFolderError, match=r"log directory .*file.txt/logs is below .*file.txt, which is a file"):
        check_log_dir(blocker / "logs")
    with pytest.raises(RunFolderError, match="cannot create the log directory"):  # not a bare NotADirectoryError
        RunFolder.create(blocker / "logs", "p", "dry-run", {}, canonical_columns(3))


@pytest.mark.skipif(not HAS_PROC, reason="needs Linux's /proc")
def test_a_session_refuses_the_log_directory_before_the_bus_opens(monkeypatch):
    """The review's field report: the run folder's mkdir ran after the bus was open, and gave a traceback."""
    from harness.profile import load_profile
    from harness.runs import session
    from tests.conftest import PROFILES

    opened = []
    monkeypatch.setattr(session, "open_harness", lambda can: opened.append(can))
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    settings = session.SessionSettings(kind="dry-run", can=profile.can_settings(), duration_s=1.0, log_dir=Path("/proc/1"))
    with pytest.raises(RunFolderError, match="log directory /proc/1: cannot create a folder there"):
        session.run_session(profile, settings)
    assert opened == []
