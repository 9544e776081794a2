"""End to end, as a lab would: a lockstep dry run on a rig whose truth is not the profile's, then ``harness identify``.

The virtual rig gets its own stiffness (+15 %, -12 %, +18 %) and bearing (mu_max +25 %, mu_delta
-20 %, a_mu -22 %) through ``rig.truth``; each run folder's profile holds the design. The
identification reads only the run folders, with the rig's noise and quantization as shipped.
Minutes each: marked slow (benchmarks/identify_dry_run.py prints the full table).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
import yaml

from harness import exit_codes
from harness.cli import main
from harness.model.building import fixed_base_modes
from harness.profile import load_profile

DESIGN = load_profile()
TRUE_STIFFNESS = (0.8395e6, 1.848e6, 1.7464e6)
TRUE_BEARING = {"mu_max": 0.075, "mu_delta": 0.024, "a_mu_s_per_m": 70.0}
TRUTH = [
    "--set", f"rig.truth.structure.story_stiffness_N_per_m=[{','.join(f'{k:g}' for k in TRUE_STIFFNESS)}]",
    *[word for key, value in TRUE_BEARING.items() for word in ("--set", f"rig.truth.bearing.{key}={value:g}")],
]


def _dry_run(log_dir: Path, *options: str) -> Path:
    status = main(["dry-run", "--lockstep", "--quiet", "--log-dir", str(log_dir), *TRUTH, *options])
    assert status == exit_codes.OK
    (folder,) = [p for p in log_dir.iterdir() if (p / "metadata.json").is_file()]
    return folder


@pytest.mark.slow
def test_a_white_noise_dry_run_identifies_the_rigs_structure(tmp_path, capsys):
    run = _dry_run(tmp_path / "logs", "--record", "white_noise:0.5-20", "--duration", "40")
    status = main(["identify", "structure", str(run), "--out", str(tmp_path / "ident")])
    printed = capsys.readouterr().out
    assert status == exit_codes.OK, printed
    overlay = yaml.safe_load((tmp_path / "ident" / "identified.yaml").read_text())["structure"]
    assert np.allclose(overlay["story_stiffness_N_per_m"], TRUE_STIFFNESS, rtol=0.1)
    truth = dataclasses.replace(DESIGN.structure, story_stiffness_N_per_m=TRUE_STIFFNESS)
    true_omega, true_zeta = fixed_base_modes(truth)
    found = [float(line.split("mode ")[1].split(": ")[1].split(" Hz")[0]) for line in printed.splitlines()
             if line.strip().startswith("mode ")]  # "mode 1: 2.398 Hz (95 % 2.397-2.399), damping ..."
    assert np.allclose(found, true_omega / (2 * np.pi), rtol=0.02)
    assert overlay["first_mode_damping_ratio"] == pytest.approx(true_zeta[0], rel=0.3)


@pytest.mark.slow
def test_an_earthquake_dry_run_identifies_the_rigs_bearing(tmp_path, capsys):
    run = _dry_run(tmp_path / "logs", "--duration", "30")
    status = main(["identify", "bearing", str(run), "--out", str(tmp_path / "ident")])
    printed = capsys.readouterr().out
    assert status == exit_codes.OK, printed
    overlay = yaml.safe_load((tmp_path / "ident" / "identified.yaml").read_text())["bearing"]
    estimates = {line.split(" = ")[0].strip(): line for line in printed.splitlines() if " = " in line and "+/-" in line}
    for key, value in TRUE_BEARING.items():
        if key in overlay:
            assert overlay[key] == pytest.approx(value, rel=0.1), key
        else:
            # Left out of the overlay by the fit's quality gate (standard error above 10 %): a_mu, the shape of
            # the velocity law, needs slow sliding through many reversals, and the shipped controller (the
            # estimator's 6 dB margin) leaves fewer of them in 30 s (22 % measured; 13 % in 60 s). The estimate
            # printed beside "not determined" must still be near the truth.
            assert key == "a_mu_s_per_m" and "not determined" in estimates[key], printed
            assert float(estimates[key].split(" = ")[1].split(" +/-")[0]) == pytest.approx(value, rel=0.1), printed
    assert {"mu_max", "mu_delta"} <= set(overlay)
