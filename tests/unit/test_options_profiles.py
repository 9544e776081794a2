"""A shipped profile is found by its name from any folder; help texts say what the commands really do."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from harness.cli import build_parser, main
from harness.commands.options import profile_path, shipped_profile
from harness.paths import PROFILE_DIR


@pytest.mark.parametrize("typed", ["eight_story", "eight_story.yaml", "profiles/eight_story.yaml"])
def test_a_shipped_profile_is_found_by_name_from_another_folder(typed: str, tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert Path(profile_path(typed)) == PROFILE_DIR / "eight_story.yaml"


def test_an_existing_file_wins_over_a_shipped_name(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    (tmp_path / "eight_story.yaml").write_text("name: mine\n")
    assert profile_path("eight_story.yaml") == "eight_story.yaml"
    assert shipped_profile("eight_story.yaml") is None


def test_other_paths_are_left_for_the_loader_to_refuse(tmp_path: Path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    for typed in ("no_such_profile", "elsewhere/eight_story.yaml", "/abs/eight_story.yaml"):
        assert profile_path(typed) == typed


def test_simulate_runs_a_shipped_profile_by_name_outside_the_checkout(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    status = main(["simulate", "eight_story", "--controller", "OF-I", "--duration", "1", "--json", "out.json", "--quiet"])
    assert status == 0, capsys.readouterr().err
    assert json.loads((tmp_path / "out.json").read_text())["profile"] == "eight_story"


def test_an_unknown_profile_name_lists_the_shipped_ones(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "nine_story", "--duration", "1", "--quiet"]) == 2
    assert "eight_story.yaml" in capsys.readouterr().err


def _help(command: str) -> str:
    parser = build_parser()
    sub = next(action for action in parser._actions if action.dest == "command")
    return sub.choices[command].format_help()


@pytest.mark.parametrize("command", ["simulate", "report", "records", "dry-run", "run", "rig"])
def test_help_shows_no_doubled_percent_sign(command: str) -> None:
    assert "%%" not in _help(command)


@pytest.mark.parametrize("command", ["simulate", "report", "records"])
def test_offline_commands_list_only_the_exit_statuses_they_can_return(command: str) -> None:
    text = _help(command)
    assert "  2  bad input" in text
    assert "tripped" not in text and "stopped early" not in text


def test_rig_refuses_an_in_process_bus_no_other_process_could_reach(capsys) -> None:
    assert main(["rig", "--interface", "virtual"]) == 2
    assert "inside one process" in capsys.readouterr().out
