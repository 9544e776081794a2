"""One self-contained HTML page: runs, warnings, tables, and the plots embedded as data URIs.

The page needs no server and no other file: styles are inline and every PNG is a
``data:image/png;base64,...`` URI, so it can be mailed or archived on its own.
"""

from __future__ import annotations

import base64
import datetime as _dt
from collections.abc import Sequence
from html import escape

from harness.recording.reader import RunData
from harness.report.figure import PlotFile
from harness.report.labels import common_facts
from harness.report.peak_table import PeakTable
from harness.report.text_table import TextTable

_CSS = """
body { font-family: system-ui, -apple-system, 'Segoe UI', sans-serif; margin: 2em auto; max-width: 1260px; color: #222; }
h1 { font-size: 1.6em; } h2 { margin-top: 1.6em; border-bottom: 1px solid #ccc; }
h2.part { font-size: 1.4em; border-bottom: 2px solid #888; } h3 { margin-top: 1.2em; }
table { border-collapse: collapse; margin: 0.6em 0; font-size: 0.92em; }
th, td { border: 1px solid #bbb; padding: 3px 8px; } th { background: #f0f0f0; }
td.num { text-align: right; font-variant-numeric: tabular-nums; }
.warn { background: #fff4d6; border-left: 4px solid #e0a000; padding: 0.5em 1em; }
.note { color: #555; font-size: 0.88em; }
figure { margin: 1em 0; } figcaption { color: #444; font-size: 0.92em; }
img { max-width: 100%; height: auto; border: 1px solid #ddd; }
"""


def data_uri(plot: PlotFile) -> str:
    """``data:image/png;base64,...`` of a written plot."""
    return "data:image/png;base64," + base64.b64encode(plot.path.read_bytes()).decode("ascii")


def _replay_section(lines: Sequence[str]) -> str:
    """The replay lines under their own heading, as preformatted text (the command copies as it is); "" if none."""
    if not lines:
        return ""
    body = "\n".join(escape(line) for line in lines[1:])  # the first line is the summary's heading
    return f"<h2>Replay</h2><pre>{body}</pre>"


def _runs_section(runs: Sequence[RunData]) -> str:
    names = ("Run", "Folder", "Kind", "Outcome", "Controller", "Record", "Start (UTC)", "Ticks", "Dropped rows")
    header = "<tr>" + "".join(f"<th>{name}</th>" for name in names) + "</tr>"
    rows = []
    for run in runs:
        meta = run.metadata
        reason = f" ({meta.get('trip_reason')})" if meta.get("trip_reason") else ""
        dropped = (meta.get("recorder") or {}).get("dropped", {}).get("rows", "-")
        cells = (
            run.label,
            str(run.path),
            run.kind,
            run.outcome + reason,
            "passive" if run.is_passive else str(meta.get("controller", "-")),
            run.record_name or "-",
            str(meta.get("start_time", "-")),
            str(run.n_rows),
            str(dropped),
        )
        rows.append("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in cells) + "</tr>")
    return "<h2>Runs</h2><table>" + header + "".join(rows) + "</table>" + _versions(runs)


def _versions(runs: Sequence[RunData]) -> str:
    lines = []
    for run in runs:
        packages = run.metadata.get("packages") or {}
        text = ", ".join(f"{k} {v}" for k, v in packages.items())
        commit = run.metadata.get("git_commit") or "no git commit"
        if run.metadata.get("git_dirty"):
            commit += " (with local changes)"
        host = str(run.metadata.get("host", "-"))
        lines.append(f"<li>{escape(run.label)}: {escape(text)}; {escape(str(commit))}; host {escape(host)}</li>")
    return "<p class='note'>Software:</p><ul class='note'>" + "".join(lines) + "</ul>"


def _figure_html(plot: PlotFile) -> str:
    return (
        f"<figure><img src='{data_uri(plot)}' alt='{escape(plot.title)}' width='{plot.width_px}' height='{plot.height_px}'>"
        f"<figcaption>{escape(plot.title)}</figcaption></figure>"
    )


def report_html(
    runs: Sequence[RunData], tables: Sequence[PeakTable], plots: Sequence[PlotFile], warnings: Sequence[str],
    context: Sequence[TextTable] = (),
    replay: Sequence[str] = (),
) -> str:
    """The whole report page.

    Parameters
    ----------
    runs : sequence of RunData
        Labelled (:func:`harness.report.labels.with_labels`).
    tables : sequence of PeakTable
    plots : sequence of PlotFile
        Written PNGs, embedded in order.
    warnings : sequence of str
        Shown in a highlighted box at the top.
    context : sequence of TextTable
        Record, table motion, controller, timing, events: after the peak tables.
    replay : sequence of str
        How the runs link to their replays (:mod:`harness.report.replay_link`): after the runs, as text.
    """
    made = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    shared = common_facts(runs)
    title = "Shaking-table run report" + (f": {shared}" if shared else "")
    warn = "".join(f"<p class='warn'>{escape(w)}</p>" for w in warnings)
    parts = [
        "<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>",
        f"<title>{escape(title)}</title><style>{_CSS}</style></head><body>",
        f"<h1>{escape(title)}</h1><p class='note'>Generated {escape(made)} by shaketable-harness. "
        f"Runs are labelled by what differs between them.</p>",
        warn,
        _runs_section(runs),
        _replay_section(replay),
        "<h2 class='part'>Peak tables</h2>",
        *(table.to_html().replace("<h2>", "<h3>").replace("</h2>", "</h3>") for table in tables),
        "<h2 class='part'>What the runs were run with</h2>" if context else "",
        *(table.to_html(level=3) for table in context),
        "<h2 class='part'>Plots</h2>" if plots else "",
        *(_figure_html(p) for p in plots),
        "</body></html>",
    ]
    return "\n".join(parts)
