"""A dry run with ``--overlay``: the run folder's metadata names the overlay and its hash,
and the resolved profile it ran holds the overlay's values."""

from __future__ import annotations

import hashlib
import json

import yaml

from harness.cli import main


def test_a_dry_run_records_its_overlay(tmp_path, capsys) -> None:
    overlay = tmp_path / "identified.yaml"
    overlay.write_text("bearing:\n  mu_max: 0.071\n")
    logs = tmp_path / "logs"
    status = main(["dry-run", "--lockstep", "--record", "synthetic", "--duration", "1", "--overlay", str(overlay),
                   "--log-dir", str(logs), "--quiet"])
    assert status == 0, capsys.readouterr()
    (run,) = [p for p in logs.iterdir() if p.is_dir()]
    metadata = json.loads((run / "metadata.json").read_text())
    assert metadata["overlay"] == {"path": str(overlay.resolve()), "sha256": hashlib.sha256(overlay.read_bytes()).hexdigest()}
    profiles = list(run.glob("profile*.yaml"))
    assert profiles, sorted(p.name for p in run.iterdir())
    assert yaml.safe_load(profiles[0].read_text())["bearing"]["mu_max"] == 0.071
