"""What the commands print when the output is captured, and under --quiet: the console, rich tables that
wrap instead of cutting a figure, the console's wording of a batch's tables, questions under --quiet."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from harness.commands.output import CAPTURED_WIDTH, CommandConsole, command_console, print_always
from harness.report.batch_summary import BatchCase, batch_tables
from harness.report.tables import in_console_wording, reduction_table
from harness.report.text_table import TextTable
from harness.signals.peaks import Peaks


def _rendered(renderable, width: int) -> str:
    console = Console(file=io.StringIO(), width=width, color_system=None)
    console.print(renderable)
    return console.file.getvalue()


def _wide_table() -> TextTable:
    headings = ("design", "record", "cases", *(f"quantity {k} median %" for k in range(8)))
    rows = tuple(
        (f"FSF-I, design_stiffness_scale={scale}", "all", "12", *(f"{99.123456 - k - i:.6g}" for k in range(8)))
        for i, scale in enumerate(("0.7", "1.0", "1.3"))
    )
    return TextTable("a summary wider than a terminal", headings, rows, "a note under it", key_columns=2,
                     numeric=(False, False, *(True,) * 9))


@pytest.mark.parametrize("width", [60, 80, 120])
def test_a_table_wider_than_the_console_is_split_into_blocks_that_keep_every_figure(width: int) -> None:
    table = _wide_table()
    text = _rendered(table.to_rich(width), width)
    assert "…" not in text
    assert max(len(line) for line in text.splitlines()) <= width
    for row in table.rows:
        for cell in row:
            assert cell in text, cell  # every figure and every design label, whole, somewhere
    assert text.count("FSF-I, design_stiffness_scale=0.7") >= 2  # the key columns repeat in each block


def test_a_table_that_fits_keeps_its_headings_on_one_line_and_one_block() -> None:
    table = _wide_table()
    text = _rendered(table.to_rich(CAPTURED_WIDTH), CAPTURED_WIDTH)
    assert "quantity 7 median %" in text and text.count("FSF-I, design_stiffness_scale=0.7") == 1


def test_a_console_without_a_terminal_is_wide_and_cuts_nothing(monkeypatch) -> None:
    monkeypatch.delenv("COLUMNS", raising=False)
    console = command_console()
    assert not console.is_terminal and console.width == CAPTURED_WIDTH
    monkeypatch.setenv("COLUMNS", "72")
    assert command_console().width == 72  # an explicit width is kept


def test_quiet_prints_only_what_print_always_prints_and_still_asks(monkeypatch) -> None:
    console = CommandConsole(file=io.StringIO(), quiet=True, width=100)
    console.print("a table")
    print_always(console, "outcome: completed")
    monkeypatch.setattr("builtins.input", lambda: "y")
    assert console.input("Arm the actuator? ") == "y"
    assert console.file.getvalue() == "outcome: completed\nArm the actuator? "
    assert console.quiet  # quiet again afterwards


def _peaks(scale: float) -> Peaks:
    return Peaks(sliding_displacement_m=0.05 * scale, base_acceleration_m_s2=2.0 * scale, drift_m=(0.01 * scale, 0.02 * scale),
                 floor_acceleration_m_s2=(3.0 * scale, 4.0 * scale), peak_force_pct_weight=5.0 * (scale < 1))


def test_the_batch_tables_on_the_console_read_like_the_single_study_table() -> None:
    cases = [BatchCase(record, "FSF-I", _peaks(1.0), _peaks(0.1)) for record in ("el_centro", "pacoima")]
    single = reduction_table(_peaks(1.0), _peaks(0.1), "one study")
    for table in batch_tables(cases):
        shown = in_console_wording(table)
        assert shown.headings == single.headings
        assert [row.values for row in shown.rows] == [row.values for row in table.rows]  # the numbers untouched
        for row in shown.rows:
            if row.key in {r.key for r in single.rows} and row.unit != "%":
                assert (row.label, row.unit) == (single.row(row.key).label, single.row(row.key).unit)
        text = _rendered(shown.to_rich(100), 100)
        assert "m/s^2" not in text
    peaks_text = _rendered(in_console_wording(batch_tables(cases)[0]).to_rich(200), 200)
    assert "floor 1 abs. acceleration   m/s²" in peaks_text and "% weight" in peaks_text
