"""ControlTick's row: every value lands in the column harness.signals.columns names for it."""

from __future__ import annotations

import uuid

import pytest

from harness.canbus.config import CanConfig
from harness.canbus.link import open_harness, open_rig
from harness.control.estimator import FrictionEstimator
from harness.loop.tick import ControlTick
from harness.profile import load_profile
from harness.safety.supervisor import Supervisor
from harness.signals import columns as layout

PERIOD_S = 0.002
# Sensor values on the DBC's grids (1 um, 10 um/s, 2 um drifts, 0.002 m/s^2 floor accelerations).
TABLE = (0.012, 0.25, 1.5)
BASE = (0.015, 0.31, -2.25)
DRIFTS = (0.002, -0.004, 0.006)
ACCELS = (1.002, -2.004, 3.006)


class KnownController:
    """A controller whose visible internals are known values."""

    sliding_variable = 0.125
    equivalent_force_N = -375.0

    def update(self, t, dt, meas, friction, state):
        return 1_250.0


@pytest.fixture
def ticked():
    """A ControlTick after one tick on a bus that carried the values above."""
    profile = load_profile(None)
    can = CanConfig(interface="virtual", channel=f"row-{uuid.uuid4().hex[:8]}")
    rig, link = open_rig(can), open_harness(can)
    estimator = FrictionEstimator(profile.bearing, profile.structure.total_weight_N)
    tick = ControlTick(link, KnownController(), estimator, Supervisor(profile.safety, period_s=PERIOD_S), None)
    t = 0.5
    rig.writer.table(*TABLE, t)
    rig.writer.base(*BASE, t)
    rig.writer.drifts(*DRIFTS, t)
    rig.writer.accels(*ACCELS, t)
    tick.run(t, PERIOD_S, t, lateness_s=3e-5, missed_periods=2)
    yield tick
    link.close()
    rig.close()


def column(tick: ControlTick, name: str) -> float:
    return float(tick.row[layout.CONTROL_ROW_INDEX[name]])


def test_the_row_has_one_cell_per_layout_column(ticked):
    assert ticked.row.shape == (len(layout.CONTROL_ROW),)


def test_measured_signals_land_in_their_named_columns(ticked):
    names = (*layout.TABLE, *layout.BASE, *layout.story_columns(layout.PROTOCOL_STORIES))
    for name, sent in zip(names, (*TABLE, *BASE, *DRIFTS, *ACCELS), strict=True):
        assert column(ticked, name) == pytest.approx(sent, abs=1e-9), name
    assert column(ticked, layout.SLIDING_DISPLACEMENT) == pytest.approx(BASE[0] - TABLE[0], abs=1e-9)
    assert column(ticked, layout.SLIDING_VELOCITY) == pytest.approx(BASE[1] - TABLE[1], abs=1e-9)


def test_loop_values_land_in_their_named_columns(ticked):
    assert column(ticked, layout.TIME) == 0.5
    assert column(ticked, layout.STATE) == int(ticked.supervisor.state)
    assert column(ticked, layout.ESTIMATED_NU) == ticked.estimator.nu
    assert column(ticked, layout.SLIDING_VARIABLE) == KnownController.sliding_variable
    assert column(ticked, layout.EQUIVALENT_FORCE) == KnownController.equivalent_force_N
    assert column(ticked, layout.FORCE_RAW) == 1_250.0
    assert column(ticked, layout.FORCE_COMMAND) == ticked.command.force_N
    assert column(ticked, layout.LATENESS) == 3e-5
    assert column(ticked, layout.OVERRUN) == 2
    assert 0.0 < column(ticked, layout.COMPUTE) < 1.0
