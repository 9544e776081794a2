"""The table of the feed-forward study (profiles/studies/feedforward.yaml) from its results folders (issue 31).

Per record and PGA level and per feed-forward gain alpha, over the rig's nine true actuators
(valve flow gain and bulk modulus each -30 %, 0, +30 %): the story drift reductions (%, against
the twin's passive case), median and range over the nine, and the largest peak force (% W).

Usage: python benchmarks/feedforward_table.py RESULTS [RESULTS ...]   (each a ``harness sweep --out`` folder)
"""

from __future__ import annotations

import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

GAIN = "rig.actuator.hydraulics.feedforward.gain"
STORIES = ("reduction_pct.drift_1_m", "reduction_pct.drift_2_m", "reduction_pct.drift_3_m")


def rows_of(folder: Path) -> list[dict]:
    """Every case row of a results folder: ``cases.parquet`` of a finished sweep, and the ``parts`` of one under way."""
    rows: list[dict] = []
    for part in sorted([*folder.glob("cases.parquet"), *(folder / "parts").glob("*.parquet")]):
        table = pq.read_table(part).to_pydict()
        rows += [dict(zip(table, values, strict=True)) for values in zip(*table.values(), strict=True)]
    return rows


def table(rows: list[dict]) -> str:
    """The Markdown table: one line per record, level and gain."""
    groups: dict[tuple, list[dict]] = defaultdict(list)
    for row in rows:
        groups[(row["record"], row["pga_g"], row[GAIN])].append(row)
    lines = ["| record | alpha | actuators | drift reduction % stories 1/2/3: median [min, max] | peak force % W, largest |",
             "|---|---|---|---|---|"]
    for (record, pga_g, gain), group in sorted(groups.items()):
        cells = []
        for story in STORIES:
            values = np.array([row[story] for row in group])
            cells.append(f"{np.median(values):.0f} [{values.min():.0f}, {values.max():.0f}]")
        force = max(row["controlled.peak_force_pct_weight"] for row in group)
        lines.append(f"| {record} {pga_g:g} g | {gain:g} | {len(group)} | {' / '.join(cells)} | {force:.1f} |")
    return "\n".join(lines)


def main(argv: list[str]) -> int:
    """Print the table of the results folders given."""
    rows = [row for folder in argv for row in rows_of(Path(folder))]
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
