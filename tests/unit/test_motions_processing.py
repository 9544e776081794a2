"""Processing: exact triple, baseline, scaling, time compression, padding, interpolation, summary."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.errors import RecordError
from harness.motions import (
    G_M_S2,
    RawRecord,
    integrate_from_rest,
    load_record,
    process_record,
    rule_residuals,
    summarize,
    synthetic_record,
)

DATA_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "ground_motions"
needs_data = pytest.mark.skipif(
    not DATA_DIR.is_dir(), reason=f"real ground motions not found at {DATA_DIR.resolve()} (shared data set absent)"
)
REAL = ["elcentro_1940_NS.csv", "elcentro_1940_NS_classic.csv", "hachinohe_1968_NS.csv", "pacoima_1971_S16E.csv"]


@pytest.fixture(scope="module")
def synthetic() -> RawRecord:
    return synthetic_record(seed=3, duration_s=20.0)


def _relative_residuals(motion) -> tuple[float, float]:
    rv, rx = rule_residuals(motion.accel_m_s2, motion.velocity_m_s, motion.displacement_m, motion.dt_s)
    return float(np.max(np.abs(rv)) / motion.pgv_m_s), float(np.max(np.abs(rx)) / motion.pgd_m)


def _assert_exact_triple(motion) -> None:
    rel_v, rel_x = _relative_residuals(motion)
    assert rel_v < 1e-12 and rel_x < 1e-12
    assert motion.displacement_m[0] == 0.0 and motion.velocity_m_s[0] == 0.0


# --- the rule itself -----------------------------------------------------------------------


def test_integration_rule_is_exact_for_a_linear_acceleration():
    dt, slope, a0 = 0.01, 3.0, -1.5
    t = np.arange(101) * dt
    v, x = integrate_from_rest(a0 + slope * t, dt)
    np.testing.assert_allclose(v, a0 * t + slope * t**2 / 2, atol=1e-13)
    np.testing.assert_allclose(x, a0 * t**2 / 2 + slope * t**3 / 6, atol=1e-13)


def test_rule_residuals_detect_an_inconsistent_triple(synthetic):
    motion = process_record(synthetic)
    bumped = np.array(motion.displacement_m)
    bumped[500] += 1e-6
    _, rx = rule_residuals(motion.accel_m_s2, motion.velocity_m_s, bumped, motion.dt_s)
    assert np.max(np.abs(rx)) > 0.5e-6


def test_state_at_samples_and_inside_intervals_follows_the_rule(synthetic):
    motion = process_record(synthetic)
    x, v, a = motion.state_at(motion.t_s)
    np.testing.assert_allclose(a, motion.accel_m_s2, atol=1e-12)
    np.testing.assert_allclose(x, motion.displacement_m, atol=1e-12)
    k, dt = 700, motion.dt_s
    a_k, a_k1 = motion.accel_m_s2[k], motion.accel_m_s2[k + 1]
    tau = 0.3 * dt
    xs, vs, accs = motion.state_at(motion.t_s[k] + tau)
    assert accs == pytest.approx(a_k + (a_k1 - a_k) * tau / dt, rel=1e-12)
    assert vs == pytest.approx(motion.velocity_m_s[k] + a_k * tau + (a_k1 - a_k) * tau**2 / (2 * dt), rel=1e-12)
    expected_x = motion.displacement_m[k] + motion.velocity_m_s[k] * tau + a_k * tau**2 / 2 + (a_k1 - a_k) * tau**3 / (6 * dt)
    assert xs == pytest.approx(expected_x, rel=1e-12)


def test_state_at_outside_the_record_holds_the_end_states(synthetic):
    motion = process_record(synthetic)
    x, v, a = motion.state_at(np.array([-1.0, motion.duration_s + 5.0]))
    assert x[0] == 0.0 and v[0] == 0.0 and a[0] == motion.accel_m_s2[0]
    assert x[1] == motion.displacement_m[-1] and a[1] == motion.accel_m_s2[-1]


def test_scalar_sample_agrees_with_the_vectorized_state(synthetic):
    motion = process_record(synthetic)
    times = np.r_[-0.5, 0.0, np.random.default_rng(0).uniform(0.0, motion.duration_s, 200), motion.duration_s, 99.0]
    xs, vs, accs = motion.state_at(times)
    for t, x, v, a in zip(times, xs, vs, accs, strict=True):
        assert motion.sample(float(t)) == pytest.approx((x, v, a), rel=1e-12, abs=1e-15)
    assert isinstance(motion.sample(1.0)[0], float)


def test_arrays_are_read_only(synthetic):
    motion = process_record(synthetic)
    with pytest.raises(ValueError):
        motion.displacement_m[3] = 1.0


# --- real records ---------------------------------------------------------------------------


@needs_data
@pytest.mark.parametrize("filename", REAL)
@pytest.mark.parametrize(("time_scale", "pga_g"), [(1.0, 0.3), (2.0, 0.34)])
def test_real_records_give_an_exact_triple_at_rest_at_both_ends(filename, time_scale, pga_g):
    motion = process_record(load_record(DATA_DIR / filename), pga_g=pga_g, time_scale=time_scale, duration_s=30.0)
    _assert_exact_triple(motion)
    assert motion.pga_g == pytest.approx(pga_g, rel=1e-9)
    assert abs(motion.displacement_m[-1]) < 1e-3 * motion.pgd_m
    assert abs(motion.velocity_m_s[-1]) < 1e-9
    assert motion.accel_m_s2[0] == 0.0 and motion.accel_m_s2[-1] == 0.0


@needs_data
def test_el_centro_at_0_3_g_does_not_drift():
    raw = load_record(DATA_DIR / "elcentro_1940_NS.csv")
    motion = process_record(raw, pga_g=0.3, duration_s=30.0)
    assert abs(motion.displacement_m[-1]) < 1e-3
    # the 40 s record cut to 30 s: its last seconds move as the whole corrected record does there
    whole = process_record(raw, pga_g=0.3)
    late = slice(int(0.9 * motion.n_samples), None)
    assert np.max(np.abs(motion.displacement_m[late])) <= 1.01 * np.max(np.abs(whole.displacement_m[: motion.n_samples][late]))
    assert motion.pgd_m < 0.2


@needs_data
def test_uncorrected_classic_trace_drifts_raw_but_not_processed():
    raw = load_record(DATA_DIR / "elcentro_1940_NS_classic.csv")
    _, x_raw = integrate_from_rest(raw.accel_m_s2, raw.dt_s)
    motion = process_record(raw)
    assert abs(x_raw[-1]) > 0.5
    assert motion.pgd_m < 0.3
    assert abs(motion.displacement_m[-1]) < 1e-6


@needs_data
def test_time_compression_of_el_centro():
    raw = load_record(DATA_DIR / "elcentro_1940_NS.csv")
    base = process_record(raw, pga_g=0.3)
    fast = process_record(raw, pga_g=0.3, time_scale=2.0)
    assert fast.dt_s == pytest.approx(base.dt_s / 2, rel=1e-12)
    assert fast.duration_s == pytest.approx(base.duration_s / 2, rel=1e-12)
    assert 0.15 < fast.pgd_m / base.pgd_m < 0.4
    assert 0.35 < fast.pgv_m_s / base.pgv_m_s < 0.65


@needs_data
@pytest.mark.parametrize(
    ("filename", "t5", "t95", "pgv_cm_s"),
    [
        ("elcentro_1940_NS.csv", 1.99, 26.09, 29.7),
        ("pacoima_1971_S16E.csv", 2.74, 9.76, 114.4),
        ("hachinohe_1968_NS.csv", 16.50, 44.90, 34.4),
    ],
)
def test_summary_matches_the_readme_figures(filename, t5, t95, pgv_cm_s):
    summary = summarize(process_record(load_record(DATA_DIR / filename)))
    assert summary.t5_s == pytest.approx(t5, abs=0.05)
    assert summary.t95_s == pytest.approx(t95, abs=0.05)
    assert summary.significant_duration_s == pytest.approx(t95 - t5, abs=0.1)
    assert summary.pgv_m_s * 100 == pytest.approx(pgv_cm_s, rel=0.1)


@needs_data
def test_hachinohe_long_period_content_is_found():
    summary = summarize(process_record(load_record(DATA_DIR / "hachinohe_1968_NS.csv")))
    assert 2.3 < summary.predominant_period_s < 3.0


# --- options and notes -------------------------------------------------------------------------


def test_short_record_is_zero_padded_with_a_note(synthetic):
    motion = process_record(synthetic, duration_s=30.0)
    assert motion.duration_s == pytest.approx(30.0)
    assert any("zero-padded" in note for note in motion.notes)
    padded = motion.accel_m_s2[motion.t_s > 20.5]
    assert 0.0 < np.max(np.abs(padded)) < 0.01 * motion.pga_g * G_M_S2  # only the slow baseline correction
    _assert_exact_triple(motion)


def test_cut_to_duration_in_compressed_time(synthetic):
    motion = process_record(synthetic, time_scale=2.0, duration_s=5.0)
    assert motion.dt_s == pytest.approx(0.005)
    assert motion.n_samples == 1001
    assert not any("zero-padded" in note for note in motion.notes)


def test_optional_highpass_keeps_the_triple_exact_and_is_stated(synthetic):
    motion = process_record(synthetic, highpass_hz=0.1, pga_g=0.2)
    _assert_exact_triple(motion)
    assert motion.highpass_hz == 0.1
    assert any("0.1 Hz" in note and "high-pass" in note for note in motion.notes)
    assert motion.pga_g == pytest.approx(0.2, rel=1e-9)


def test_without_taper_the_start_step_is_noted():
    raw = RawRecord("step", 0.01, np.r_[np.full(50, 0.5), np.zeros(50)], "test")
    motion = process_record(raw, taper_fraction=0.0)
    assert any("no taper" in note for note in motion.notes)
    _assert_exact_triple(motion)


def test_without_target_the_record_pga_is_kept(synthetic):
    assert process_record(synthetic).pga_g == pytest.approx(synthetic.pga_g, rel=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"pga_g": 0.0}, "pga_g > 0"),
        ({"pga_g": float("nan")}, "pga_g > 0"),
        ({"time_scale": -2.0}, "time_scale > 0"),
        ({"duration_s": 0.01}, "duration_s >="),
        ({"highpass_hz": 60.0}, "highpass_hz"),
        ({"taper_fraction": 0.6}, "taper_fraction"),
        ({"baseline_corner_hz": 0.0}, "baseline_corner_hz"),
        ({"highpass_hz": 0.1, "highpass_order": 0}, "highpass_order"),
    ],
)
def test_bad_options_are_refused(synthetic, kwargs, message):
    with pytest.raises(RecordError, match=message):
        process_record(synthetic, **kwargs)


def test_record_with_motion_only_under_the_taper_is_refused():
    values = np.zeros(20)
    values[0] = 1.0
    with pytest.raises(RecordError, match="no motion is left"):
        process_record(RawRecord("edge", 0.01, values, "test"), taper_fraction=0.2)


def test_all_zero_record_is_refused():
    with pytest.raises(RecordError, match="only zeros"):
        process_record(RawRecord("quiet", 0.01, np.zeros(100), "test"))


# --- invariants (hypothesis) --------------------------------------------------------------------

_SETTINGS = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])


@_SETTINGS
@given(seed=st.integers(0, 2**31), pga=st.floats(0.01, 2.0), duration=st.floats(3.0, 12.0))
def test_scaling_is_exact_and_keeps_the_triple(seed, pga, duration):
    raw = synthetic_record(seed=seed, duration_s=duration, pga_g=0.5)
    motion = process_record(raw, pga_g=pga)
    assert abs(motion.pga_g - pga) <= 1e-9 * pga
    _assert_exact_triple(motion)


@_SETTINGS
@given(seed=st.integers(0, 1000), pga_a=st.floats(0.05, 1.5), pga_b=st.floats(0.05, 1.5))
def test_scaling_is_linear_in_all_three(seed, pga_a, pga_b):
    raw = synthetic_record(seed=seed, duration_s=6.0)
    a, b = process_record(raw, pga_g=pga_a), process_record(raw, pga_g=pga_b)
    ratio = pga_b / pga_a
    np.testing.assert_allclose(b.accel_m_s2, a.accel_m_s2 * ratio, rtol=1e-9, atol=1e-12 * pga_b * G_M_S2)
    np.testing.assert_allclose(b.displacement_m, a.displacement_m * ratio, rtol=1e-9, atol=1e-12 * b.pgd_m)


@_SETTINGS
@given(seed=st.integers(0, 1000), factor=st.floats(0.5, 4.0))
def test_time_compression_scales_velocity_by_1_over_f_and_displacement_by_1_over_f_squared(seed, factor):
    raw = synthetic_record(seed=seed, duration_s=8.0)
    corner = 0.1
    base = process_record(raw, pga_g=0.3, baseline_corner_hz=corner)
    fast = process_record(raw, pga_g=0.3, time_scale=factor, baseline_corner_hz=corner * factor)
    assert fast.dt_s == pytest.approx(base.dt_s / factor, rel=1e-12)
    assert fast.duration_s == pytest.approx(base.duration_s / factor, rel=1e-12)
    np.testing.assert_allclose(fast.accel_m_s2, base.accel_m_s2, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(fast.velocity_m_s * factor, base.velocity_m_s, rtol=1e-9, atol=1e-12 * base.pgv_m_s)
    np.testing.assert_allclose(fast.displacement_m * factor**2, base.displacement_m, rtol=1e-9, atol=1e-12 * base.pgd_m)
    assert fast.pgd_m == pytest.approx(base.pgd_m / factor**2, rel=1e-9)


@_SETTINGS
@given(
    accel=st.lists(st.floats(-20.0, 20.0, allow_nan=False), min_size=10, max_size=400),
    dt=st.sampled_from([0.001, 0.005, 0.01, 0.02]),
    factor=st.floats(0.5, 4.0),
    taper=st.sampled_from([0.0, 0.01, 0.2]),
)
def test_any_record_gives_an_exact_triple_that_ends_at_rest(accel, dt, factor, taper):
    values = np.array(accel)
    values[values.size // 2] += 1.0  # some motion outside the tapers
    motion = process_record(RawRecord("any", dt, values, "hypothesis"), pga_g=0.5, time_scale=factor, taper_fraction=taper)
    _assert_exact_triple(motion)
    assert abs(motion.displacement_m[-1]) <= 1e-6 * motion.pgd_m
    assert abs(motion.velocity_m_s[-1]) <= 1e-6 * motion.pgv_m_s
    assert motion.pga_g == pytest.approx(0.5, rel=1e-9)
