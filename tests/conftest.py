"""Shared fixtures: paths to the repository, its profiles, and the shared ground-motion records; edited DBCs."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import settings

from drivers.transports.seqpacket.bus import SeqPacketBus
from tests import realtime_runs

# No hypothesis deadline: how long an example takes is not what these tests judge (speed targets are in benchmarks/),
# and the first example of a compiled kernel pays its load from numba's cache: 2.46 s against the default 200 ms
# deadline in a fresh pytest-xdist worker on a loaded machine (test_frame_kernel's CRC test, issue 32 item 5).
settings.register_profile("suite", deadline=None)
settings.load_profile("suite")

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


@pytest.fixture(autouse=True)
def _captured_width(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every test starts without ``$COLUMNS``, as a command whose output is captured (a log file, a pipe) runs.

    The commands print at ``$COLUMNS`` where it is set, else unwrapped when captured (harness/commands/output.py),
    and the tests read their one-line outputs so. A pytest-xdist worker starts with ``COLUMNS=80`` in its
    environment, which wrapped them there; a test that wants a width sets it itself.
    """
    monkeypatch.delenv("COLUMNS", raising=False)


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


# ------------------------------------------------------------ real-time runs: counted, reported (tests/realtime_runs.py)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """Attach the real-time runs a test (or its module's fixture) made to its report, before the report is made.

    The report carries them from an xdist worker to the stage's summary, and into the JUnit XML as properties.
    """
    while realtime_runs.RECORDS:
        item.user_properties.append((realtime_runs.PROPERTY, realtime_runs.RECORDS.pop(0).as_dict()))
    yield


def pytest_terminal_summary(terminalreporter, exitstatus, config) -> None:
    """One line at the end of the stage: the real-time runs, the pre-flight's refusals and the waits for a quiet second."""
    latest: dict[str, list] = {}  # a test's last report holds every record of its earlier phases too
    for reports in terminalreporter.stats.values():
        for report in reports:
            properties = [value for name, value in getattr(report, "user_properties", ()) if name == realtime_runs.PROPERTY]
            if properties and len(properties) >= len(latest.get(report.nodeid, [])):
                latest[report.nodeid] = properties
    if not latest:
        return
    records = [record for properties in latest.values() for record in properties]
    terminalreporter.write_sep("-", "real-time runs")
    for nodeid, properties in sorted(latest.items()):
        for record in properties:
            if record["refusals"] or record["never_quiet"]:
                terminalreporter.write_line(
                    f"{nodeid}: {record['what']}: {record['runs']} runs, {len(record['refusals'])} refused "
                    f"by the pre-flight, {record['waited_s']:.0f} s waiting for a quiet second")
                for figures in record["refusals"]:
                    terminalreporter.write_line(f"    refused: {figures}")
    terminalreporter.write_line(realtime_runs.summary_line(records))
