"""Issue 33, item 4: a study file names its base profile as the command line does, shipped names included."""

from __future__ import annotations

from pathlib import Path

from harness.cli import main
from harness.paths import PROFILE_DIR
from harness.sweep.study import load_study

STUDY = """name: by_name
profile: {profile}
options: {{duration_s: 2}}
axes:
  records: [synthetic]
  controllers: [phi]
"""


def _study(folder: Path, profile: str) -> Path:
    path = folder / "study.yaml"
    path.write_text(STUDY.format(profile=profile))
    return path


def test_a_shipped_profile_name_in_a_study_is_found(tmp_path: Path) -> None:
    for name in ("nceer_4dof", "nceer_4dof.yaml", "profiles/nceer_4dof.yaml"):
        assert load_study(_study(tmp_path, name)).profile_path() == (PROFILE_DIR / "nceer_4dof.yaml").resolve()


def test_a_file_beside_the_study_wins_over_a_shipped_name(tmp_path: Path) -> None:
    own = tmp_path / "nceer_4dof.yaml"
    own.write_text((PROFILE_DIR / "nceer_4dof.yaml").read_text())
    assert load_study(_study(tmp_path, "nceer_4dof.yaml")).profile_path() == own.resolve()


def test_sweep_plans_a_study_naming_a_shipped_profile(tmp_path: Path, capsys) -> None:
    status = main(["sweep", str(_study(tmp_path, "nceer_4dof")), "--plan", "--out", str(tmp_path / "results")])
    output = capsys.readouterr()
    assert status == 0, output.out + output.err
    assert "profile file not found" not in output.out + output.err
