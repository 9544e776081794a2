"""docs/SAFETY.md's stall budget per rate, re-derived here from the shipped profile's rig physics.

The budget is the smaller of (1) the drive watchdog less two periods, halved, and (2) the
stroke look-ahead less the actuator's lag and the oldest sensor sample accepted. These tests
compute both at 500 Hz, 1 kHz and 2 kHz from the profile's own values, check that the profile's
``safety.run.max_stall_s`` never exceeds the derivation at any of them, and that the doc's
figures are the computed ones, so the doc cannot drift from the profile.
"""

from __future__ import annotations

import re

import pytest

from harness.profile import load_profile
from tests.conftest import PROFILES, REPO

RATES = {500.0: "500 Hz", 1000.0: "1 kHz", 2000.0: "2 kHz"}


def derivation(rate_hz: float) -> dict[str, float]:
    """Both bounds, the budget and what it means at ``rate_hz``, from nceer_4dof.yaml."""
    profile = load_profile(PROFILES / "nceer_4dof.yaml", overrides=["can.fd=true"])
    safety, period = profile.safety, 1.0 / rate_hz
    watchdog = profile.rig.drive.watchdog_timeout_s
    watchdog_bound = watchdog - 2.0 * period
    look_ahead = safety.stroke.stop_time_s - safety.force.actuator_time_constant_s - safety.sensors.max_sensor_age_s
    budget = min(watchdog_bound / 2.0, look_ahead)
    return {
        "watchdog_ms": watchdog_bound * 1e3, "halved_ms": watchdog_bound / 2.0 * 1e3, "look_ahead_ms": look_ahead * 1e3,
        "budget_ms": budget * 1e3, "profile_budget_ms": safety.run.max_stall_s * 1e3,
        "missed": round(budget / period) - 1, "force_step_N": safety.force.max_force_rate_N_per_s * period,
    }


@pytest.mark.parametrize("rate_hz", sorted(RATES))
def test_the_profiles_budget_never_exceeds_the_derivation_at_any_rate(rate_hz: float) -> None:
    d = derivation(rate_hz)
    assert d["profile_budget_ms"] <= d["budget_ms"] + 1e-9
    assert d["budget_ms"] == pytest.approx(20.0), "set by the stroke look-ahead, the same at every rate"
    assert d["look_ahead_ms"] < d["halved_ms"]


@pytest.mark.parametrize("rate_hz", sorted(RATES))
def test_the_safety_doc_gives_the_derived_figures_for_each_rate(rate_hz: float) -> None:
    d = derivation(rate_hz)
    text = (REPO / "docs" / "SAFETY.md").read_text()
    match = re.search(rf"^- \*\*{re.escape(RATES[rate_hz])}\*\* .*?(?=^- \*\*|^\s*$)", text, re.MULTILINE | re.DOTALL)
    assert match, f"docs/SAFETY.md has no stall-budget line for {RATES[rate_hz]}"
    line = " ".join(match.group(0).split())
    assert f"{d['watchdog_ms']:g} ms" in line and f"halved {d['halved_ms']:g} ms" in line
    assert f"Budget **{d['budget_ms']:.0f} ms**, {d['missed']} " in line
    assert f"{d['force_step_N']:.0f} N" in line
