"""Why the adaptive compensator trips ``compensation_fault``: measured on the rig twin (issue 31, item 4).

Three measurements, each on the rig twin (``harness simulate --rig-effects``: the servo-hydraulic
actuator and table, the sensors, the supervisor), the phi controller with ``control.compensation:
adaptive``, 30 s, time scale 2:

1. ``runs``: El Centro 0.34 g, Hachinohe 0.23 g, Pacoima 0.40 g, with no asynchrony and with one
   loop period of it (``asynchronous_delay_s`` 2 ms, what a real-time dry run reproduces), on the
   shipped rig (its servo controller's velocity feed-forward, alpha 1) and on a plain force loop
   (alpha 0, and the tracking check told so); and on the shipped rig with an ideal feed-forward
   velocity (the stroke LVDT without delay, its filter at 2 kHz). Per run: the outcome, when the
   first coefficient left its range, which one and the fit that was refused.
2. ``realign``: the inputs the compensator was given in the shipped-rig Pacoima run (no
   asynchrony) replayed into a fresh compensator with each regression row realigned: the velocity,
   the load cell or the command sent one tick (2 ms) or half a tick older or newer. Per variant: the
   range of ``a2`` the fits take in the record's quiet part (13-16 s) and how many fits left a range.
3. ``residual``: the same inputs, fitted offline over the compensator's 2 s window at chosen
   times by least squares, with the three terms of (C5) and with a fourth, the sliding
   acceleration ``F(xddot_b) = (xdot_b - F(xdot_b)) / tau_f``: what the window asks of each term.
4. ``with_acceleration`` (``--only with_acceleration``): that fourth term closed in the loop, a
   measurement-only prototype (:class:`WithAcceleration`: numpy solves, clipped to the ranges and
   ``a3`` to 0-2000 kg, not the shipped compensator), on El Centro with one period of asynchrony.

Usage: python benchmarks/adaptive_trips.py [--records-dir DIR] [--out FILE] [--only with_acceleration]
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from drivers.measurements import Measurements  # noqa: E402
from harness.control.adaptive_compensation import AdaptiveCompensator  # noqa: E402
from harness.control.factory import build_controller_for_rig, make_compensator  # noqa: E402
from harness.profile import Profile, load_profile  # noqa: E402
from harness.runs.options import StudyOptions, prepare_motion, resolve_profile  # noqa: E402
from harness.simulation.twin import run_rig_twin  # noqa: E402

RECORDS = {"el_centro": 0.34, "hachinohe": 0.23, "pacoima": 0.40}
PERIOD_S = 0.002
PLAIN_LOOP = ("rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0")
IDEAL_FEEDFORWARD_VELOCITY = ("rig.actuator.hydraulics.feedforward.velocity_filter_hz=2000",
                              "rig.actuator.hydraulics.feedforward.lvdt.delay_s=0")
RIGS = {"shipped (alpha 1)": (), "plain loop (alpha 0)": PLAIN_LOOP, "ideal feed-forward velocity": IDEAL_FEEDFORWARD_VELOCITY}


class Recorder:
    """The adaptive compensator, with what it was given and what it fitted at every update."""

    name = "adaptive"

    def __init__(self, compensator: AdaptiveCompensator):
        self.compensator = compensator
        self.rows: list[tuple[float, ...]] = []

    def __getattr__(self, attribute: str) -> Any:
        return getattr(self.compensator, attribute)

    def reset(self) -> None:
        """As the compensator's."""
        self.compensator.reset()

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """The compensator's command; its inputs, coefficients and flags recorded."""
        command = self.compensator.update(t, dt, force_N, meas, applied_N)
        c = self.compensator
        self.rows.append((t, meas.actuator_force_N, meas.sliding_velocity_m_s, applied_N, *c.coefficients,
                          float(c.pinned), c.bound_value))
        return command


def _profile(record: str, records_dir: str, overrides: tuple[str, ...]) -> Profile:
    profile = load_profile(overrides=["control.compensation=adaptive", *overrides])
    options = StudyOptions(record=record, records_dir=records_dir, pga_g=RECORDS[record], time_scale=2.0, duration_s=30.0)
    return resolve_profile(profile, options)


def twin_run(record: str, records_dir: str, overrides: tuple[str, ...], delay_s: float) -> tuple[dict, np.ndarray]:
    """One twin run with the compensator recorded: its summary and the recorded rows."""
    profile = _profile(record, records_dir, overrides)
    recorder = Recorder(make_compensator(profile, controller="phi"))
    result = run_rig_twin(profile, prepare_motion(profile), 1.0 / PERIOD_S, build_controller_for_rig(profile, "phi"),
                          asynchronous_delay_s=delay_s, compensator=recorder)  # type: ignore[arg-type]
    rows = np.array(recorder.rows)
    pinned = np.flatnonzero(rows[:, 8] > 0)
    summary = {"record": record, "asynchrony_ms": delay_s * 1e3, "outcome": result.extra["outcome"],
               "trip_reason": result.extra["trip_reason"], "end_s": float(rows[-1, 0])}
    if pinned.size:
        k = int(pinned[0])
        names = ("a0", "a1_s", "a2_Ns_per_m", "a3_kg")
        low = np.array(recorder.compensator._low)
        high = np.array(recorder.compensator._high)
        at = [i for i in range(4) if rows[k, 4 + i] in (low[i], high[i])]
        summary.update(first_pinned_s=float(rows[k, 0]), coefficient=names[at[0]] if at else "?",
                       refused_fit=float(rows[k, 9]))
    return summary, rows


class WithAcceleration:
    """(C5) with a fourth term ``a3 F(xddot_b)``, fitted as the shipped compensator fits (C5); for measurement only.

    The window, filter, reference, excitation check and ranges are the shipped compensator's,
    ``a3`` held to 0-2000 kg; solved with numpy, clipped, and ``pinned`` when a fit was clipped.
    """

    name = "adaptive"

    def __init__(self, start: tuple[float, float, float], window_s: float = 2.0, tau_f: float = 0.01, tau_r: float = 0.004):
        self.size, self.tau_f, self.tau_r = int(round(window_s / PERIOD_S)), tau_f, tau_r
        self.low, self.high = np.array([0.8, 0.0, 0.0, 0.0]), np.array([1.25, 0.02, 2.0e5, 2000.0])
        self.start = np.array([*start, 0.0])
        self.rows: list[tuple[float, ...]] = []
        self.reset()

    def reset(self) -> None:
        """Empty window, coefficients at their start."""
        self.ring = np.zeros((self.size, 5))
        self.count = self.head = 0
        self.coefficients = self.start.copy()
        self.reference_N = self.command_N = self.bound_value = 0.0
        self.pinned = self.diverged = self.primed = False
        self.u_f = self.v_f = self.y_f = 0.0

    def update(self, t: float, dt: float, force_N: float, meas: Measurements, applied_N: float) -> float:
        """Learn from the previous command and this tick's response, then command ``a0 r + a1 r' + a2 v + a3 F(v')``."""
        from harness.control.compensation import reference_step

        u, v = meas.actuator_force_N, meas.sliding_velocity_m_s
        if not self.primed:
            self.u_f, self.v_f, self.y_f, self.primed = u, v, applied_N, True
        alpha = 1.0 - math.exp(-dt / self.tau_f)
        self.u_f += alpha * (u - self.u_f)
        self.v_f += alpha * (v - self.v_f)
        self.y_f += alpha * (applied_N - self.y_f)
        self.ring[self.head] = (self.u_f, (u - self.u_f) / self.tau_f, self.v_f, (v - self.v_f) / self.tau_f, self.y_f)
        self.head, self.count = (self.head + 1) % self.size, min(self.count + 1, self.size)
        if 2 * self.count >= self.size:
            x, y = self.ring[: self.count, :4], self.ring[: self.count, 4]
            normal = x.T @ x
            scale = np.sqrt(np.diag(normal))
            if np.all(scale > 0) and np.linalg.det(normal / np.outer(scale, scale)) >= 1.0e-4:
                solution = np.linalg.solve(normal, x.T @ y)
                clipped = np.clip(solution, self.low, self.high)
                self.pinned = bool(np.any(clipped != solution))
                self.coefficients = clipped
        self.reference_N, rate = reference_step(self.reference_N, force_N, dt, self.tau_r)
        a = self.coefficients
        self.command_N = float(a[0] * self.reference_N + a[1] * rate + a[2] * v + a[3] * (v - self.v_f) / self.tau_f)
        self.rows.append((t, *a, float(self.pinned)))
        return self.command_N


def with_acceleration(records_dir: str, delay_s: float = PERIOD_S) -> dict:
    """The prototype on El Centro with ``delay_s`` of asynchrony: outcome and its coefficients over the record."""
    profile = _profile("el_centro", records_dir, ())
    shipped = make_compensator(profile, controller="phi")
    assert isinstance(shipped, AdaptiveCompensator)
    prototype = WithAcceleration(tuple(float(x) for x in shipped.coefficients))
    result = run_rig_twin(profile, prepare_motion(profile), 1.0 / PERIOD_S, build_controller_for_rig(profile, "phi"),
                          asynchronous_delay_s=delay_s, compensator=prototype)  # type: ignore[arg-type]
    rows = np.array(prototype.rows)
    spans = []
    for low, high in ((0.0, 5.0), (5.0, 10.0), (10.0, 15.0), (15.0, 20.0), (20.0, 30.0)):
        m = (rows[:, 0] >= low) & (rows[:, 0] < high)
        if m.any():
            spans.append({"from_s": low, "to_s": high, "a0": [float(rows[m, 1].min()), float(rows[m, 1].max())],
                          "a1_s": [float(rows[m, 2].min()), float(rows[m, 2].max())],
                          "a2_Ns_per_m": [float(rows[m, 3].min()), float(rows[m, 3].max())],
                          "a3_kg": [float(rows[m, 4].min()), float(rows[m, 4].max())], "ticks_pinned": int(rows[m, 5].sum())})
    return {"record": "el_centro", "asynchrony_ms": delay_s * 1e3, "outcome": result.extra["outcome"],
            "trip_reason": result.extra["trip_reason"], "end_s": float(rows[-1, 0]), "spans": spans}


def _replay(rows: np.ndarray, force: np.ndarray, velocity: np.ndarray, applied: np.ndarray) -> np.ndarray:
    """Fresh compensator (the shipped settings, started from the model) fed the given inputs: its coefficients and flags."""
    compensator = make_compensator(load_profile(overrides=["control.compensation=adaptive"]), controller="phi")
    assert isinstance(compensator, AdaptiveCompensator)
    out = np.zeros((rows.shape[0], 5))
    for k in range(rows.shape[0]):
        compensator._learn(PERIOD_S, force[k], velocity[k], applied[k])
        out[k, :4], out[k, 4] = compensator.coefficients, compensator.pinned
    return out


def _shift(x: np.ndarray, ticks: float) -> np.ndarray:
    """``x`` older by ``ticks`` (negative: newer); a half tick is the mean of two neighbours."""
    whole = int(math.floor(ticks))
    shifted = np.roll(x, whole)
    if whole > 0:
        shifted[:whole] = x[0]
    elif whole < 0:
        shifted[whole:] = x[-1]
    if ticks != whole:
        return 0.5 * (shifted + _shift(x, whole + 1))
    return shifted


def realign(rows: np.ndarray, quiet: tuple[float, float]) -> list[dict]:
    """The fits of the recorded inputs with each row realigned: ``a2`` over ``quiet`` and the fits out of range."""
    t, force, velocity, applied = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    variants = {"as recorded": (0, 0, 0)}
    for name, index in (("velocity", 0), ("load cell", 1), ("command", 2)):
        for ticks in (1.0, 0.5, -0.5, -1.0):
            shift = [0.0, 0.0, 0.0]
            shift[index] = ticks
            variants[f"{name} {abs(ticks):g} tick {'older' if ticks > 0 else 'newer'}"] = tuple(shift)
    mask = (t >= quiet[0]) & (t < quiet[1])
    results = []
    for name, (dv, du, dy) in variants.items():
        fits = _replay(rows, _shift(force, du), _shift(velocity, dv), _shift(applied, dy))
        results.append({"variant": name, "a2_min_Ns_per_m": float(fits[mask, 2].min()),
                        "a2_max_Ns_per_m": float(fits[mask, 2].max()), "a1_min_s": float(fits[mask, 1].min()),
                        "ticks_pinned": int(fits[:, 4].sum())})
    return results


def residual(rows: np.ndarray, times: tuple[float, ...], window_s: float = 2.0, tau_s: float = 0.01) -> list[dict]:
    """Least-squares fits over the window ending at each time: (C5)'s three terms, and with the sliding acceleration."""
    t, force, velocity, applied = rows[:, 0], rows[:, 1], rows[:, 2], rows[:, 3]
    alpha = 1.0 - math.exp(-PERIOD_S / tau_s)
    columns = np.zeros((t.size, 4))
    target = np.zeros(t.size)
    u_f, v_f, y_f = force[0], velocity[0], applied[0]
    for k in range(t.size):
        u_f += alpha * (force[k] - u_f)
        v_f += alpha * (velocity[k] - v_f)
        y_f += alpha * (applied[k] - y_f)
        columns[k] = (u_f, (force[k] - u_f) / tau_s, v_f, (velocity[k] - v_f) / tau_s)
        target[k] = y_f
    size = int(round(window_s / PERIOD_S))
    results = []
    for time_s in times:
        end = int(np.searchsorted(t, time_s))
        if end >= t.size:
            break
        window = slice(max(0, end - size + 1), end + 1)
        three, *_ = np.linalg.lstsq(columns[window, :3], target[window], rcond=None)
        four, *_ = np.linalg.lstsq(columns[window], target[window], rcond=None)
        rms3 = float(np.std(target[window] - columns[window, :3] @ three))
        rms4 = float(np.std(target[window] - columns[window] @ four))
        results.append({"t_s": time_s, "C5": [float(x) for x in three], "C5_rms_N": rms3,
                        "with_acceleration": [float(x) for x in four], "with_acceleration_rms_N": rms4,
                        "velocity_rms_m_s": float(np.std(columns[window, 2]))})
    return results


def main(argv: list[str] | None = None) -> int:
    """Run the three measurements and write them as JSON."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--records-dir", default=str(REPO.parent / "shared" / "data" / "ground_motions"))
    parser.add_argument("--out", default=str(REPO / "benchmarks" / "results" / "adaptive_trips.json"))
    parser.add_argument("--only", choices=("with_acceleration",), help="run this measurement alone, added to --out")
    args = parser.parse_args(argv)
    if args.only == "with_acceleration":
        out = Path(args.out)
        results = json.loads(out.read_text()) if out.is_file() else {}
        results["with_acceleration"] = with_acceleration(args.records_dir)
        out.write_text(json.dumps(results, indent=1))
        print(json.dumps(results["with_acceleration"]))
        return 0
    runs, recorded = [], {}
    for rig, overrides in RIGS.items():
        delays = (0.0, PERIOD_S) if rig != "ideal feed-forward velocity" else (0.0,)
        records = RECORDS if rig != "ideal feed-forward velocity" else {"el_centro": 0.34}
        for record in records:
            for delay in delays:
                summary, rows = twin_run(record, args.records_dir, overrides, delay)
                summary["rig"] = rig
                runs.append(summary)
                print(json.dumps(summary), flush=True)
                recorded[(rig, record, delay)] = rows
    pacoima = recorded[("shipped (alpha 1)", "pacoima", 0.0)]
    el_centro = recorded[("shipped (alpha 1)", "el_centro", 0.0)]
    results = {
        "runs": runs,
        "realign": realign(pacoima, (13.0, 16.0)),
        "residual": {"pacoima, shipped": residual(pacoima, (2.0, 3.0, 5.0, 8.0, 10.0, 12.0, 14.0, 16.0)),
                     "el_centro, shipped": residual(el_centro, (1.0, 1.2, 1.3))},
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(results, indent=1))
    for row in results["realign"]:
        print(json.dumps(row))
    for name, rows in results["residual"].items():
        for row in rows:
            print(name, json.dumps(row))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
