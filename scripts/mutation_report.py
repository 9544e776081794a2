"""After ``python -m mutmut run`` (``make mutation``): re-run the import-time mutants, then print the kill rate and survivors.

mutmut forks each mutant's test run from a process that has imported the project with no
mutant active, and maps each function to the tests that called it. Code that runs only while
a module is imported (the CRC table in drivers/protocol/e2e.py, the safety table, the trip-action
defaults) is therefore never run with its mutant active, and mutmut's map gives it only the
first test of the session (the one running when the imports happened). Its survivors are run
again here, each in a fresh interpreter over the whole test selection of ``[tool.mutmut]``,
so the mutant is active while the modules are imported.

A mutant counts as killed when a test failed (``killed``, or a failed fresh re-run) or the
tests did not finish within mutmut's timeout (``timeout``). A survivor judged equivalent (no input
can tell it from the original) is listed in ``scripts/mutation_verdicts.toml`` with the line it
plants and why; the kill rate is over the others. A verdict whose line no longer matches the
mutant's (the code changed) is reported as stale and counts as a survivor until judged again.
The other survivors are printed with their diff, to be killed by a test or judged.

Usage: python scripts/mutation_report.py [--jobs N]   (from the checkout, after a finished run)
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tomllib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

MUTANTS = Path("mutants")
VERDICTS = Path(__file__).with_name("mutation_verdicts.toml")
#: Longest fresh re-run of one mutant over the whole selection (s); a hang counts as killed, as in mutmut.
RERUN_TIMEOUT_S = 900.0


def _mutmut(*args: str) -> str:
    return subprocess.run([sys.executable, "-m", "mutmut", *args], check=True, capture_output=True, text=True).stdout


def _selection() -> list[str]:
    return tomllib.loads(Path("pyproject.toml").read_text())["tool"]["mutmut"]["pytest_add_cli_args_test_selection"]


def _first_test(selection: list[str]) -> str:
    """The first test pytest collects from the selection (mutmut's map gives it what ran at import)."""
    out = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider", *selection],
                         cwd=MUTANTS, capture_output=True, text=True).stdout
    return next(line.strip() for line in out.splitlines() if "::" in line)


def _function_of(mutant: str) -> str:
    return mutant.rsplit("__mutmut_", 1)[0]


def _killed_in_a_fresh_interpreter(mutant: str, selection: list[str]) -> bool:
    """Run the whole selection with ``mutant`` active from the first import; True when a test fails or it hangs."""
    env = {**os.environ, "MUTANT_UNDER_TEST": mutant}
    try:
        done = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *selection],
                              cwd=MUTANTS, env=env, capture_output=True, timeout=RERUN_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        return True
    return done.returncode not in (0, 5)


def _planted_line(diff: str) -> str:
    """The first line the mutant adds, stripped: what a verdict is checked against."""
    return next((line[1:].strip() for line in diff.splitlines() if line.startswith("+") and not line.startswith("+++")),
                "")


def _equivalent(survivors: list[str]) -> tuple[dict[str, str], list[str]]:
    """Survivors with a current equivalence verdict (name to why), and the names of stale verdicts."""
    verdicts = {v["mutant"]: v for v in tomllib.loads(VERDICTS.read_text()).get("equivalent", [])} if VERDICTS.is_file() else {}
    equivalent: dict[str, str] = {}
    stale: list[str] = []
    for name in survivors:
        verdict = verdicts.get(name)
        if verdict is None:
            continue
        if _planted_line(_mutmut("show", name)) == verdict["line"].strip():
            equivalent[name] = verdict["why"]
        else:
            stale.append(name)
    return equivalent, stale


def _verdict_table(equivalent: dict[str, str]) -> str:
    """The equivalent survivors as a markdown table: one row per function and reason, with the mutant numbers."""
    rows: dict[tuple[str, str], list[str]] = {}
    for name, why in equivalent.items():
        function, _, number = name.rpartition("__mutmut_")
        rows.setdefault((function.replace(".x_", ".").replace(".xǁ", ".").replace("ǁ", "."), why), []).append(number)
    lines = ["| function | mutants | why equivalent |", "|---|---|---|"]
    lines += [f"| `{function}` | {', '.join(sorted(numbers, key=int))} | {why} |"
              for (function, why), numbers in sorted(rows.items())]
    return "\n".join(lines)


def main() -> int:
    """Re-run the import-time survivors, print the summary and every survivor's diff."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--jobs", type=int, default=2, help="fresh re-runs in parallel (default 2)")
    parser.add_argument("--no-rerun", action="store_true", help="report mutmut's verdicts as they are, without the re-runs")
    args = parser.parse_args()
    if not (MUTANTS / "mutmut-stats.json").is_file():
        print(f"no finished run in {MUTANTS}/: run `python -m mutmut run` first", file=sys.stderr)
        return 1
    status = {name.strip(): state.strip() for name, _, state in
              (line.rpartition(":") for line in _mutmut("results", "--all", "true").splitlines() if ":" in line)}
    selection = _selection()
    first = _first_test(selection)
    tests_of = json.loads((MUTANTS / "mutmut-stats.json").read_text())["tests_by_mangled_function_name"]
    import_time = [] if args.no_rerun else sorted(
        name for name, state in status.items() if state == "survived" and tests_of.get(_function_of(name)) == [first])
    with ThreadPoolExecutor(max(1, args.jobs)) as pool:
        rerun = dict(zip(import_time, pool.map(lambda m: _killed_in_a_fresh_interpreter(m, selection), import_time),
                         strict=True))
    for name, killed in rerun.items():
        if killed:
            status[name] = "killed at import"
    counts: dict[str, int] = {}
    for state in status.values():
        counts[state] = counts.get(state, 0) + 1
    print("mutants by outcome: " + ", ".join(f"{state} {n}" for state, n in sorted(counts.items())))
    print(f"import-time survivors re-run in a fresh interpreter: {len(import_time)}, killed there: {sum(rerun.values())}")
    killed = counts.get("killed", 0) + counts.get("timeout", 0) + counts.get("killed at import", 0)
    survivors = [name for name, state in status.items() if state in ("survived", "no tests", "suspicious")]
    equivalent, stale = _equivalent(survivors)
    judged = killed + len(survivors)
    if judged:
        print(f"kill rate: {killed}/{judged} = {100.0 * killed / judged:.1f} % (killed + timeout + killed at import, "
              "over every mutant run; survivors and mutants no selected test reaches count against it)")
        print(f"equivalent survivors ({VERDICTS.name}): {len(equivalent)}; stale verdicts: {len(stale)}")
        print(f"kill rate of non-equivalent mutants: {killed}/{judged - len(equivalent)} = "
              f"{100.0 * killed / (judged - len(equivalent)):.1f} %")
    for name in stale:
        print(f"stale verdict (the mutant's line changed; judge it again): {name}")
    if equivalent:
        print()
        print(_verdict_table(equivalent))
    for name in survivors:
        if name not in equivalent:
            print()
            print(f"[{status[name]}] " + _mutmut("show", name).rstrip())
    return 0


if __name__ == "__main__":
    sys.exit(main())
