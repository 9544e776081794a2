"""The ``seize`` fault of the plant (``rig.faults`` kind ``seize``, id 150): the virtual rig's bearings stop the sliding."""

from __future__ import annotations

import uuid

import numpy as np
import pytest

from harness.canbus.config import CanConfig
from harness.canbus.link import open_rig
from harness.errors import ModelError
from harness.profile import load_profile
from harness.rig.faults import fault_id_for
from harness.rig.table import TablePlant
from harness.rig.virtual_rig import RigParts, VirtualRig
from harness.runs.options import prepare_motion

PERIOD_S = 0.002


def _sliding_velocity(table: TablePlant) -> float:
    _, table_velocity = table.live.table_now(table.time_s)
    return float(table.y[table._i_vb] - table_velocity)


def test_the_virtual_rig_seizes_its_bearings_while_the_fault_is_on_and_frees_them_after():
    profile = load_profile(overrides=["record.duration_s=4"])
    link = open_rig(CanConfig(channel=f"seize-{uuid.uuid4().hex[:10]}"))
    try:
        rig = VirtualRig(RigParts.from_profile(profile), prepare_motion(profile), link, step_period_s=PERIOD_S, lockstep=True)
        rig.table.start()
        sliding = []
        for k in range(1500):  # 3 s of record, the fault on from 1 s to 2 s
            if k == 500:
                assert rig.faults.inject(fault_id_for("seize"), 0.0)
            if k == 1000:
                assert rig.faults.inject(0, 0.0)  # cleared
            rig.step_lockstep(0.0, False, k * PERIOD_S)
            sliding.append(_sliding_velocity(rig.table))
        sliding = np.abs(np.array(sliding))
        assert sliding[:500].max() > 1e-3  # the base mat slides on the record before the seize
        assert sliding[501:1000].max() < 1e-9  # seized: it moves with the table, at once
        assert sliding[1000:].max() > 1e-3 and not rig.table.seized  # freed, it slides again
        assert rig.table.seized_at_velocity_m_s == pytest.approx(sliding[499], abs=0.05)
    finally:
        link.close()


def test_a_plant_without_the_rigs_coupled_parameters_cannot_seize():
    profile = load_profile(variant="force_source", overrides=["record.duration_s=2"])
    parts = RigParts.from_profile(profile)
    table = TablePlant(parts.building, parts.bearing, prepare_motion(profile), parts.rtol, profile.rig)
    assert not table.can_seize
    table.set_seized(False)  # no change: nothing to refuse
    with pytest.raises(ModelError, match="coupled plant"):
        table.set_seized(True)
