"""``harness sweep`` end to end: a case equals ``harness simulate``, resume, failures, 192 cases on two engines."""

from __future__ import annotations

import json
import math
import os
import shlex
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from harness.cli import main
from harness.recording import strict_json
from harness.sweep.store import ResultStore, have_pyarrow
from tests.conftest import PROFILES, SHARED_RECORDS

EIGHT = PROFILES / "eight_story.yaml"
REAL_RECORDS = (SHARED_RECORDS / "elcentro_1940_NS.csv").is_file()
#: The records of the 192-case sweep: the real ones where the shared data is beside the checkout.
RECORDS = "[el_centro, hachinohe, pacoima]" if REAL_RECORDS else '["synthetic:1", "synthetic:2", "synthetic:3"]'


@pytest.fixture(autouse=True)
def wide_console(monkeypatch):
    """Console lines long enough that a message is not wrapped in the middle of the words a test looks for."""
    monkeypatch.setenv("COLUMNS", "250")


def _study(tmp_path: Path, body: str, name: str = "study.yaml") -> Path:
    path = tmp_path / name
    path.write_text(f"profile: {EIGHT}\n" + textwrap.dedent(body))
    return path


def _sweep(capsys, *args: str) -> tuple[int, str]:
    status = main(["sweep", *args])
    captured = capsys.readouterr()
    return status, captured.out + captured.err


def _rows(folder: Path) -> dict[str, dict]:
    return {row["case_id"]: row for row in ResultStore(folder).rows()}


def _ran(rows: dict[str, dict]) -> dict[str, tuple]:
    """Per case, when and where it ran (its wall time and worker): unchanged if it did not run again."""
    return {key: (row["wall_time_s"], row["worker"]) for key, row in rows.items()}


EQUAL_CASES = """\
name: equal
options: {duration_s: 2}
axes:
  records: ["synthetic:4"]
  pga_g: [0.25]
  controllers: [FSF-I, OF-I]
  scale: {structure.story_stiffness_N_per_m: [0.9]}
monte_carlo:
  samples: 1
  seed: 5
  set: {bearing.mu_max: {kind: uniform, low: 0.06, high: 0.11}}
"""


def _simulated_peaks(row: dict, doc: dict) -> list[tuple[float, float]]:
    """(sweep row value, harness simulate --json value) of every peak of both cases."""
    pairs = []
    for case in ("passive", "controlled"):
        peaks = doc["cases"][case]
        for name in ("sliding_displacement_m", "base_acceleration_m_s2", "peak_force_pct_weight"):
            pairs.append((row[f"{case}.{name}"], peaks[name]))
        for j, (drift, accel) in enumerate(zip(peaks["drift_m"], peaks["floor_acceleration_m_s2"], strict=True), 1):
            pairs += [(row[f"{case}.drift_{j}_m"], drift), (row[f"{case}.floor_acceleration_{j}_m_s2"], accel)]
    return pairs


def test_a_sweep_case_gives_exactly_the_peaks_of_harness_simulate(tmp_path, capsys):
    study = _study(tmp_path, EQUAL_CASES)
    status, out = _sweep(capsys, str(study), "--out", str(tmp_path / "results"), "--workers", "2")
    assert status == 0, out
    rows = _rows(tmp_path / "results")
    assert len(rows) == 2 and all(row["outcome"] == "ok" for row in rows.values())
    for key, row in rows.items():
        status, out = _sweep(capsys, str(study), "--case", key[:8])
        argv = shlex.split(out.strip())[1:]
        assert argv[0] == "simulate" and "--set" in argv
        path = tmp_path / f"{key}.json"
        if row["controller"] == "FSF-I":
            # The sweep's workers run OpenBLAS single-threaded (engines.SINGLE_THREAD_ENV); the
            # threaded library sums in another order (peaks differ by 1e-13). With the same
            # threading, harness simulate gives the very same numbers.
            env = {**os.environ, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
            command = [sys.executable, "-m", "harness.cli", *argv, "--json", str(path), "--quiet"]
            subprocess.run(command, env=env, check=True, capture_output=True, timeout=120)
            assert all(swept == simulated for swept, simulated in _simulated_peaks(row, json.loads(path.read_text())))
        # this process: BLAS threads as it has them (--force: over the subprocess's file, if any)
        assert main([*argv, "--json", str(path), "--force", "--quiet"]) == 0
        capsys.readouterr()
        for swept, simulated in _simulated_peaks(row, json.loads(path.read_text())):
            assert swept == pytest.approx(simulated, rel=1e-9, abs=1e-15)


def test_a_study_overlay_reaches_every_case_and_its_simulate_command(tmp_path, capsys):
    """``overlay:`` in a study file is merged as --overlay is (after the variant, before set), changes the
    cases' keys (a study with another overlay is another study), and ``--case`` prints it."""
    overlay = tmp_path / "identified.yaml"
    overlay.write_text("bearing:\n  mu_max: 0.09\n")
    body = "name: overlaid\noverlay: identified.yaml\noptions: {duration_s: 2}\naxes:\n  records: ['synthetic:4']\n" \
           "  controllers: [OF-I]\n"
    study = _study(tmp_path, body)
    status, out = _sweep(capsys, str(study), "--out", str(tmp_path / "with"), "--workers", "0")
    assert status == 0, out
    (key, row), = _rows(tmp_path / "with").items()
    status, out = _sweep(capsys, str(study), "--case", key[:8])
    argv = shlex.split(out.strip())[1:]
    assert argv[argv.index("--overlay") + 1] == str(overlay.resolve())
    path = tmp_path / "case.json"
    assert main([*argv, "--json", str(path), "--quiet"]) == 0
    capsys.readouterr()
    for swept, simulated in _simulated_peaks(row, json.loads(path.read_text())):
        assert swept == pytest.approx(simulated, rel=1e-9, abs=1e-15)
    plain = _study(tmp_path, body.replace("overlay: identified.yaml\n", ""), name="plain.yaml")
    status, out = _sweep(capsys, str(plain), "--out", str(tmp_path / "without"), "--workers", "0")
    assert status == 0, out
    (other, plain_row), = _rows(tmp_path / "without").items()
    assert other != key  # the overlay is part of what a case is
    assert plain_row["passive.sliding_displacement_m"] != row["passive.sliding_displacement_m"]
    (tmp_path / "bad.yaml").write_text("bearing:\n  mu_max: -1\n")
    bad = _study(tmp_path, body.replace("identified.yaml", "bad.yaml"), name="bad_study.yaml")
    status, out = _sweep(capsys, str(bad), "--out", str(tmp_path / "bad"), "--workers", "0")
    assert status == 2 and "mu_max" in out


def test_a_study_on_the_rig_twin_compares_compensations_as_harness_simulate_does(tmp_path, capsys):
    """``options.rig_effects`` runs every case as ``harness simulate --rig-effects``, and a set axis over
    ``control.compensation`` compares the methods (profiles/studies/compensation.yaml at scale)."""
    body = f"""\
name: twin
profile: {PROFILES / "nceer_4dof.yaml"}
options: {{duration_s: 2, rig_effects: true}}
axes:
  records: ["synthetic:4"]
  controllers: [phi]
  set: {{control.compensation: [none, model]}}
"""
    study = tmp_path / "twin.yaml"
    study.write_text(body)
    status, out = _sweep(capsys, str(study), "--out", str(tmp_path / "twin"), "--workers", "0")
    assert status == 0, out
    rows = _rows(tmp_path / "twin")
    assert len(rows) == 2 and all(row["outcome"] == "ok" for row in rows.values())
    by_method = {row["control.compensation"]: row for row in rows.values()}
    assert by_method["none"]["controlled.peak_force_pct_weight"] != by_method["model"]["controlled.peak_force_pct_weight"]
    for key, row in rows.items():
        status, out = _sweep(capsys, str(study), "--case", key[:8])
        argv = shlex.split(out.strip())[1:]
        assert "--rig-effects" in argv
        path = tmp_path / f"{key}.json"
        assert main([*argv, "--json", str(path), "--quiet"]) == 0
        capsys.readouterr()
        doc = json.loads(path.read_text())
        assert doc["sampling"]["rig_effects"] is True
        for swept, simulated in _simulated_peaks(row, doc):
            assert swept == pytest.approx(simulated, rel=1e-9, abs=1e-15)
    plain = tmp_path / "plain.yaml"
    plain.write_text(body.replace("rig_effects: true", "rig_effects: false"))
    status, out = _sweep(capsys, str(plain), "--out", str(tmp_path / "plain"), "--workers", "0")
    assert status == 0, out
    assert not set(_rows(tmp_path / "plain")) & set(rows)  # the twin's cases are other cases


def test_the_shipped_compensation_study_plans_its_243_cases(capsys, records_dir):  # its records are the real ones
    status, out = _sweep(capsys, "compensation", "--plan")
    assert status == 0, out
    assert "243 cases (3 records x 3 PGA levels x 1 controller x 27 grid points x 1 sample)" in out


RESUME = """\
name: resume
options: {duration_s: 2}
axes:
  records: ["synthetic:1", "synthetic:2"]
  pga_g: [0.1, 0.2]
  controllers: [OF-I]
"""


def test_a_rerun_skips_the_cases_done_and_an_extended_study_runs_only_the_new(tmp_path, capsys):
    study, results = _study(tmp_path, RESUME), tmp_path / "results"
    status, out = _sweep(capsys, str(study), "--out", str(results), "--workers", "0")
    assert status == 0 and "4 cases, 0 already in" in out and "ran 4 cases" in out
    first = _rows(results)
    status, out = _sweep(capsys, str(study), "--out", str(results), "--workers", "0")
    assert status == 0 and "4 cases, 4 already in" in out and "0 to run" in out and "ran " not in out
    assert _ran(_rows(results)) == _ran(first), "nothing ran again"
    study.write_text(study.read_text().replace("pga_g: [0.1, 0.2]", "pga_g: [0.1, 0.2, 0.3]"))
    status, out = _sweep(capsys, str(study), "--out", str(results), "--workers", "0")
    assert status == 0 and "6 cases, 4 already in" in out and "ran 2 cases" in out
    rows = _rows(results)
    assert len(rows) == 6 and all(_ran(rows)[key] == _ran(first)[key] for key in first)


def test_an_interrupted_sweep_keeps_its_rows_and_the_rerun_goes_on(tmp_path):
    from harness.sweep.cases import expand
    from harness.sweep.driver import open_folder, plan, run_sweep
    from harness.sweep.study import load_study

    study = load_study(_study(tmp_path, RESUME))
    cases = expand(study)

    class StopsAfterTwo:
        workers, description = 1, "test"

        def rows(self, runner, todo):
            for case in todo[:2]:
                yield {**case.input_columns(), "outcome": "ok", "error": ""}
            raise KeyboardInterrupt

    with open_folder(tmp_path / "results", study) as store:
        outcome = run_sweep(plan(cases, store).todo, StopsAfterTwo(), None, store)  # type: ignore[arg-type]
        assert outcome.interrupted and outcome.ran == 2
    with open_folder(tmp_path / "results", study) as store:
        remaining = plan(cases, store).todo
    assert [case.key for case in remaining] == [case.key for case in cases[2:]]


FAILING = """\
name: failing
options: {duration_s: 2}
axes:
  records: ["synthetic:1"]
  pga_g: [0.2]
  controllers: [OF-I]
  set: {bearing.mu_delta: [0.04, 0.09]}
monte_carlo:
  samples: 4
  seed: 1
  set: {bearing.mu_max: {kind: uniform, low: 0.05, high: 0.12}}
"""


def test_a_failing_case_is_recorded_with_its_error_and_the_sweep_goes_on(tmp_path, capsys):
    # mu_delta 0.09 is valid alone, so is every mu_max sample; together some exceed mu_max:
    # those cases fail in their worker, and the others still run.
    status, out = _sweep(capsys, str(_study(tmp_path, FAILING)), "--out", str(tmp_path / "results"), "--workers", "2")
    assert status == 0, out
    rows = list(_rows(tmp_path / "results").values())
    failed = [row for row in rows if row["outcome"] == "failed"]
    ok = [row for row in rows if row["outcome"] == "ok"]
    assert len(rows) == 8 and failed and ok and f"{len(failed)} cases failed" in out
    for row in failed:
        assert row["bearing.mu_delta"] == 0.09 and row["bearing.mu_max"] < 0.09
        assert row["error"].startswith("ProfileError:") and "mu_delta = 0.09 exceeds mu_max" in row["error"]
        assert math.isnan(row.get("controlled.max_drift_m") or math.nan)
    assert all(row["controlled.max_drift_m"] > 0 for row in ok)


def test_bad_study_files_and_folders_are_refused_with_status_2(tmp_path, capsys):
    bad = _study(tmp_path, RESUME.replace("controllers: [OF-I]", "controllers: [OF-I]\n  design: [x]"))
    status, out = _sweep(capsys, str(bad))
    assert status == 2 and "axes.design: unknown key 'design'" in out
    status, out = _sweep(capsys, "--summarize", str(tmp_path))
    assert status == 2 and "holds no sweep" in out
    other = _study(tmp_path, RESUME.replace("name: resume", "name: other"), "other.yaml")
    assert _sweep(capsys, str(_study(tmp_path, RESUME)), "--out", str(tmp_path / "r"), "--workers", "0")[0] == 0
    status, out = _sweep(capsys, str(other), "--out", str(tmp_path / "r"), "--plan")
    assert status == 2 and "holds the results of study 'resume'" in out


LARGE = f"""\
name: ida_small
options: {{duration_s: 2, records_dir: {SHARED_RECORDS}}}
axes:
  records: {RECORDS}
  pga_levels: {{start_g: 0.1, stop_g: 0.4, count: 4}}
  controllers: [FSF-I, OF-I]
monte_carlo:
  samples: 8
  seed: 2024
  set: {{bearing.mu_max: {{kind: uniform, low: 0.05, high: 0.12}}}}
fragility: {{drift_limit_m: "5 mm"}}
"""


@pytest.fixture(scope="module")
def large_local(tmp_path_factory) -> tuple[Path, Path]:
    """The 192-case sweep (3 records x 4 PGA x 2 designs x 8 friction samples, 2 s each) on two local workers."""
    folder = tmp_path_factory.mktemp("large")
    study = _study(folder, LARGE)
    status = main(["sweep", str(study), "--out", str(folder / "local"), "--workers", "2", "--quiet",
                   "--report", str(folder / "report")])
    assert status == 0
    return study, folder


@pytest.mark.slow
def test_192_cases_on_local_workers_with_the_report(large_local):
    _, folder = large_local
    rows = _rows(folder / "local")
    assert len(rows) == 192 and all(row["outcome"] == "ok" for row in rows.values())
    assert {row["controller"] for row in rows.values()} == {"FSF-I", "OF-I"}
    assert len({row["worker"] for row in rows.values()}) == 2, "both workers took cases"
    meta = strict_json.loads((folder / "local" / "sweep.json").read_text())
    assert meta["ran"] == 192 and meta["storage"] == ("parquet" if have_pyarrow() else "csv")
    assert (folder / "local" / "cases.csv").is_file()
    for name in ("summary.csv", "peaks.csv", "summary.md", "ida.csv", "ida.png", "fragility.csv", "fragility.png"):
        assert (folder / "report" / name).stat().st_size > 0, name
    summary = (folder / "report" / "summary.md").read_text()
    assert "| FSF-I | all | 96 | 0 |" in summary


@pytest.mark.slow
def test_the_same_sweep_through_a_dask_local_cluster_gives_the_same_rows(large_local, capsys):
    pytest.importorskip("distributed", reason="dask.distributed is not installed (pip install '.[cluster]')")
    study, folder = large_local
    status, out = _sweep(capsys, str(study), "--out", str(folder / "dask"), "--local-cluster", "--workers", "2")
    assert status == 0 and "Dask, 2 worker threads on a LocalCluster" in out, out
    local, dask = _rows(folder / "local"), _rows(folder / "dask")
    assert set(local) == set(dask)
    peaks = [name for name in next(iter(local.values())) if name.startswith(("passive.", "controlled."))]
    for key, row in local.items():
        assert all(row[name] == dask[key][name] for name in peaks), key


def test_the_table_2_study_shows_peaks_invariant_under_30_percent_stiffness_error(tmp_path, capsys, records_dir):
    study = PROFILES / "studies" / "robustness_table2.yaml"
    status, out = _sweep(capsys, str(study), "--out", str(tmp_path / "t2"), "--workers", "0", "--records-dir", str(records_dir))
    assert status == 0, out
    rows = {row["control.design_stiffness_scale"]: row for row in _rows(tmp_path / "t2").values()}
    assert sorted(rows) == [0.7, 1.0, 1.3] and {row["record"] for row in rows.values()} == {"el_centro"}
    nominal = rows[1.0]
    for scale in (0.7, 1.3):
        row = rows[scale]
        assert row["controlled.sliding_displacement_m"] == pytest.approx(nominal["controlled.sliding_displacement_m"], rel=0.01)
        assert row["controlled.peak_force_pct_weight"] == pytest.approx(nominal["controlled.peak_force_pct_weight"], rel=0.01)
        assert row["reduction_pct.max_drift_m"] > 99.0 and row["reduction_pct.max_floor_acceleration_m_s2"] > 97.5
        assert row["reduction_pct.max_drift_m"] == pytest.approx(nominal["reduction_pct.max_drift_m"], abs=0.5)
