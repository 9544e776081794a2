"""Force-tracking compensation (harness/control/compensation.py, model_compensation.py) and compensation_fault.

The model-based compensator on a known plant: the first-order actuator model (C1),
``udot = w_f (u_c - u) - k_h xdot_b``, stepped exactly with the command held over each
period. Without compensation a constant sliding velocity leaves a force deficit of
``(k_h / w_f) xdot_b``; the flow term cancels it, the load-cell correction takes out a model
error within its bound and pins at it beyond. The supervisor's ``compensation_fault`` check
trips on a pinned or non-finite compensator; the loop's tick and the rig twin run the
compensator between the controller and the supervisor, so the clamp bounds the compensated
command.
"""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

from drivers.measurements import Measurements
from harness.control.actuator_aware import ActuatorModel
from harness.control.adaptive_compensation import AdaptiveCompensator, solve_normalized
from harness.control.compensation import NoCompensation
from harness.control.config import AdaptiveCompensationConfig, ModelCompensationConfig
from harness.control.factory import build_controller_for_rig, make_compensator
from harness.control.model_compensation import ModelCompensator
from harness.errors import ModelError, ProfileError
from harness.profile import load_profile
from harness.runs.options import StudyOptions, prepare_motion
from harness.runs.simulate import run_study
from harness.safety.actuator_detectors import CompensationFault
from harness.safety.config import ForceConfig
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.simulation.twin import run_rig_twin
from tests.unit.test_control_tick import PERIOD_S, Bench

#: The shipped rig's actuator (profiles/nceer_4dof.yaml): k_h = 11.8 MN/m, w_f = 2 pi 20 Hz.
ACTUATOR = ActuatorModel(11.8e6, 2.0 * math.pi * 20.0)
#: A servo controller without velocity feed-forward (SPEC 7a'), what harness-side compensation is for:
#: the shipped profile's feed-forward leaves the flow term nothing to add.
PLAIN_LOOP = ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0"]
DT = 0.002


class FirstOrderActuator:
    """The known plant (C1), stepped exactly over ``dt`` with the command and the velocity held."""

    def __init__(self, model: ActuatorModel) -> None:
        self.model = model
        self.force_N = 0.0

    def step(self, command_N: float, sliding_velocity_m_s: float, dt: float) -> float:
        decay = math.exp(-self.model.bandwidth_rad_s * dt)
        target = command_N - self.model.loop_damping_Ns_per_m * sliding_velocity_m_s
        self.force_N = decay * self.force_N + (1.0 - decay) * target
        return self.force_N


def _run(compensator, plant: FirstOrderActuator, force_N, velocity_m_s: float, seconds: float):
    """Drive ``plant`` through ``compensator`` for ``seconds``; (reference-free) forces per tick."""
    meas = Measurements()
    meas.set(0.0, 0.0, 0.0, velocity_m_s)  # table at rest, the base mat sliding at velocity_m_s
    applied = 0.0
    forces, targets = [], []
    for k in range(int(round(seconds / DT))):
        t = k * DT
        meas.actuator_force_N = plant.force_N
        target = force_N(t) if callable(force_N) else force_N
        applied = compensator.update(t, DT, target, meas, applied)
        plant.step(applied, velocity_m_s, DT)
        forces.append(plant.force_N)
        targets.append(target)
    return np.array(forces), np.array(targets)


def test_the_model_compensator_cancels_a_constant_velocity_force_bleed() -> None:
    velocity, wanted = 0.1, 2_000.0
    bleed = ACTUATOR.loop_damping_Ns_per_m * velocity  # 9.4 kN at 0.1 m/s
    uncompensated, _ = _run(NoCompensation(), FirstOrderActuator(ACTUATOR), wanted, velocity, 0.5)
    assert uncompensated[-1] == pytest.approx(wanted - bleed, rel=1e-6)  # the deficit without compensation
    compensated, _ = _run(ModelCompensator(ACTUATOR, ModelCompensationConfig()), FirstOrderActuator(ACTUATOR),
                          wanted, velocity, 0.5)
    assert abs(compensated[-1] - wanted) < 1.0
    assert abs(compensated[-1] - wanted) < 1e-3 * bleed


def test_the_flow_term_alone_cancels_the_bleed_without_the_load_cell() -> None:
    settings = ModelCompensationConfig(correction_rate_per_s=0.0)
    compensated, _ = _run(ModelCompensator(ACTUATOR, settings), FirstOrderActuator(ACTUATOR), 2_000.0, -0.12, 0.5)
    assert abs(compensated[-1] - 2_000.0) < 1.0


def test_the_inverse_dynamics_make_the_force_follow_the_reference_not_the_actuators_lag() -> None:
    settings = ModelCompensationConfig(correction_rate_per_s=0.0)
    step = lambda t: 0.0 if t < 0.01 else 3_000.0  # noqa: E731
    compensator = ModelCompensator(ACTUATOR, settings)
    compensated, _ = _run(compensator, FirstOrderActuator(ACTUATOR), step, 0.0, 0.1)
    uncompensated, _ = _run(NoCompensation(), FirstOrderActuator(ACTUATOR), step, 0.0, 0.1)
    # the reference: the step through the 4 ms lag of (C2), sampled as the compensator steps it
    times = np.arange(compensated.size) * DT
    reference = np.where(times < 0.01, 0.0, 3_000.0 * (1.0 - np.exp(-(times - 0.01 + DT) / settings.reference_time_constant_s)))
    k = int(round(0.018 / DT))  # 1 / w_f = 8 ms after the step
    assert compensated[k] > 0.85 * 3_000.0  # the compensated force is nearly there after one actuator lag
    assert uncompensated[k] < 0.75 * 3_000.0  # the bare actuator is still on its way (1 - 1/e of it)
    # within a sample's hold of the reference; the bare actuator lags it by a fifth of the step and more
    assert np.max(np.abs(compensated - reference)) < 0.06 * 3_000.0 < 0.2 * 3_000.0 < np.max(np.abs(uncompensated - reference))


def test_the_correction_takes_out_a_model_error_within_its_bound() -> None:
    plant = FirstOrderActuator(ACTUATOR.scaled(stiffness=1.08))  # the rig's k_h is 8 % above the model's
    compensator = ModelCompensator(ACTUATOR, ModelCompensationConfig())
    forces, _ = _run(compensator, plant, 2_000.0, 0.1, 2.0)
    missing = 0.08 * ACTUATOR.loop_damping_Ns_per_m * 0.1  # 750 N the flow term leaves
    assert abs(forces[-1] - 2_000.0) < 5.0
    assert compensator.correction_N == pytest.approx(missing, rel=0.01)
    assert not compensator.pinned


def test_a_model_error_beyond_the_bound_pins_the_correction_at_it() -> None:
    plant = FirstOrderActuator(ACTUATOR.scaled(stiffness=1.2))  # 1.9 kN missing, the bound is 1 kN
    compensator = ModelCompensator(ACTUATOR, ModelCompensationConfig())
    forces, _ = _run(compensator, plant, 2_000.0, 0.1, 2.0)
    assert compensator.correction_N == 1_000.0
    assert compensator.pinned and compensator.bound_value == 1_000.0
    assert forces[-1] == pytest.approx(2_000.0 - (0.2 * ACTUATOR.loop_damping_Ns_per_m * 0.1 - 1_000.0), rel=1e-3)


def test_the_correction_does_not_wind_up_while_the_supervisor_changes_the_command() -> None:
    compensator = ModelCompensator(ACTUATOR, ModelCompensationConfig())
    meas = Measurements()
    meas.actuator_force_N = 0.0  # the actuator gives nothing: a large error
    compensator.update(0.0, DT, 5_000.0, meas, 0.0)
    for k in range(1, 200):  # the supervisor sends less than asked (a clamp, a ramp) on every tick
        compensator.update(k * DT, DT, 5_000.0, meas, compensator.command_N - 100.0)
    assert compensator.correction_N == 0.0
    compensator.update(200 * DT, DT, 5_000.0, meas, compensator.command_N)  # sent as computed: it integrates
    assert compensator.correction_N > 0.0


def test_a_non_finite_force_gives_a_non_finite_command_and_keeps_the_state() -> None:
    compensator = ModelCompensator(ACTUATOR, ModelCompensationConfig())
    meas = Measurements()
    compensator.update(0.0, DT, 1_000.0, meas, 0.0)
    reference = compensator.reference_N
    assert math.isnan(compensator.update(DT, DT, math.nan, meas, 0.0))
    assert compensator.reference_N == reference and not compensator.diverged


def test_a_correction_gain_above_a_quarter_of_the_bandwidth_is_refused() -> None:
    with pytest.raises(ModelError, match="w_f / 4"):
        ModelCompensator(ACTUATOR, ModelCompensationConfig(correction_rate_per_s=40.0))


# ---------------------------------------------------------------- the profile key
def test_the_profile_key_builds_each_method_and_none_is_the_default() -> None:
    assert isinstance(make_compensator(load_profile(None)), NoCompensation)
    compensator = make_compensator(load_profile(None, overrides=["control.compensation=model",
                                                                  "rig.actuator.hydraulics.feedforward.gain=0"]))
    assert isinstance(compensator, ModelCompensator)
    assert compensator.actuator.loop_damping_Ns_per_m == pytest.approx(94_000.0, rel=0.01)  # rig.actuator's plain loop
    # The servo controller's feed-forward (the shipped profile's, alpha = 1) leaves the flow term nothing to add.
    shipped = make_compensator(load_profile(None, overrides=["control.compensation=model"]))
    assert isinstance(shipped, ModelCompensator)
    assert shipped.actuator.loop_damping_Ns_per_m == 0.0
    with pytest.raises(ProfileError, match="control.compensation"):
        load_profile(None, overrides=["control.compensation=magic"])


def test_a_correction_bound_not_below_the_tracking_tolerance_is_refused() -> None:
    profile = load_profile(None, overrides=["control.compensation=model", "control.compensator.model.correction_limit_N=1500"])
    with pytest.raises(ProfileError, match="tracking_tolerance_N"):
        make_compensator(profile)


def test_the_ideal_simulation_has_no_actuator_to_compensate() -> None:
    profile = load_profile(None, overrides=["record.duration_s=2", "control.compensation=model"])
    ideal = run_study(profile, StudyOptions())
    assert ideal.to_json()["sampling"]["compensation"] == "none" and "force_tracking_rms_N" not in ideal.to_json()
    with_rig = run_study(profile, StudyOptions(rig_effects=True)).to_json()
    assert with_rig["sampling"]["compensation"] == "model" and with_rig["force_tracking_rms_N"]["controller_force"] > 0.0


# ---------------------------------------------------------------- compensation_fault
def test_compensation_fault_at_and_around_tracking_time() -> None:
    detector = CompensationFault(ForceConfig(tracking_time_s=0.1))
    health = TickHealth()
    health.compensation_pinned, health.compensation_value = True, 1_000.0
    fired = [detector.update(k * DT, DT, health) for k in range(52)]
    assert not any(fired[:50]) and fired[50]  # 0.1 s after the first pinned tick, not before
    health.compensation_pinned = False
    assert not detector.update(52 * DT, DT, health)
    health.compensation_pinned = True  # pinned again: the time starts afresh
    assert not any(detector.update(k * DT, DT, health) for k in range(53, 103))
    assert detector.update(103 * DT, DT, health)
    assert "1000" in detector.detail(health) and detector.present(health) == ""


def test_compensation_fault_trips_at_once_on_a_state_not_finite() -> None:
    detector = CompensationFault(ForceConfig())
    health = TickHealth()
    assert not detector.update(0.0, DT, health)
    health.compensation_diverged, health.compensation_value = True, math.inf
    assert detector.update(DT, DT, health)
    assert "not finite" in detector.present(health)  # a reset is refused while it lasts


class _Pinning:
    """A compensator that passes the force through and reports a parameter pinned from ``pin_at`` on."""

    name = "test"

    def __init__(self, pin_at_s: float) -> None:
        self.pin_at_s = pin_at_s
        self.command_N, self.pinned, self.diverged, self.bound_value = 0.0, False, False, 0.0

    def reset(self) -> None:
        self.pinned = False

    def update(self, t, dt, force_N, meas, applied_N):
        self.pinned = t >= self.pin_at_s
        self.bound_value = 7.0 if self.pinned else 0.0
        self.command_N = force_N
        return force_N


@pytest.fixture
def bench():
    benches: list[Bench] = []

    def make() -> Bench:
        b = Bench()
        benches.append(b)
        return b

    yield make
    for b in benches:
        b.close()


def test_the_tick_hands_the_compensators_flags_to_the_supervisor(bench) -> None:
    b = bench()
    b.tick.compensator = _Pinning(pin_at_s=math.inf)
    b.run_until_running()
    b.tick.compensator.pin_at_s = b.t
    pinned_from = b.t
    while True:
        command, sent = b.step()
        if command.state is State.TRIPPED:
            break
        assert sent[0] and b.t - pinned_from < 0.1 + 2 * PERIOD_S
    assert command.trip_reason == "compensation_fault" and sent == (False, 0.0)
    assert b.t - pinned_from == pytest.approx(0.1 + PERIOD_S, abs=1e-9)  # tracking_time_s after the first pinned tick


def test_the_supervisor_clamps_the_setpoint_and_lets_the_flow_term_through_within_its_bound(bench) -> None:
    """The controller's 9 kN is inside max_force_N; the flow term (2.8 kN at 0.03 m/s) is inside max_flow_term_N,
    so the command goes out whole, above max_force_N (the clamp on the command cut it to 10 kN: issue 31)."""
    b = bench()
    profile = load_profile(None, overrides=[*PLAIN_LOOP, "control.compensation=model"])
    b.tick.compensator = make_compensator(profile)
    b.controller.force_N = 9_000.0
    b.run_until_running()
    b.v_b = 0.03
    for _ in range(60):
        b.x_b += b.v_b * PERIOD_S
        command, sent = b.step()
    force = profile.safety.force
    assert force.max_force_N < b.tick.compensator.command_N < force.max_force_N + force.max_flow_term_N
    assert command.state is State.RUNNING, b.tick.supervisor.trip_detail
    assert command.force_N == pytest.approx(b.tick.compensator.command_N, abs=force.max_force_rate_N_per_s * PERIOD_S)
    assert command.force_N > force.max_force_N and sent[0]


def test_a_compensator_on_the_wrong_actuator_model_trips_compensation_fault_and_force_tracking_stays_quiet() -> None:
    profile = load_profile(None, overrides=[*PLAIN_LOOP, "record.duration_s=10"])
    motion = prepare_motion(profile)
    wrong = ActuatorModel.from_rig_actuator(profile.rig.actuator).scaled(stiffness=0.5)  # half the rig's k_h
    compensator = ModelCompensator(wrong, profile.control.compensator.model)
    result = run_rig_twin(profile, motion, profile.control.rate_hz, build_controller_for_rig(profile, "phi"),
                          compensator=compensator)
    assert result.extra["outcome"] == "tripped" and result.extra["trip_reason"] == "compensation_fault"
    # the same run with the rig's own model completes: the trip is the model's error, not the record's
    right = make_compensator(load_profile(None, overrides=[*PLAIN_LOOP, "record.duration_s=10", "control.compensation=model"]))
    healthy = run_rig_twin(profile, motion, profile.control.rate_hz, build_controller_for_rig(profile, "phi"), compensator=right)
    assert healthy.extra["outcome"] == "completed" and healthy.extra["compensation"] == "model"


# ---------------------------------------------------------------- the adaptive compensator
def _excite(compensator, plant: FirstOrderActuator, seconds: float, period_s: float = DT, feedforward_lag_s: float | None = None):
    """Drive ``plant`` through ``compensator`` with a force of two sines and a sliding velocity of a third.

    ``feedforward_lag_s``: a servo controller's velocity feed-forward cancels the plant's bleed with
    the velocity delayed by that much (None: no feed-forward), so what it leaves is
    ``c (xdot_b(t) - xdot_b(t - lag))``. Returns the coefficients after each tick (n, 4) and the
    force error against the reference (n,).
    """
    meas = Measurements()
    applied = 0.0
    history, errors = [], []
    for k in range(int(round(seconds / period_s))):
        t = k * period_s
        velocity = 0.08 * math.sin(2.0 * math.pi * 1.3 * t)
        meas.set(0.0, 0.0, 0.0, velocity)
        meas.actuator_force_N = plant.force_N
        errors.append(plant.force_N - compensator.reference_N)
        wanted = 2_000.0 * math.sin(2.0 * math.pi * 0.7 * t) + 800.0 * math.sin(2.0 * math.pi * 4.1 * t)
        applied = compensator.update(t, period_s, wanted, meas, applied)
        bleeding = velocity
        if feedforward_lag_s is not None:
            bleeding -= 0.08 * math.sin(2.0 * math.pi * 1.3 * (t - feedforward_lag_s))
        plant.step(applied, bleeding, period_s)
        history.append(tuple(compensator.coefficients))
    return np.array(history), np.array(errors)


def _bounds(settings: AdaptiveCompensationConfig) -> tuple[tuple[float, ...], tuple[float, ...]]:
    pairs = (settings.gain_bounds, settings.lead_bounds_s, settings.flow_bounds_Ns_per_m, settings.acceleration_bounds_kg)
    return tuple(pair[0] for pair in pairs), tuple(pair[1] for pair in pairs)


def test_the_adaptive_compensator_converges_to_the_inverse_of_a_known_plant_within_its_bounds() -> None:
    settings = AdaptiveCompensationConfig()
    compensator = AdaptiveCompensator(settings, DT)
    history, errors = _excite(compensator, FirstOrderActuator(ACTUATOR), 6.0)
    a0, a1, a2, a3 = history[-1]
    assert a0 == pytest.approx(1.0, abs=0.03)  # the continuous relation fitted to a plant held over 2 ms samples
    assert a1 == pytest.approx(1.0 / ACTUATOR.bandwidth_rad_s, rel=0.15)  # 8 ms, and half a sample's hold
    assert a2 == pytest.approx(ACTUATOR.loop_damping_Ns_per_m, rel=0.03)  # 94 kN s/m
    # no feed-forward, so no lag to make up for: only the period between the velocity and the load cell it drove, -c T
    assert a3 == pytest.approx(-ACTUATOR.loop_damping_Ns_per_m * DT, rel=0.15)  # -188 kg
    low, high = _bounds(settings)
    assert np.all(history >= low) and np.all(history <= high)  # at every tick, not only at the end
    assert not compensator.pinned and not compensator.diverged and compensator.fits > 0
    first, last = errors[: int(0.5 / DT)], errors[-int(1.0 / DT):]
    rms = lambda x: float(np.sqrt(np.mean(np.square(x))))  # noqa: E731
    assert rms(last) < 0.1 * rms(first)  # from the bare actuator's error (it starts as none) to a tenth of it


def test_a_lagging_feedforward_is_fitted_as_the_sliding_accelerations_term() -> None:
    lag_s = 0.006  # a feed-forward velocity 6 ms old: it leaves c (v - v(t - 6 ms)) ~ c 6 ms xddot_b
    compensator = AdaptiveCompensator(AdaptiveCompensationConfig(), DT)
    history, errors = _excite(compensator, FirstOrderActuator(ACTUATOR), 6.0, feedforward_lag_s=lag_s)
    a0, a1, a2, a3 = history[-1]
    assert a3 == pytest.approx(ACTUATOR.loop_damping_Ns_per_m * lag_s, rel=0.15)  # 564 kg
    assert a2 < 0.02 * ACTUATOR.loop_damping_Ns_per_m  # the feed-forward took the flow term
    assert a0 == pytest.approx(1.0, abs=0.03) and not compensator.pinned
    rms = lambda x: float(np.sqrt(np.mean(np.square(x))))  # noqa: E731
    assert rms(errors[-int(1.0 / DT):]) < 0.1 * rms(errors[: int(0.5 / DT)])


def test_the_adaptive_compensator_starts_as_none_and_learns_nothing_at_rest() -> None:
    compensator = AdaptiveCompensator(AdaptiveCompensationConfig(), DT)
    meas = Measurements()
    for k in range(1000):
        assert compensator.update(k * DT, DT, 0.0, meas, 0.0) == 0.0
    assert tuple(compensator.coefficients) == (1.0, 0.0, 0.0, 0.0) and compensator.fits == 0
    assert compensator.update(1000 * DT, DT, 500.0, meas, 0.0) == pytest.approx(compensator.reference_N)


def test_nothing_is_learnt_while_the_base_mat_slides_slower_than_a_stuck_bearing_can_creep() -> None:
    """(C8): below ``v_learn`` no sample enters the window; above it they do."""
    plant = FirstOrderActuator(ACTUATOR)
    creeping = AdaptiveCompensator(AdaptiveCompensationConfig(), DT, learn_above_m_s=0.1)  # above the 0.08 m/s peak
    _excite(creeping, plant, 2.0)
    assert creeping._count == 0 and creeping.fits == 0
    assert tuple(creeping.coefficients) == (1.0, 0.0, 0.0, 0.0)
    sliding = AdaptiveCompensator(AdaptiveCompensationConfig(), DT, learn_above_m_s=0.04)  # half the peak: some samples
    _excite(sliding, FirstOrderActuator(ACTUATOR), 2.0)
    assert 0 < sliding._count < int(2.0 / DT) and sliding.fits > 0
    with pytest.raises(ModelError, match=">= 0 m/s"):
        AdaptiveCompensator(AdaptiveCompensationConfig(), DT, learn_above_m_s=-1.0)


def test_the_factory_learns_above_the_creep_of_the_profiles_bearing() -> None:
    profile = load_profile(None, overrides=["control.compensation=adaptive"])
    compensator = make_compensator(profile)
    expected = profile.bearing.yield_displacement_m / profile.control.compensator.adaptive.filter_time_constant_s
    assert compensator._learn_above == pytest.approx(expected) and expected == pytest.approx(0.00254)


def test_an_actuator_outside_the_stated_bounds_pins_the_adaptation_at_them() -> None:
    settings = AdaptiveCompensationConfig(flow_bounds_Ns_per_m=(0.0, 50_000.0))  # the plant's 94 kN s/m is outside
    compensator = AdaptiveCompensator(settings, DT)
    history, _ = _excite(compensator, FirstOrderActuator(ACTUATOR), 4.0)
    assert compensator.pinned and history[-1, 2] == 50_000.0
    assert compensator.bound_value > 50_000.0  # the fit that was refused
    assert compensator.clip_N > 1_000.0  # 44 kN s/m on a velocity of 57 mm/s RMS
    assert np.all(history[:, 2] <= 50_000.0)


def test_a_clip_the_load_cell_cannot_see_is_not_a_pin() -> None:
    """(C7): a bound 1 N s/m below the fitted flow gain clips every fit by about 0.06 N RMS: held, not pinned."""
    free = AdaptiveCompensator(AdaptiveCompensationConfig(), DT)
    _excite(free, FirstOrderActuator(ACTUATOR), 4.0)
    settings = AdaptiveCompensationConfig(flow_bounds_Ns_per_m=(0.0, free.coefficients[2] - 1.0))
    compensator = AdaptiveCompensator(settings, DT)
    history, _ = _excite(compensator, FirstOrderActuator(ACTUATOR), 4.0)
    assert history[-1, 2] == settings.flow_bounds_Ns_per_m[1]  # clipped
    assert 0.0 < compensator.clip_N < settings.clip_tolerance_N and not compensator.pinned
    tight = AdaptiveCompensator(AdaptiveCompensationConfig(flow_bounds_Ns_per_m=settings.flow_bounds_Ns_per_m,
                                                           clip_tolerance_N=0.01), DT)
    _excite(tight, FirstOrderActuator(ACTUATOR), 4.0)
    assert tight.pinned  # the same clip against a tolerance below it


def test_the_windows_running_sums_are_the_sums_of_the_samples_it_holds() -> None:
    compensator = AdaptiveCompensator(AdaptiveCompensationConfig(window_s=0.2), DT)  # 100 samples: wraps 15 times
    _excite(compensator, FirstOrderActuator(ACTUATOR), 3.0)
    ring = compensator._ring
    p, y = ring[:, :4], ring[:, 4]
    normal, right = p.T @ p, p.T @ y
    assert np.allclose(compensator._normal, normal, rtol=1e-9, atol=1e-9 * np.max(np.abs(normal)))
    assert np.allclose(compensator._right, right, rtol=1e-9, atol=1e-9 * np.max(np.abs(right)))


def test_solve_normalized_agrees_with_a_direct_solve_and_refuses_collinear_regressors() -> None:
    rng = np.random.default_rng(3)
    p = rng.normal(size=(200, 4)) * (1e3, 1e5, 0.1, 2.0)
    p[:, 3] += 10.0 * p[:, 2]  # correlated, as velocity and acceleration are, yet well excited
    y = p @ (1.0, 0.008, 94_000.0, 600.0) + rng.normal(size=200)
    normal, right = p.T @ p, p.T @ y
    work, solution = [[0.0] * 6 for _ in range(4)], [0.0] * 4  # lists, as the tick has them (rows are swapped)
    assert solve_normalized(normal, right, 1e-3, work, solution)
    assert np.allclose(solution, np.linalg.solve(normal, right), rtol=1e-9)
    scale = np.sqrt(np.diag(normal))
    determinant = np.linalg.det(normal / np.outer(scale, scale))
    assert not solve_normalized(normal, right, determinant * 1.001, work, solution)  # the threshold is the determinant
    assert solve_normalized(normal, right, determinant * 0.999, work, solution)
    mixed = np.random.default_rng(1)  # a system whose elimination swaps rows (partial pivoting)
    q = mixed.normal(size=(50, 4)) @ mixed.normal(size=(4, 4))
    q_right = q.T @ mixed.normal(size=50)
    rows = [[0.0] * 6 for _ in range(4)]
    order = [id(row) for row in rows]
    assert solve_normalized(q.T @ q, q_right, 1e-12, rows, solution)
    assert [id(row) for row in rows] != order  # the swap happened
    assert np.allclose(solution, np.linalg.solve(q.T @ q, q_right), rtol=1e-8)
    p[:, 2] = p[:, 0] * 1e-4  # the velocity a copy of the force: nothing tells a0 from a2
    normal, right = p.T @ p, p.T @ y
    before = list(solution)
    assert not solve_normalized(normal, right, 1e-3, work, solution)
    assert solution == before  # untouched when refused


def test_the_adaptive_compensators_bounds_are_checked() -> None:
    with pytest.raises(ValueError, match="low < high"):
        AdaptiveCompensationConfig(lead_bounds_s=(0.02, 0.0))
    with pytest.raises(ValueError, match="hold 1"):
        AdaptiveCompensationConfig(gain_bounds=(1.1, 1.5))
    assert isinstance(make_compensator(load_profile(None, overrides=["control.compensation=adaptive"])), AdaptiveCompensator)


def test_the_adaptive_compensator_allocates_nothing_per_tick() -> None:
    compensator = AdaptiveCompensator(AdaptiveCompensationConfig(), DT)
    plant = FirstOrderActuator(ACTUATOR)
    _excite(compensator, plant, 1.5)  # the window is more than half full: every tick fits
    meas = Measurements()

    def ticks(first: int, count: int) -> None:
        for k in range(first, first + count):
            meas.base_velocity_m_s = 0.05 * math.sin(k * 0.01)
            meas.actuator_force_N = plant.force_N
            plant.step(compensator.update(k * DT, DT, 1_000.0 * math.sin(k * 0.02), meas, compensator.command_N), 0.0, DT)

    tracemalloc.start()
    try:
        ticks(0, 100)  # the floats the sums and the scratch hold are now ones traced: a fixed count, not growth
        before = tracemalloc.get_traced_memory()[0]
        ticks(100, 2000)
        growth = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert growth < 1024  # 2000 ticks: half a byte each would show


def test_a_rig_outside_the_adaptive_bounds_trips_compensation_fault_on_the_twin() -> None:
    overrides = [*PLAIN_LOOP, "record.duration_s=10", "control.compensation=adaptive", "control.compensator.adaptive.start=none",
                 "control.compensator.adaptive.flow_bounds_Ns_per_m=[0, 50000]"]  # the rig's k_h / w_f is 94 kN s/m
    profile = load_profile(None, overrides=overrides)
    result = run_rig_twin(profile, prepare_motion(profile), profile.control.rate_hz, build_controller_for_rig(profile, "phi"))
    assert result.extra["outcome"] == "tripped" and result.extra["trip_reason"] == "compensation_fault"
    healthy = load_profile(None, overrides=overrides[:4])
    result = run_rig_twin(healthy, prepare_motion(healthy), healthy.control.rate_hz, build_controller_for_rig(healthy, "phi"))
    assert result.extra["outcome"] == "completed" and result.extra["compensation"] == "adaptive"


def test_the_adaptive_compensator_starts_from_the_actuator_model_or_from_none() -> None:
    from_model = make_compensator(load_profile(None, overrides=[*PLAIN_LOOP, "control.compensation=adaptive"]))
    assert isinstance(from_model, AdaptiveCompensator)
    assert tuple(from_model.coefficients) == pytest.approx((1.0, 1.0 / ACTUATOR.bandwidth_rad_s, 94_000.0, 0.0), rel=0.01)
    from_none = make_compensator(load_profile(None, overrides=["control.compensation=adaptive",
                                                               "control.compensator.adaptive.start=none"]))
    assert tuple(from_none.coefficients) == (1.0, 0.0, 0.0, 0.0)
    outside = [*PLAIN_LOOP, "control.compensation=adaptive", "control.compensator.adaptive.flow_bounds_Ns_per_m=[0, 50000]"]
    with pytest.raises(ProfileError, match="outside its bounds"):
        make_compensator(load_profile(None, overrides=outside))


def test_an_actuator_aware_design_refuses_a_compensation_on_top_of_its_own_inverse() -> None:
    profile = load_profile(None, overrides=["control.compensation=model", "control.controller=phi-A"])
    with pytest.raises(ProfileError, match="already carries the inverse"):
        make_compensator(profile, controller="phi-A")
    with pytest.raises(ProfileError, match="already carries the inverse"):
        run_study(load_profile(None, overrides=["control.compensation=adaptive", "record.duration_s=2"]),
                  StudyOptions(controller="phi-A", rig_effects=True))
    assert isinstance(make_compensator(profile, controller="phi"), ModelCompensator)
    assert isinstance(make_compensator(profile, "none", controller="phi-A"), NoCompensation)
