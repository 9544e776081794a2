"""Shared fixtures: paths to the repository, its profiles, and the shared ground-motion records; edited DBCs."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from drivers.seqpacket.bus import SeqPacketBus

REPO = Path(__file__).resolve().parent.parent
PROFILES = REPO / "profiles"
SHARED_RECORDS = REPO.parent / "shared" / "data" / "ground_motions"


def edited_dbc(folder: Path, source: Path, *replacements: tuple[str, str], name: str = "edited.dbc") -> Path:
    """A copy of the DBC ``source`` in ``folder`` with each ``(old, new)`` replaced; each ``old`` must occur."""
    text = source.read_text(encoding="cp1252")
    for old, new in replacements:
        assert old in text, f"{old!r} is not in {source.name}"
        text = text.replace(old, new)
    path = folder / name
    path.write_text(text, encoding="cp1252")
    return path


@pytest.fixture(scope="session")
def records_dir() -> Path:
    """The real accelerograms beside the checkout; skips the test where they are absent."""
    if not (SHARED_RECORDS / "elcentro_1940_NS.csv").is_file():
        pytest.skip(f"real records not found in {SHARED_RECORDS} (they are kept outside the project; see README)")
    return SHARED_RECORDS


@pytest.fixture(scope="session")
def eight():
    """The eight-story building of SPEC 6a (profiles/eight_story.yaml)."""
    from harness.profile import load_profile

    return load_profile(PROFILES / "eight_story.yaml").structure


@pytest.fixture(scope="session")
def rig():
    """The quarter-scale rig's building of SPEC 6b (profiles/nceer_4dof.yaml)."""
    from harness.profile import load_profile

    return load_profile(PROFILES / "nceer_4dof.yaml").structure


@pytest.fixture
def buses() -> Iterator[list[SeqPacketBus]]:
    """``seqpacket`` buses a test opens; all shut down afterwards."""
    opened: list[SeqPacketBus] = []
    yield opened
    for bus in opened:
        bus.shutdown()
