"""The white-noise record kind (``--record white_noise:LOW-HIGH[:PGA]``): its name, its band, its amplitude."""

from __future__ import annotations

import numpy as np
import pytest

from harness.errors import RecordError
from harness.motions import G_M_S2, RecordConfig, load_motion, resolve_record
from harness.motions.loading import load_raw_and_motion
from harness.motions.white_noise_name import DEFAULT_PGA_G, WhiteNoiseSpec, white_noise_spec


def _band_share(motion, low_hz: float, high_hz: float) -> float:
    """Share of the acceleration's energy between ``low_hz`` and ``high_hz``."""
    power = np.abs(np.fft.rfft(motion.accel_m_s2)) ** 2
    freq = np.fft.rfftfreq(len(motion.accel_m_s2), motion.dt_s)
    return float(power[(freq >= low_hz) & (freq <= high_hz)].sum() / power.sum())


def test_the_name_gives_band_and_amplitude():
    assert white_noise_spec("white_noise:0.5-20") == WhiteNoiseSpec(0.5, 20.0, DEFAULT_PGA_G)
    assert white_noise_spec(" white_noise:1-12.5:0.08g ") == WhiteNoiseSpec(1.0, 12.5, 0.08)
    assert white_noise_spec("white_noise:1-12.5:0.08") == WhiteNoiseSpec(1.0, 12.5, 0.08)
    assert white_noise_spec("synthetic:3") is None and white_noise_spec("el_centro") is None
    assert white_noise_spec(WhiteNoiseSpec(0.5, 20.0, 0.1).name) == WhiteNoiseSpec(0.5, 20.0, 0.1)


@pytest.mark.parametrize("name, expected", [
    ("white_noise", "LOW-HIGH"),
    ("white_noise:", "LOW-HIGH"),
    ("white_noise:20", "LOW-HIGH"),
    ("white_noise:20-0.5", "0 < LOW < HIGH"),
    ("white_noise:0-20", "0 < LOW < HIGH"),
    ("white_noise:0.5-80", "<= 50 Hz"),
    ("white_noise:a-20", "expected a number"),
    ("white_noise:0.5-nan", "finite"),
    ("white_noise:0.5-20:0", "(0, 10]"),
    ("white_noise:0.5-20:0.1:3", "LOW-HIGH"),
])
def test_a_malformed_name_is_refused_saying_the_format(name, expected):
    with pytest.raises(RecordError, match="white_noise") as err:
        white_noise_spec(name)
    assert expected in str(err.value)


def test_the_profile_refuses_a_malformed_white_noise_name():
    with pytest.raises(ValueError, match="LOW-HIGH"):
        RecordConfig(name="white_noise:20")


def test_it_plays_its_band_at_its_amplitude_whatever_the_time_scale(tmp_path):
    for time_scale in (1.0, 2.0):
        config = RecordConfig(name="white_noise:0.5-20:0.08", time_scale=time_scale, duration_s=40.0)
        motion = load_motion(config, base_dir=tmp_path)
        assert motion.duration_s == pytest.approx(40.0)
        assert motion.pga_g == pytest.approx(0.08, rel=1e-9)
        assert _band_share(motion, 0.5, 20.0) > 0.99  # compression put the band back where the name says
        assert _band_share(motion, 0.5, 10.0) < 0.9  # and the top half of it is there too
        assert motion.accel_m_s2[0] == 0.0 and abs(motion.displacement_m[-1]) < 1e-6  # from rest to rest


def test_the_profile_pga_does_not_apply_and_a_note_says_so(tmp_path):
    raw, motion = load_raw_and_motion(RecordConfig(name="white_noise:0.5-20", pga_g=0.34, duration_s=20.0), base_dir=tmp_path)
    assert motion.pga_g == pytest.approx(DEFAULT_PGA_G)
    assert any("does not apply to white noise" in note and "white_noise:0.5-20:0.34" in note for note in motion.notes)
    assert np.max(np.abs(raw.accel_m_s2)) == pytest.approx(DEFAULT_PGA_G * G_M_S2)


def test_the_seed_gives_the_motion(tmp_path):
    def motion(seed: int):
        return load_motion(RecordConfig(name="white_noise:1-10", seed=seed, duration_s=10.0), base_dir=tmp_path).accel_m_s2

    assert np.array_equal(motion(1), motion(1))
    assert not np.allclose(motion(1), motion(2))


def test_it_is_generated_not_looked_up():
    with pytest.raises(RecordError, match="generated"):
        resolve_record("white_noise:0.5-20", None)
