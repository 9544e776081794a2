"""Building the command line's parser and printing ``--help`` import nothing heavy.

A command that does not need scipy, numba, matplotlib or dask must not pay for them: ``harness --help``
took 2.1 s on a quiet machine when the parser imported ``scipy.signal`` through the identification
modules (issue 32). Each check runs in a fresh interpreter, so what an earlier test imported does not
hide a regression.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

#: Packages the parser must leave unimported: each costs 0.1-1.2 s to import (numpy 0.11-0.16 s: with it
#: `harness --help` took 0.44-0.66 s, without it 0.22-0.30 s, on the 2-vCPU VM on 29 Nov 2026).
HEAVY = ("scipy", "numba", "llvmlite", "matplotlib", "pandas", "dask", "distributed", "pyarrow", "cantools", "can", "numpy")

PROBE = """
import json, sys, contextlib, io
from harness import cli
{action}
print(json.dumps(sorted({{name.split('.')[0] for name in sys.modules}})))
"""


def _top_level_modules_after(action: str) -> set[str]:
    done = subprocess.run([sys.executable, "-c", PROBE.format(action=action)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize("action", [
    "cli.build_parser()",
    "with contextlib.redirect_stdout(io.StringIO()): cli.main(['--help'])",
    "with contextlib.redirect_stdout(io.StringIO()): cli.main(['identify', 'actuator', '--help'])",
    "with contextlib.redirect_stdout(io.StringIO()): cli.main(['identify', 'structure', '--help'])",
    "with contextlib.redirect_stdout(io.StringIO()): cli.main(['dry-run', '--help'])",
], ids=["parser", "help", "identify-actuator-help", "identify-structure-help", "dry-run-help"])
def test_the_parser_and_help_leave_the_heavy_packages_unimported(action: str) -> None:
    imported = _top_level_modules_after(action)
    assert "harness" in imported  # the probe ran
    assert not imported & set(HEAVY), f"imported by {action}: {sorted(imported & set(HEAVY))}"


def test_the_safety_package_still_gives_its_names() -> None:
    """The package loads its names on first use (harness/safety/__init__.py): each named one resolves."""
    import harness.safety as safety

    for name in safety.__all__:
        assert getattr(safety, name) is not None
    with pytest.raises(AttributeError, match="no_such_name"):
        safety.no_such_name  # noqa: B018 (the access is the test)


def test_the_synthetic_record_leaves_scipy_signal_unimported() -> None:
    """``harness simulate``'s default record: its filter is written out (harness/motions/synthetic.py), not
    taken from ``scipy.signal``, whose import (with ``scipy.stats``) was a quarter of the command's time."""
    probe = ("import json, sys\nfrom harness.motions.synthetic import synthetic_record\nsynthetic_record(seed=1)\n"
             "print(json.dumps(sorted(name for name in sys.modules if name.startswith('scipy'))))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    imported = set(json.loads(done.stdout.strip().splitlines()[-1]))
    assert not {"scipy.signal", "scipy.stats"} & imported, sorted(imported)
