"""``harness simulate --rig-effects --drive-from RUN_DIR`` and ``harness report``'s link to replay (issue 34, items 3 and 5).

On the folder of a short lockstep dry run made here: the twin's table moves through the run's
measured table displacement and velocity at every tick (closed loop on the twin, the table doing
what it did in the run); folders that cannot drive it are refused with what was expected; and the
run's report gives the command that replays it, the replay made of it, or why it cannot be replayed.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.recording import load_run
from harness.runs.options import StudyOptions
from harness.runs.simulate import run_study
from harness.signals.columns import TABLE_DISPLACEMENT, TABLE_VELOCITY, TIME
from tests.replay_checks import logged_before_replay


@pytest.fixture(scope="module")
def dry_run(tmp_path_factory) -> Path:
    log_dir = tmp_path_factory.mktemp("drive_from")
    status = main(["dry-run", "--lockstep", "--duration", "1", "--log-dir", str(log_dir), "--quiet"])
    assert status == exit_codes.OK
    (folder,) = [p for p in log_dir.iterdir() if p.is_dir()]
    return folder


def _cli(capsys, *args: str) -> tuple[int, str]:
    capsys.readouterr()
    status = main(list(args))
    captured = capsys.readouterr()
    return status, " ".join((captured.out + captured.err).split())  # rich wraps long lines


def test_the_twins_table_moves_through_the_runs_measured_table_motion(dry_run):
    run = load_run(dry_run)
    study = run_study(load_profile(), StudyOptions(rig_effects=True, drive_from=str(dry_run)))
    table = study.cases["controlled"].extra["true_table"]
    x, v = table[TABLE_DISPLACEMENT], table[TABLE_VELOCITY]
    assert len(x) == run.n_rows  # twin sample k is the run's tick k
    np.testing.assert_array_equal(x, run[TABLE_DISPLACEMENT])
    np.testing.assert_array_equal(v[:-1], run[TABLE_VELOCITY][:-1])
    assert v[-1] == 0.0  # the drive ends at the run's last tick: the table holds there
    passive = study.cases["passive"].columns  # the passive case is driven by the same motion
    np.testing.assert_array_equal(passive[TABLE_DISPLACEMENT], run[TABLE_DISPLACEMENT])
    assert study.motion.dt_s == pytest.approx(1.0 / run.metadata["rate_hz"])
    assert study.profile.rig.table.model == "motion_source"


def test_the_drive_says_where_it_came_from_and_when_the_runs_profile_was_another(dry_run):
    from harness.simulation.drive import achieved_motion

    motion = achieved_motion(dry_run, 500.0, duration_s=0.5, profile_name="eight_story")
    assert motion.duration_s == pytest.approx(0.5) and motion.time_scale == 1.0
    assert any(f"the table motion run {dry_run} achieved" in note for note in motion.notes)
    assert any("the run was made with profile 'nceer_4dof', this simulation runs 'eight_story'" in note
               for note in motion.notes)
    assert len(achieved_motion(dry_run, 500.0, profile_name="nceer_4dof").notes) == 1


def test_simulate_drive_from_runs_on_the_command_line(dry_run, capsys, tmp_path):
    path = tmp_path / "twin.json"
    status, out = _cli(capsys, "simulate", "--rig-effects", "--drive-from", str(dry_run), "--duration", "1",
                       "--json", str(path), "--quiet")
    assert status == exit_codes.OK, out
    doc = json.loads(path.read_text())
    assert doc["record"]["name"] == f"achieved_{dry_run.name}" and doc["record"]["duration_s"] == pytest.approx(1.0)
    assert doc["sampling"]["rig_effects"] is True


def _copy(dry_run: Path, tmp_path: Path) -> Path:
    return Path(shutil.copytree(dry_run, tmp_path / dry_run.name))


def _without_table_signals(dry_run: Path, tmp_path: Path) -> Path:
    folder = _copy(dry_run, tmp_path)
    signals = (folder / "signals.csv").read_text().splitlines()
    header = signals[0].split(",")
    keep = [i for i, name in enumerate(header) if name not in (TABLE_DISPLACEMENT, TABLE_VELOCITY)]
    (folder / "signals.csv").write_text("".join(",".join(line.split(",")[i] for i in keep) + "\n" for line in signals))
    metadata = json.loads((folder / "metadata.json").read_text())
    metadata["columns"] = [header[i] for i in keep]
    (folder / "metadata.json").write_text(json.dumps(metadata))
    return folder


def _of_kind_simulation(dry_run: Path, tmp_path: Path) -> Path:
    folder = _copy(dry_run, tmp_path)
    metadata = json.loads((folder / "metadata.json").read_text())
    (folder / "metadata.json").write_text(json.dumps({**metadata, "kind": "simulation"}))
    return folder


#: Folders and options that cannot drive the twin, and what the refusal must say.
BAD_DRIVES = {
    "not_a_run_folder": (lambda run, tmp: tmp, (), ["--drive-from", "found no metadata.json", "`harness dry-run`"]),
    "no_table_signals": (_without_table_signals, (),
                         ["found no table_displacement_m and table_velocity_m_s", "expected the table's measured"]),
    "a_simulation": (_of_kind_simulation, (), ["kind 'simulation'", "expected one of dry-run, run"]),
    "another_rate": (lambda run, tmp: run, ("--rate", "1000"),
                     ["found a run at 500 Hz, expected the twin's rate 1000 Hz", "give --rate 500"]),
    "without_rig_effects": (lambda run, tmp: run, ("--no-rig-effects",), ["expected --rig-effects with it"]),
    "with_a_record": (lambda run, tmp: run, ("--record", "el_centro"), ["found --record with --drive-from"]),
}


@pytest.mark.parametrize("case", sorted(BAD_DRIVES))
def test_a_drive_the_twin_cannot_take_is_refused_with_what_was_expected(dry_run, tmp_path, capsys, case):
    make, extra, expected = BAD_DRIVES[case]
    folder = make(dry_run, tmp_path)
    rig_effects = [] if "--no-rig-effects" in extra else ["--rig-effects"]
    options = [arg for arg in extra if arg != "--no-rig-effects"]
    status, out = _cli(capsys, "simulate", *rig_effects, "--drive-from", str(folder), *options, "--quiet")
    assert status == exit_codes.INPUT_ERROR, out
    assert out.startswith("error:") and "Traceback" not in out
    for text in expected:
        assert text in out, out


def test_the_report_gives_the_command_that_replays_the_run_and_the_replay_made_of_it(dry_run, capsys, tmp_path):
    status, out = _cli(capsys, "report", str(dry_run), "--out", str(tmp_path / "report"))
    assert status == exit_codes.OK, out
    assert "its tick record (ticks.bin) makes an exact replay possible" in out
    assert f"harness replay {dry_run}" in out and "replayed in" not in out
    status, out = _cli(capsys, "replay", str(dry_run), "--set", "safety.stroke.hard_limit_m=0.097", "--out",
                       str(dry_run.parent / "whatif"), "--quiet")
    assert status == exit_codes.OK, out
    (replayed,) = (dry_run.parent / "whatif").iterdir()
    status, out = _cli(capsys, "report", str(dry_run), "--out", str(tmp_path / "report_again"))
    assert f"replayed in {replayed.resolve()}" in out
    summary = (tmp_path / "report_again" / "summary.txt").read_text()
    assert f"harness replay {dry_run}" in summary and f"replayed in {replayed.resolve()}" in summary
    page = (tmp_path / "report_again" / "report.html").read_text()
    assert "<h2>Replay</h2>" in page and f"harness replay {dry_run}" in page
    status, out = _cli(capsys, "report", str(replayed), "--out", str(tmp_path / "report_of_replay"))
    assert f"a what-if replay (--set safety.stroke.hard_limit_m=0.097; open loop) of {dry_run.resolve()}" in out
    shutil.rmtree(dry_run.parent / "whatif")


def test_the_report_of_a_run_logged_before_replay_says_it_cannot_be_replayed(dry_run, capsys, tmp_path):
    old = logged_before_replay(dry_run, tmp_path)
    status, out = _cli(capsys, "report", str(old), "--out", str(tmp_path / "report"))
    assert status == exit_codes.OK, out
    assert "replay is not possible: logged before replay existed: it has no tick record (ticks.bin" in out
    assert "harness replay" not in out
    assert load_run(old)[TIME].size == load_run(dry_run)[TIME].size  # the rest of the folder is the run's
