"""``harness records``: names never cut, a record beyond the table shown anyway, ``--plot`` without a file."""

from __future__ import annotations

from pathlib import Path

import pytest

from harness.cli import main


def test_the_list_keeps_every_name_whole_at_80_columns(records_dir: Path, capsys, monkeypatch) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    assert main(["records", "--records-dir", str(records_dir)]) == 0
    out = capsys.readouterr().out
    for name in ("el_centro_classic", "pacoima_1971_S16E__RSN77_SFERN_PUL164", "hachinohe"):
        assert name in out
    assert "Set the directory" not in out
    for line in out.splitlines():  # only a line naming a record and its file may be longer: names are never cut
        assert len(line) <= 80 or line.startswith("  ") and len(line.split()) == 3, line


def test_without_a_directory_the_list_says_how_to_set_one(capsys, monkeypatch, tmp_path: Path) -> None:
    monkeypatch.delenv("HARNESS_RECORDS_DIR", raising=False)
    assert main(["records"]) == 0
    assert "Set the directory" in capsys.readouterr().out


def test_a_record_beyond_the_table_shows_its_statistics_and_the_largest_pga_that_fits(
    records_dir: Path, capsys, tmp_path: Path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)
    status = main(["records", "pacoima", "--records-dir", str(records_dir), "--time-scale", "1", "--pga", "1.2", "--plot"])
    out = capsys.readouterr().out
    assert status == 2
    assert "PGD" in out and "Arias intensity" in out and "pseudo-acceleration" in out
    assert "exceeds the table's stroke" in out and "the largest PGA that fits" in out
    assert (tmp_path / "pacoima_motion.png").is_file()


@pytest.mark.parametrize("args", [["--plot"], ["--plot", "chosen.png"]])
def test_plot_with_or_without_a_file(args: list[str], tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["records", "synthetic:3", "--duration", "5", *args]) == 0
    expected = "chosen.png" if len(args) == 2 else "synthetic-3_motion.png"
    assert (tmp_path / expected).is_file(), capsys.readouterr().out
