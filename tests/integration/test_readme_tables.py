"""Issue 33, item 4: the README's tables say what the commands print today.

The source's Table 2 (README, "Studies at scale") is checked against ``harness simulate`` run
as its study (``profiles/studies/robustness_table2.yaml``) runs each case: every cell must
round to what the command gives, to the digits the README shows. A change in the models that
moves a peak fails here until the table is updated (``python -m
tests.integration.test_readme_tables`` prints the rows to paste).
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import pytest

from harness.cli import main
from harness.signals.peaks import reduction_pct
from tests.conftest import REPO, SHARED_RECORDS

README = REPO / "README.md"
TABLE2_HEADING = "| design | sliding (mm) |"
#: The study's cases: El Centro at 0.3 g, 30 s, FSF-I designed on the story stiffness x0.7, x1.0, x1.3.
CASE = ["simulate", "eight_story", "--record", "el_centro", "--pga", "0.3", "--duration", "30", "--controller", "FSF-I"]
SCALES = (0.7, 1.0, 1.3)


def readme_table2() -> list[list[str]]:
    """The rows of the README's Table 2, cells stripped (the heading and rule left out)."""
    lines = README.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith(TABLE2_HEADING))
    rows = []
    for line in lines[start + 2:]:
        if not line.startswith("|"):
            break
        rows.append([cell.strip() for cell in line.strip().strip("|").split("|")])
    return rows


def _row(name: str, peaks: dict, passive: dict | None) -> list[float | str]:
    drift, floor = max(peaks["drift_m"]), max(peaks["floor_acceleration_m_s2"])
    cells: list[float | str] = [name, peaks["sliding_displacement_m"] * 1e3, peaks["base_acceleration_m_s2"], drift * 1e3,
                                floor, peaks["peak_force_pct_weight"]]
    if passive is not None:
        cells += [reduction_pct(max(passive["drift_m"]), drift),
                  reduction_pct(max(passive["floor_acceleration_m_s2"]), floor)]
    return cells


def simulated_table2(folder: Path, records: Path) -> list[list[float | str]]:
    """Table 2 as ``harness simulate --json`` gives it today: the passive case, then each design."""
    rows: list[list[float | str]] = []
    for scale in SCALES:
        out = folder / f"table2_{scale}.json"
        status = main([*CASE, "--design-stiffness-scale", str(scale), "--records-dir", str(records), "--json", str(out),
                       "--quiet"])
        assert status == 0, f"harness {' '.join(CASE)} --design-stiffness-scale {scale}: exit status {status}"
        cases = json.loads(out.read_text())["cases"]
        if not rows:
            rows.append(_row("passive", cases["passive"], None))
        rows.append(_row(f"FSF-I, design stiffness x{scale:.1f}", cases["controlled"], cases["passive"]))
    return rows


def _agrees(written: str, value: float | str) -> bool:
    """Whether ``value`` rounds to the README's cell, to the digits it shows (blank: nothing to show)."""
    if isinstance(value, str) or not written:
        return written == value if isinstance(value, str) else not written and value is None
    decimals = len(written.split(".")[1]) if "." in written else 0
    return math.isclose(float(written), value, abs_tol=0.5 * 10.0**-decimals + 1e-12)


def test_the_readme_table2_is_what_simulate_prints(tmp_path: Path, capsys) -> None:
    if not (SHARED_RECORDS / "elcentro_1940_NS.csv").is_file():
        pytest.skip(f"real records not found in {SHARED_RECORDS} (Table 2 is El Centro's)")
    written, simulated = readme_table2(), simulated_table2(tmp_path, SHARED_RECORDS)
    capsys.readouterr()
    assert len(written) == len(simulated) == 1 + len(SCALES)
    for cells, values in zip(written, simulated, strict=True):
        values = values + [None] * (len(cells) - len(values))
        wrong = [f"{cell!r} (simulate: {value})" for cell, value in zip(cells, values, strict=True)
                 if not _agrees(cell, value)]
        assert not wrong, f"README Table 2, row {cells[0]}: {', '.join(wrong)}"


def test_the_table_is_found() -> None:
    rows = readme_table2()
    assert [row[0] for row in rows][:1] == ["passive"] and len(rows) == 4
    assert all(re.fullmatch(r"-?\d+(\.\d+)?", cell) for row in rows for cell in row[1:6])


def _format(value: float | str, column: int) -> str:
    if isinstance(value, str):
        return value
    if column == 5:  # the force in % of the weight
        return f"{value:.2f}" if value else "0"
    return f"{value:.3g}" if abs(value) < 10 else f"{value:.1f}"


if __name__ == "__main__":  # the rows to paste into the README
    import tempfile

    for row in simulated_table2(Path(tempfile.mkdtemp()), Path(sys.argv[1]) if len(sys.argv) > 1 else SHARED_RECORDS):
        print("| " + " | ".join(_format(cell, column) for column, cell in enumerate(row)) + (" | | |" if len(row) == 6 else " |"))
