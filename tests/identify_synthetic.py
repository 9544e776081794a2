"""Synthetic runs with known answers for the identification tests.

The project's own plant (:class:`harness.model.plant.Plant`) with chosen structure and bearing,
driven by a table motion and by an actuator force that damps the base mat's absolute motion (as
the phi controller's ``m_b p1`` does), sampled at the loop's rate and measured as the rig measures
it: the noise and quantization of the profile's ``rig.sensors``, the story sensors (drifts, floor
accelerations) read at half the loop's rate and held, as their CAN messages arrive, and the load
cell's noise (``rig.actuator.force_noise_N``). :func:`write_run` writes the result as a run folder
whose ``profile.yaml`` is the design, so an identification starts from the design and must find
the plant's values.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.model.plant import Plant, TableMotion
from harness.motions.config import RecordConfig
from harness.motions.loading import load_motion
from harness.profile import Profile
from harness.recording import write_simulation_case
from harness.signals import columns as layout

#: The base mat's absolute velocity damped as the phi controller does: m_b p1 = 1148.62 kg x 8 1/s (N s/m).
DAMPER_NS_PER_M = 9200.0


def table_motion(record: str, pga_g: float | None, duration_s: float, time_scale: float = 2.0) -> TableMotion:
    """A processed record as the plant's table motion (``synthetic:SEED`` or ``white_noise:...``)."""
    motion = load_motion(RecordConfig(name=record, pga_g=pga_g, time_scale=time_scale, duration_s=duration_s), base_dir=".")
    return TableMotion.from_motion(motion)


def simulate(building: BuildingConfig, bearing: BearingConfig, table: TableMotion, rate_hz: float = 500.0,
             damper_Ns_per_m: float = DAMPER_NS_PER_M) -> dict[str, np.ndarray]:
    """The plant's true columns (:func:`harness.rowlayout.plant_columns`) and the actuator's force, at ``rate_hz``."""
    plant = Plant(building, bearing, table)
    plant.reset()
    n = int(round(table.duration_s * rate_hz)) + 1
    times = np.arange(n) / rate_hz
    states = np.empty((n, plant.y.size))
    forces = np.zeros(n)
    velocity = plant.model.i_base_velocity
    for k in range(n):
        states[k] = plant.y
        forces[k] = -damper_Ns_per_m * plant.y[velocity]  # sampled, then held over the period (zero-order hold)
        if k + 1 < n:
            plant.advance(times[k], times[k + 1], forces[k])
    columns = plant.responses(times, states, forces)
    columns[layout.FORCE_MEASURED] = forces
    return columns


def measured(true: dict[str, np.ndarray], profile: Profile, seed: int = 1) -> dict[str, np.ndarray]:
    """What the rig's sensors report of ``true``: noise, quantization, the story sensors at half rate, the load cell's noise."""
    rng = np.random.default_rng(seed)
    sensors = profile.rig.sensors
    groups = {
        "m": sensors.displacement.as_tuple(), "m_s": sensors.velocity.as_tuple(), "m_s2": sensors.acceleration.as_tuple(),
    }
    read = dict(true)
    sensed = (*layout.TABLE, layout.BASE_DISPLACEMENT, layout.BASE_VELOCITY, layout.BASE_ACCELERATION,
              *layout.story_columns(3))
    for name in sensed:
        unit = "m_s2" if name.endswith("_m_s2") else "m_s" if name.endswith("_m_s") else "m"
        std, bias, step, _delay = groups[unit]
        value = true[name] + bias + std * rng.standard_normal(len(true[name]))
        read[name] = step * np.round(value / step) if step > 0 else value
    for name in layout.story_columns(3):  # STORY_DRIFTS and FLOOR_ACCELS arrive every other tick
        held = read[name]
        held[1::2] = held[0:-1:2][: len(held[1::2])]
    read[layout.SLIDING_DISPLACEMENT] = read[layout.BASE_DISPLACEMENT] - read[layout.TABLE_DISPLACEMENT]
    read[layout.SLIDING_VELOCITY] = read[layout.BASE_VELOCITY] - read[layout.TABLE_VELOCITY]
    force = true[layout.FORCE_MEASURED] + profile.rig.actuator.force_noise_N * rng.standard_normal(len(true[layout.TIME]))
    read[layout.FORCE_MEASURED] = force
    return read


def write_run(folder: Path, name: str, columns: dict[str, np.ndarray], design: Profile,
              leave_out: tuple[str, ...] = ()) -> Path:
    """Write ``columns`` (less ``leave_out``) as the run folder ``folder/name`` whose profile is ``design``."""
    names = [column for column in columns if column not in leave_out and column not in layout.BEARING]
    return write_simulation_case(folder, name, names, {column: columns[column] for column in names},
                                 {"profile_name": design.name, "controller": "damper"},
                                 profile_data=design.resolved_data())
