"""What an identification reads from run folders: the columns it needs, on a uniform grid, and where they came from.

Any run folder the harness writes can be used: a dry run's or a real run's (``signals.csv``
is the control loop's row: what the rig measured), a ``simulate --rig-effects`` twin's, or an
offline simulation's case. Each identification names the columns it needs
(:func:`require_columns`); a folder without one of them is refused with
:class:`IdentificationError`, naming the run, the columns missing and what each would have held.

The masses, restraining springs and the design values an identification starts from are the
ones of the run's own ``profile.yaml`` (the top-level ``structure`` and ``bearing``: the design
model the lab believes, not ``rig.truth``), so a run is identified with the model it ran on.
"""

from __future__ import annotations

import hashlib
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from harness.config.schema import build
from harness.errors import HarnessError
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.recording import RunData, load_run
from harness.recording.layout import SIGNALS_FILE
from harness.signals import columns as layout


class IdentificationError(HarnessError, ValueError):
    """Data an identification cannot use (a run without the columns it needs, runs of different buildings, ...).

    The message names the run and says what was expected.
    """


@dataclass(frozen=True)
class RunUsed:
    """A run folder an identification used, as ``identification.json`` records it.

    Attributes
    ----------
    path : Path
    signals_sha256 : str
        SHA-256 of its ``signals.csv``: the data, byte for byte.
    kind, outcome : str
        ``dry-run``, ``run`` or ``simulation``; how it ended.
    record : str or None
        The ground motion it played.
    rows : int
    """

    path: Path
    signals_sha256: str
    kind: str
    outcome: str
    record: str | None
    rows: int

    def as_dict(self) -> dict[str, Any]:
        return {"path": str(self.path.resolve()), "signals_sha256": self.signals_sha256, "kind": self.kind,
                "outcome": self.outcome, "record": self.record, "rows": self.rows}


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def run_used(run: RunData) -> RunUsed:
    """What ``identification.json`` says of ``run``."""
    name = run.metadata.get("files", {}).get("signals", SIGNALS_FILE)
    return RunUsed(run.path, file_sha256(run.path / str(name)), run.kind, run.outcome, run.record_name, run.n_rows)


def load_runs_checked(paths: Iterable[Path | str]) -> list[RunData]:
    """Read the run folders, in the order given, refusing any an identification must not use.

    A run whose ``metadata.json`` still says ``incomplete`` never finished: the process that
    recorded it died or was killed, so its rows end at a last flush nobody checked, and
    nothing says what the rig was doing then.

    Raises
    ------
    RunFolderError
        For a path that is no run folder (missing, no ``metadata.json``, unknown format).
    IdentificationError
        When no path is given, or for a run whose outcome is ``incomplete``.
    """
    runs = [load_run(path) for path in paths]
    if not runs:
        raise IdentificationError("found no run folder, expected at least one RUN")
    for run in runs:
        if run.outcome == "incomplete":
            raise IdentificationError(
                f"run {run.path}: its outcome is 'incomplete' (the process that recorded it never finished it, so its "
                "rows end wherever the recorder last wrote); expected a run that ended (completed, stopped or tripped)"
            )
    return runs


def distinct_runs_used(runs: Sequence[RunData]) -> tuple[RunUsed, ...]:
    """What ``identification.json`` says of each run, refusing the same data given twice.

    A copy of a run is no second measurement: fitted twice, its noise counts twice and the
    standard errors shrink by the square root of two, so a fit that fails its quality gate on
    one run would pass it on the run and its copy.

    Raises
    ------
    IdentificationError
        Naming both runs whose ``signals.csv`` have the same SHA-256.
    """
    used = tuple(run_used(run) for run in runs)
    first: dict[str, RunUsed] = {}
    for run in used:
        earlier = first.setdefault(run.signals_sha256, run)
        if earlier is not run:
            raise IdentificationError(
                f"runs {earlier.path} and {run.path}: the same signals.csv (SHA-256 {run.signals_sha256[:16]}...); "
                "expected each run once (a copy is no second measurement: it would halve the fit's variance)"
            )
    return used


def require_columns(run: RunData, needed: Mapping[str, str], purpose: str) -> None:
    """Refuse ``run`` unless it holds every column of ``needed`` (column -> what it holds).

    Raises
    ------
    IdentificationError
        Naming the run, every missing column with what it holds, and what they are needed for.
    """
    missing = [name for name in needed if not run.has(name)]
    if missing:
        listed = "; ".join(f"{name} ({needed[name]})" for name in missing)
        raise IdentificationError(
            f"run {run.path}: has no {', '.join(missing)}; expected the columns {purpose} needs: {listed}. "
            f"It holds: {', '.join(run.columns) or 'no columns'}"
        )


def floor_columns(n_stories: int) -> dict[str, str]:
    """The floor accelerations of an ``n_stories`` building, as :func:`require_columns` takes them."""
    return {layout.floor_acceleration(j): f"absolute acceleration of floor {j} (m/s^2)" for j in range(1, n_stories + 1)}


def design_building(run: RunData) -> BuildingConfig:
    """The building of the run's ``profile.yaml`` (its top-level ``structure``: the design model).

    Raises
    ------
    ProfileError
        If the run's profile has no valid ``structure`` section.
    """
    return build(BuildingConfig, run.profile.get("structure"), source=str(run.path / "profile.yaml"), path="structure")


def design_bearing(run: RunData) -> BearingConfig:
    """The bearing of the run's ``profile.yaml`` (its top-level ``bearing``)."""
    return build(BearingConfig, run.profile.get("bearing"), source=str(run.path / "profile.yaml"), path="bearing")


def same_building(runs: Sequence[RunData]) -> BuildingConfig:
    """The building every run was made with: masses and restraining springs must agree.

    Raises
    ------
    IdentificationError
        Naming the first run whose masses or springs differ from the first run's.
    """
    first = design_building(runs[0])
    for run in runs[1:]:
        other = design_building(run)
        if (other.floor_masses_kg, other.base_mass_kg, other.restoring_stiffness_N_per_m) != (
            first.floor_masses_kg, first.base_mass_kg, first.restoring_stiffness_N_per_m
        ):
            raise IdentificationError(
                f"run {run.path}: its profile's masses or restraining springs differ from those of {runs[0].path}; "
                "expected runs of one building (identify each building on its own)"
            )
    return first


def uniform_signals(run: RunData, names: Iterable[str]) -> tuple[float, dict[str, np.ndarray]]:
    """The named columns on a uniform time grid at the run's median step, and its rate (Hz).

    A loop's rows are at its ticks; a real-time run's may jitter by a little, and a few
    may be missing. Each column is interpolated linearly onto ``t_0 + k / rate``.

    Raises
    ------
    IdentificationError
        For a run of fewer than 16 rows, whose times do not increase, or with a value that is
        not a finite number (NaN: not measured) in a column used.
    """
    names = tuple(names)
    t = run[layout.TIME]
    if len(t) < 16:
        raise IdentificationError(f"run {run.path}: holds {len(t)} rows, expected at least 16")
    for name in (layout.TIME, *names):
        bad = np.flatnonzero(~np.isfinite(run[name]))
        if len(bad):
            raise IdentificationError(
                f"run {run.path}: {name} is {run[name][bad[0]]} on {len(bad)} row(s), the first at line {bad[0] + 2} of "
                "signals.csv; expected a number on every row (a row not measured cannot be fitted)"
            )
    steps = np.diff(t)
    if np.any(steps <= 0.0):
        raise IdentificationError(f"run {run.path}: its times t_s do not increase at row {int(np.argmin(steps > 0)) + 2}")
    step = float(np.median(steps))
    grid = t[0] + np.arange(int(np.floor((t[-1] - t[0]) / step + 1e-9)) + 1) * step
    return 1.0 / step, {name: np.interp(grid, t, run[name]) for name in names}
