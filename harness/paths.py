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
