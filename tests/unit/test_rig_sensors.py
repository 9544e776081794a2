"""The rig's sensor model: noise statistics, bias, quantization, delay rounding, seeding."""

from __future__ import annotations

import numpy as np
import pytest

from harness.rig.config import (
    AccelerationSensorConfig,
    DisplacementSensorConfig,
    SensorsConfig,
    VelocitySensorConfig,
)
from harness.rig.sensors import MESSAGE_COLUMNS, SIGNALS, SensorModel

H = 0.0005


def _model(config: SensorsConfig, seed: int = 3) -> SensorModel:
    model = SensorModel(config, H, 0.1, np.random.default_rng(seed))
    model.reset(np.zeros(len(SIGNALS)))
    model.set_delays(0.0, None)
    return model


def _truth(value: float) -> np.ndarray:
    return np.full(len(SIGNALS), value)


def test_noise_mean_and_std_match_the_configuration():
    config = SensorsConfig(displacement=DisplacementSensorConfig(noise_std_m=2e-5, bias_m=1e-4))
    model = _model(config)
    model.push(_truth(0.01))
    out = [0.0, 0.0, 0.0]
    samples = []
    for _ in range(20_000):
        model.read(MESSAGE_COLUMNS[0], out)  # x_0 (displacement), xdot_0, xddot_0
        samples.append(out[0])
        assert out[1] == 0.01 and out[2] == 0.01, "velocity and acceleration groups have no noise here"
    samples = np.array(samples)
    # standard error of the mean: 2e-5 / sqrt(2e4) = 1.4e-7; of the std: about 0.5 %
    assert samples.mean() == pytest.approx(0.01 + 1e-4, abs=1e-6)
    assert samples.std() == pytest.approx(2e-5, rel=0.03)


def test_quantization_rounds_to_the_step():
    config = SensorsConfig(velocity=VelocitySensorConfig(quantization_m_s=1e-3))
    model = _model(config)
    out = [0.0, 0.0, 0.0]
    for value in (0.01234, -0.0456, 0.00049, 0.00051):
        model.push(_truth(value))
        model.read(MESSAGE_COLUMNS[1], out)  # y_b, ydot_b, yddot_b
        assert out[1] == pytest.approx(round(value / 1e-3) * 1e-3, abs=1e-12)
        assert out[0] == value, "displacement is not quantized here"


def test_quantized_noisy_values_lie_on_the_grid():
    config = SensorsConfig(acceleration=AccelerationSensorConfig(noise_std_m_s2=0.05, quantization_m_s2=0.01))
    model = _model(config)
    model.push(_truth(0.3))
    out = [0.0, 0.0, 0.0]
    values = set()
    for _ in range(200):
        model.read(MESSAGE_COLUMNS[3], out)
        for v in out:
            assert abs(v / 0.01 - round(v / 0.01)) < 1e-9
            values.add(round(v, 6))
    assert len(values) > 5, "noise must change the readings"


def test_delay_in_real_time_is_whole_substeps():
    config = SensorsConfig(displacement=DisplacementSensorConfig(delay_s=0.0021))  # 4.2 sub-steps -> 4
    model = _model(config)
    model.set_delays(0.0, None)
    out = [0.0, 0.0, 0.0]
    for k in range(1, 20):
        model.push(_truth(float(k)))
        model.read(MESSAGE_COLUMNS[0], out)
        assert out[0] == float(max(k - 4, 0)), "x_0 delayed by 4 sub-steps"
        assert out[1] == float(k), "velocity has no delay"


def test_delay_in_lockstep_is_whole_steps_and_extra_delay_adds():
    config = SensorsConfig(displacement=DisplacementSensorConfig(delay_s=0.0015))  # 0.75 step of 2 ms -> 1 step
    model = _model(config)
    model.set_delays(0.0, 4)
    assert model.delay_substeps[0] == 4
    model.set_delays(0.004, 4)  # 2.75 steps -> 3
    assert model.delay_substeps[0] == 12
    assert model.delay_substeps[1] == 8, "velocity: 2 ms extra = 2 steps"


def test_same_seed_same_noise_other_seed_other_noise():
    config = SensorsConfig(displacement=DisplacementSensorConfig(noise_std_m=1e-5))

    def readings(seed: int) -> list[float]:
        model = _model(config, seed)
        model.push(_truth(0.0))
        out = [0.0, 0.0, 0.0]
        result = []
        for _ in range(5000):  # more than one noise block
            model.read(MESSAGE_COLUMNS[2], out)
            result.extend(out)
        return result

    assert readings(7) == readings(7)
    assert readings(7) != readings(8)


def test_half_a_step_rounds_up_not_to_even():
    config = SensorsConfig(displacement=DisplacementSensorConfig(delay_s=0.001), velocity=VelocitySensorConfig(delay_s=0.003))
    model = _model(config)
    model.set_delays(0.0, 4)  # 2 ms steps: 0.5 step -> 1 step, 1.5 steps -> 2 steps
    assert model.delay_substeps[0] == 4 and model.delay_substeps[1] == 8
