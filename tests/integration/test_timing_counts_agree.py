"""Every display of a real-time run's timing counts shows the same numbers (issue 33, item 5).

A review saw one run give the console "overruns 57", the timing plot "9 overruns", the console
"missed periods 62" and signals.csv's overrun column summing to 62: three counts under two names.
Each count now has one definition (harness/signals/timing_counts.py; docs/ARCHITECTURE.md,
"Timing counts"). This test runs the default dry run in real time (not lockstep, no fake clock),
the virtual rig in its own process, and makes sure it stalls: once RUNNING it stops the harness
process (SIGSTOP) for 10 ms, five periods at 500 Hz and half the 20 ms stall budget, a few times,
on top of whatever the loaded machine adds. It then reads the counts from every place that shows
them and requires one number each:

- the live console's last frame and the printed timing summary (stdout);
- ``metadata.json`` (``summary.timing``);
- ``signals.csv``'s ``overrun`` column;
- the timing plot's figure (its lateness legend);
- the ``stall_ridden_through`` / ``stall_past_budget`` events.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure

from harness import exit_codes
from harness.recording import load_run
from harness.report import plots_timing
from harness.report.plot_common import PlotOptions
from harness.signals.timing_counts import TimingCounts
from tests.realtime_runs import end, pause, running_folder

DURATION_S = 3.0
#: Each stop of the harness process (s) and how many: stalls the loop rides through, whatever the host.
STOP_S, STOPS = 0.010, 4
#: The counts as every display prints them (harness.signals.timing_counts.stall_words).
STALL_LINE = re.compile(r"(\d+) missed periods? in (\d+) stalls? \(ridden through (\d+), past the budget (\d+)\)")


@pytest.fixture(scope="module")
def stalled_run(tmp_path_factory) -> tuple[str, Path]:
    log_dir = tmp_path_factory.mktemp("timing_counts")
    process = subprocess.Popen(
        [sys.executable, "-m", "harness.cli", "dry-run", "--duration", str(DURATION_S), "--log-dir", str(log_dir)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env={**os.environ, "COLUMNS": "250"},
    )
    try:
        folder = running_folder(log_dir, process)
        if folder is None:
            out, err = process.communicate(timeout=120)
            if process.returncode == exit_codes.INPUT_ERROR and "pre-flight" in (out + err):
                pytest.skip("the pre-flight refused this busy host before arming: " + out.strip()[-300:])
            pytest.fail("the run never reached RUNNING: " + out[-2000:] + err[-2000:])
        for _ in range(STOPS):
            pause(process, STOP_S, after_s=0.2)
        out, err = process.communicate(timeout=300)
    finally:
        end(process)
    # a stop can land on a loaded host's own stall and pass the budget (loop_stall): the counts must agree all the same
    assert process.returncode in (exit_codes.OK, exit_codes.TRIPPED), out[-3000:] + err[-3000:]
    return out, folder


def _printed(out: str) -> list[tuple[int, int, int, int]]:
    return [tuple(int(n) for n in match) for match in STALL_LINE.findall(out)]  # type: ignore[misc]


def test_the_run_stalled_in_real_time(stalled_run) -> None:
    _, folder = stalled_run
    timing = json.loads((folder / "metadata.json").read_text())["summary"]["timing"]
    assert timing["lockstep"] is False
    assert timing["stalls"] >= 1 and timing["missed_periods"] >= timing["stalls"]  # each stop is at least 5 periods
    assert timing["longest_stall_s"] >= STOP_S


def test_console_metadata_signals_events_and_plot_show_the_same_counts(stalled_run, monkeypatch) -> None:
    out, folder = stalled_run
    metadata = json.loads((folder / "metadata.json").read_text())
    assert metadata["recorder"]["dropped"]["rows"] == 0, "a dropped row would leave the column short of the loop's count"
    timing = metadata["summary"]["timing"]
    loop = (timing["missed_periods"], timing["stalls"], timing["stalls_ridden_through"], timing["gaps_past_budget"])
    assert "overruns" not in timing  # one count, one name: the missed periods

    # the console: the live panel's last frame and the printed summary, one line each
    printed = _printed(out)
    assert len(printed) == 2, out[-4000:]
    assert printed == [loop, loop]

    run = load_run(folder)
    column = TimingCounts.of_overrun_column(run["overrun"])
    assert (column.missed_periods, column.stalls) == (timing["missed_periods"], timing["stalls"])
    assert len(run["overrun"]) == timing["ticks"]  # every tick is a row: the column covers what the loop counted

    events = [e["name"] for e in run.events]
    assert (events.count("stall_ridden_through"), events.count("stall_past_budget")) == loop[2:]

    figures: list[Figure] = []
    save = plots_timing.save
    monkeypatch.setattr(plots_timing, "save", lambda fig, *args: figures.append(fig) or save(fig, *args))
    assert plots_timing.timing_plot([run], folder, PlotOptions()) is not None
    (figure,) = figures
    legends = [text.get_text() for ax in figure.axes if ax.get_legend() for text in ax.get_legend().get_texts()]
    lateness = [text for text in legends if "missed period" in text]
    assert len(lateness) == 1, legends
    assert f"{timing['missed_periods']} missed periods in {timing['stalls']} stall" in lateness[0]
    assert np.nansum(run["overrun"]) == timing["missed_periods"]
