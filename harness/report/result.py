"""What ``harness report`` produced: :class:`ReportResult`, the files it wrote and what they hold.

Built by :func:`harness.report.build.build_report` and read by
:func:`harness.report.summary.summary_text`; it lives below both, so neither imports the other.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # names for the fields' types only: reading a result loads neither matplotlib nor rich
    from harness.recording.reader import RunData
    from harness.report.figure import PlotFile
    from harness.report.peak_table import PeakTable
    from harness.report.text_table import TextTable


@dataclass
class ReportResult:
    """What :func:`harness.report.build.build_report` produced.

    Attributes
    ----------
    out_dir : Path
        Where the files are.
    html_path : Path
        The self-contained page.
    plots : list of PlotFile
        Written PNGs (plots without data are skipped).
    tables : list of PeakTable
        Peak, pair, reference and comparison tables.
    context : list of TextTable
        Record, target against achieved table motion, controller, loop timing, events and interlocks.
    runs : list of RunData
        The runs read, each with its report label (:attr:`RunData.label`).
    table_files : list of Path
        One CSV per table (``table_1_peak_responses.csv`` ...), for spreadsheets and MATLAB.
    warnings : list of str
        Incomplete runs, torn files, mismatched records ...
    summary : str
        Plain-text summary (``summary.txt``; the console prints it at its own width).
    replay : list of str
        How each run links to its replay (:mod:`harness.report.replay_link`): the command that
        replays it and the replays found, or why it cannot be replayed; [] where no run has a replay.
    """

    out_dir: Path
    html_path: Path
    plots: list[PlotFile] = field(default_factory=list)
    tables: list[PeakTable] = field(default_factory=list)
    context: list[TextTable] = field(default_factory=list)
    runs: list[RunData] = field(default_factory=list)
    table_files: list[Path] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    summary: str = ""
    replay: list[str] = field(default_factory=list)
