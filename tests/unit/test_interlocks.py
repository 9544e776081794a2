"""Tests of the stroke and force interlocks at and around their thresholds, and of check_config."""

from __future__ import annotations

import dataclasses

import pytest

from harness.config.schema import build
from harness.errors import ProfileError
from harness.safety.config import (
    ActuatorConfig,
    ForceConfig,
    SafetyConfig,
    SensorConfig,
    StrokeConfig,
    TripActionsConfig,
    check_config,
)
from harness.safety.events import Action
from harness.safety.interlocks import (
    ForceClamp,
    ForceRateLimit,
    StrokeHardLimit,
    StrokePredictiveLimit,
    StrokeSoftFade,
)

STROKE = StrokeConfig(soft_limit_m=0.05, fade_band_m=0.01, hard_limit_m=0.075, stop_time_s=0.1)
EPS = 1e-9


# ------------------------------------------------------------------ soft fade


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_soft_fade_passes_outward_force_inside_and_at_the_soft_limit(sign: float) -> None:
    fade = StrokeSoftFade(STROKE)
    for x in (0.0, 0.02, 0.05 - EPS, 0.05):
        assert fade.apply(sign * 1000.0, sign * x) == sign * 1000.0
        assert not fade.acted


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_soft_fade_scales_outward_force_linearly_across_the_band(sign: float) -> None:
    fade = StrokeSoftFade(STROKE)
    for fraction in (1e-6, 0.25, 0.5, 0.9):
        x = sign * (0.05 + fraction * 0.01)
        out = fade.apply(sign * 1000.0, x)
        assert fade.acted
        assert out == pytest.approx(sign * 1000.0 * (1.0 - fraction), rel=1e-6)
        assert out * sign > 0.0


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_soft_fade_is_zero_at_and_after_the_band_end(sign: float) -> None:
    fade = StrokeSoftFade(STROKE)
    for x in (0.06, 0.06 + EPS, 0.07, 1.0):
        assert fade.apply(sign * 1000.0, sign * x) == 0.0
        assert fade.acted


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_soft_fade_passes_force_towards_the_centre(sign: float) -> None:
    fade = StrokeSoftFade(STROKE)
    for x in (0.055, 0.06, 0.07):
        assert fade.apply(-sign * 1000.0, sign * x) == -sign * 1000.0
        assert not fade.acted


def test_soft_fade_action_is_fade() -> None:
    assert StrokeSoftFade.ACTION is Action.FADE and StrokeSoftFade.NAME == "stroke_soft"


# ------------------------------------------------------------------ hard and predictive


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_hard_limit_trips_at_and_beyond_not_below(sign: float) -> None:
    hard = StrokeHardLimit(STROKE)
    assert not hard.check(sign * (0.075 - 1e-7))
    assert hard.check(sign * 0.075)
    assert hard.check(sign * 0.08)
    assert "0.075" in hard.detail(sign * 0.08)
    assert StrokeHardLimit.ACTION is Action.TRIP


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_predictive_limit_trips_when_projection_reaches_hard(sign: float) -> None:
    pred = StrokePredictiveLimit(STROKE)
    # x_b = 0.05 m, projection over 0.1 s reaches 0.075 m at 0.25 m/s outward.
    assert not pred.check(sign * 0.05, sign * (0.25 - 1e-6))
    assert pred.check(sign * 0.05, sign * 0.25)
    assert pred.check(sign * 0.05, sign * 0.3)
    # moving back towards the centre: no trip even near the hard limit
    assert not pred.check(sign * 0.07, -sign * 0.3)
    assert "0.075" in pred.detail(sign * 0.05, sign * 0.3)


def test_predictive_limit_with_zero_stop_time_equals_hard_limit() -> None:
    pred = StrokePredictiveLimit(dataclasses.replace(STROKE, stop_time_s=0.0))
    assert not pred.check(0.0749, 100.0)
    assert pred.check(0.075, -0.0)


# ------------------------------------------------------------------ force clamp and rate


def test_force_clamp_at_and_around_the_limit() -> None:
    clamp = ForceClamp(ForceConfig(max_force_N=10_000.0))
    for value in (0.0, 9_999.999, 10_000.0, -10_000.0):
        assert clamp.apply(value) == value and not clamp.acted
    assert clamp.apply(10_000.001) == 10_000.0 and clamp.acted
    assert clamp.apply(-1e9) == -10_000.0 and clamp.acted
    assert ForceClamp.ACTION is Action.CLAMP


def test_force_rate_limit_at_and_around_the_step() -> None:
    rate = ForceRateLimit(ForceConfig(max_force_rate_N_per_s=100_000.0))
    dt = 0.01  # step 1000 N
    assert rate.apply(1000.0, 0.0, dt) == 1000.0 and not rate.acted
    assert rate.apply(-1000.0, 0.0, dt) == -1000.0 and not rate.acted
    assert rate.apply(1000.1, 0.0, dt) == pytest.approx(1000.0) and rate.acted
    assert rate.apply(-5000.0, 200.0, dt) == pytest.approx(-800.0) and rate.acted
    assert ForceRateLimit.ACTION is Action.CLAMP


# ------------------------------------------------------------------ configuration


def test_default_config_is_consistent_and_fits_the_rig() -> None:
    config = SafetyConfig()
    assert check_config(config) == []
    weight_N = (1148.62 + 3 * 958.0) * 9.81
    assert 0.14 * weight_N < config.force.max_force_N < 0.5 * weight_N
    assert config.stroke.soft_limit_m < config.stroke.hard_limit_m


def _with(**groups: object) -> SafetyConfig:
    return dataclasses.replace(SafetyConfig(), **groups)


@pytest.mark.parametrize(
    ("config", "fragment"),
    [
        (_with(stroke=StrokeConfig(soft_limit_m=0.08, hard_limit_m=0.075)), "soft_limit_m"),
        (_with(stroke=StrokeConfig(soft_limit_m=0.075, hard_limit_m=0.075)), "soft_limit_m"),
        (_with(stroke=StrokeConfig(fade_band_m=0.03)), "wider than the soft-to-hard gap"),
        (_with(stroke=StrokeConfig(arm_tolerance_m=0.05)), "arm_tolerance_m"),
        (_with(stroke=StrokeConfig(hard_limit_m=-0.1)), "hard_limit_m is -0.1"),
        (_with(force=ForceConfig(max_force_N=0.0)), "max_force_N is 0"),
        (_with(force=ForceConfig(max_force_rate_N_per_s=float("nan"))), "finite"),
        (_with(force=ForceConfig(max_force_rate_N_per_s=1000.0)), "stopping_ramp_s"),
        (_with(force=ForceConfig(tracking_tolerance_N=20_000.0)), "tracking_tolerance_N"),
        (_with(stroke=StrokeConfig(fade_band_m=0.03)), "(0.03 m) is wider than the soft-to-hard gap (0.025 m)"),
        (_with(sensors=SensorConfig(displacement_range_m=0.075)), "sensors.displacement_range_m (0.075 m) does not exceed"),
        (_with(trip_actions=TripActionsConfig(stroke=("disable", "disable"))), "expected each action once"),
        (_with(actuator=ActuatorConfig(max_status_age_s=0.0)), "actuator.max_status_age_s is 0, expected > 0"),
        (_with(force=ForceConfig(max_force_N=-1.0)), "force.max_force_N is -1, expected > 0"),
    ],
)
def test_check_config_finds_each_problem(config: SafetyConfig, fragment: str) -> None:
    problems = check_config(config)
    assert any(fragment in p for p in problems), problems


@pytest.mark.parametrize(("group", "field"), [
    ("stroke", "stop_time_s"), ("force", "actuator_time_constant_s"), ("comms", "max_e2e_rejects"),
    ("comms", "max_error_frames"), ("comms", "max_send_failures"),
])
def test_the_fields_that_may_be_zero_are_accepted_at_zero_and_refused_below(group: str, field: str) -> None:
    def at(value: float) -> SafetyConfig:
        config = SafetyConfig()
        return dataclasses.replace(config, **{group: dataclasses.replace(getattr(config, group), **{field: value})})

    # (a zero look-ahead fails the stall budget, a different check)
    assert not [p for p in check_config(at(0)) if p.startswith(f"{group}.{field} is")]
    assert check_config(at(-1)) == [f"{group}.{field} is -1, expected >= 0"]


def test_fade_band_equal_to_the_gap_is_allowed() -> None:
    assert check_config(_with(stroke=StrokeConfig(soft_limit_m=0.05, fade_band_m=0.025, hard_limit_m=0.075))) == []


def test_schema_builds_the_safety_section_with_units_and_refuses_unknown_keys() -> None:
    data = {"stroke": {"soft_limit_m": "4 cm", "hard_limit_m": 0.07}, "force": {"max_force_N": "8 kN"}}
    config = build(SafetyConfig, data)
    assert config.stroke.soft_limit_m == pytest.approx(0.04)
    assert config.force.max_force_N == pytest.approx(8000.0)
    with pytest.raises(ProfileError, match="stroke_limit"):
        build(SafetyConfig, {"stroke": {"stroke_limit": 0.1}})
    with pytest.raises(ProfileError):
        build(SafetyConfig, {"stroke": {"hard_limit_m": "3 kg"}})


def test_supervisor_refuses_an_inconsistent_config() -> None:
    from harness.safety.supervisor import Supervisor

    with pytest.raises(ProfileError, match="soft_limit_m"):
        Supervisor(_with(stroke=StrokeConfig(soft_limit_m=0.1, hard_limit_m=0.075)))


# ------------------------------------------------------------------ stall budget (docs/SAFETY.md, "Stall budget")

#: The shipped profile's look-ahead: stop_time_s 50 ms less a 10 ms actuator lag covers 40 ms of blind time.
LOOK_AHEAD = dataclasses.replace(
    SafetyConfig(),
    stroke=StrokeConfig(stop_time_s=0.05),
    force=ForceConfig(actuator_time_constant_s=0.01),
)


def _blind(max_stall_s: float, max_sensor_age_s: float, actuator_time_constant_s: float = 0.01) -> SafetyConfig:
    """LOOK_AHEAD with a stall budget, a sensor age and an actuator lag."""
    return dataclasses.replace(
        LOOK_AHEAD,
        run=dataclasses.replace(LOOK_AHEAD.run, max_stall_s=max_stall_s),
        sensors=dataclasses.replace(LOOK_AHEAD.sensors, max_sensor_age_s=max_sensor_age_s),
        force=dataclasses.replace(LOOK_AHEAD.force, actuator_time_constant_s=actuator_time_constant_s),
    )


def test_stall_budget_exactly_on_the_boundary_is_accepted() -> None:
    # 20 ms stall + 20 ms sensor age = 40 ms blind = 50 ms look-ahead - 10 ms lag: the shipped profile's numbers
    assert check_config(_blind(0.02, 0.02)) == []
    assert check_config(_blind(0.039, 0.001)) == []
    assert check_config(_blind(0.001, 0.039)) == []


@pytest.mark.parametrize(
    ("stall_s", "age_s", "lag_s"),
    [
        (0.02, 0.0201, 0.01),  # the sensor age alone pushes it over: a sum without the age passes
        (0.0201, 0.02, 0.01),  # the stall alone pushes it over
        (0.001, 0.04, 0.01),  # a small stall budget cannot hide a sensor age that fills the look-ahead
        (0.02, 0.02, 0.0101),  # the actuator lag eats into the look-ahead
    ],
)
def test_stall_budget_beyond_the_look_ahead_is_refused(stall_s: float, age_s: float, lag_s: float) -> None:
    problems = check_config(_blind(stall_s, age_s, lag_s))
    assert len(problems) == 1, problems
    assert "run.max_stall_s" in problems[0] and "sensors.max_sensor_age_s" in problems[0]
    assert f"= {(stall_s + age_s) * 1e3:.1f} ms of blind time" in problems[0]


def test_the_shipped_profile_sits_on_the_stall_budget_boundary_and_passes() -> None:
    from harness.profile import load_profile

    safety = load_profile(None).safety
    blind_s = safety.run.max_stall_s + safety.sensors.max_sensor_age_s
    cover_s = safety.stroke.stop_time_s - safety.force.actuator_time_constant_s
    assert blind_s == pytest.approx(cover_s, abs=1e-12)
    assert check_config(safety) == []
