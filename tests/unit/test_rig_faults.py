"""Fault ids, the fault set (run-time and scheduled), the drive state machine, the rig config section."""

from __future__ import annotations

import pytest

from drivers.protocol.protocol_values import DriveState, FaultCode
from harness.config.schema import build
from harness.errors import ProfileError
from harness.rig import faults as F
from harness.rig.config import FaultSpec, RigConfig
from harness.rig.drive import Drive
from harness.rig.faults import (
    FaultError,
    FaultSet,
    decode_fault_id,
    fault_id_for,
    schedule_from,
)


def test_fault_ids_follow_the_documented_table():
    assert fault_id_for("dropout", "TABLE_SENSORS") == 10
    assert fault_id_for("dropout", "ACTUATOR_STATUS") == 14
    assert fault_id_for("stuck", "BASE_SENSORS") == 21
    assert fault_id_for("spike", "FLOOR_ACCELS") == 33
    assert fault_id_for("corrupt_crc", "RIG_STATUS") == 55
    assert fault_id_for("bus_silence") == 90
    assert fault_id_for("estop") == 120
    assert decode_fault_id(71) == (F.SKIP_COUNTER, 1)
    assert decode_fault_id(110) == (F.PRESSURE_LOST, 0)


def test_every_row_of_the_docstring_table_decodes_to_its_kind():
    rows = [line.split() for line in (F.__doc__ or "").splitlines() if line[:2].isdigit() and line[2:3] in ("+", " ", "0")]
    assert len(rows) == len(F.KINDS) - 1
    for row in rows:
        base, kind = row[0], row[1]
        if base.endswith("+t"):
            first, last = (int(v) for v in row[2].split("-"))
            for target in range(first, last + 1):
                assert decode_fault_id(int(base[:-2]) + target) == (F.KINDS.index(kind), target)
            with pytest.raises(FaultError):
                decode_fault_id(int(base[:-2]) + last + 1)
        else:
            assert decode_fault_id(int(base)) == (F.KINDS.index(kind), 0)


@pytest.mark.parametrize("bad", [1, 9, 24, 34, 56, 81, 134, 144, 151, 255])  # 130-133: sign_flip, 140-143: polarity; 150: seize
def test_unknown_fault_ids_are_refused(bad):
    with pytest.raises(FaultError, match=f"unknown fault id {bad}"):
        decode_fault_id(bad)


def test_sign_flip_names_one_signal_of_a_sensor_message():
    assert fault_id_for("sign_flip", "BASE_SENSORS") == 131
    with pytest.raises(FaultError):
        fault_id_for("sign_flip", "ACTUATOR_STATUS")
    faults = FaultSet()
    assert not faults.inject(131, 3.0) and not faults.inject(131, 0.5) and faults.unknown_ids == 2
    assert faults.inject(131, 1.0)
    faults.update(None)
    assert faults.flipped_signal(1) == 1 and faults.flipped_signal(0) == -1
    with pytest.raises(FaultError, match="0, 1 or 2"):
        schedule_from([FaultSpec(kind="sign_flip", target="BASE_SENSORS", param=5.0)])


def test_runtime_injection_and_clear():
    faults = FaultSet()
    assert faults.inject(fault_id_for("dropout", "BASE_SENSORS"), 0.0)
    assert faults.inject(80, 0.25)
    assert not faults.inject(99, 0.0) and faults.unknown_ids == 1
    faults.update(None)
    assert faults.is_on(F.DROPOUT, 1) and not faults.is_on(F.DROPOUT, 0)
    assert faults.extra_delay_s == 0.25
    assert set(faults.active_ids()) == {11, 80}
    faults.inject(0, 0.0)
    faults.update(None)
    assert not faults.any_active and faults.extra_delay_s == 0.0


def test_schedule_uses_record_time_and_spike_fires_once():
    specs = (
        FaultSpec(kind="stuck", target="TABLE_SENSORS", start_s=1.0, duration_s=0.5),
        FaultSpec(kind="spike", target="BASE_SENSORS", start_s=2.0, duration_s=0.1, param=0.004),
        FaultSpec(kind="pressure_lost", start_s=3.0),
    )
    faults = FaultSet(schedule_from(specs))
    faults.update(None)
    assert not faults.any_active, "nothing before the table starts"
    faults.update(1.2)
    assert faults.is_on(F.STUCK, 0)
    faults.update(1.6)
    assert not faults.is_on(F.STUCK, 0)
    faults.update(2.0)
    assert faults.take_spike(1) == 0.004 and faults.take_spike(1) == 0.0
    faults.update(2.05)
    assert faults.take_spike(1) == 0.0, "a spike is one sample"
    faults.update(100.0)
    assert faults.is_on(F.PRESSURE_LOST), "duration 0 lasts until reset"


def test_fault_spec_in_a_profile_is_checked():
    config = build(RigConfig, {"faults": [{"kind": "corrupt_crc", "target": "ACTUATOR_STATUS", "start_s": "2 s"}]})
    assert config.faults[0].start_s == 2.0
    with pytest.raises(ProfileError, match="needs a target"):
        build(RigConfig, {"faults": [{"kind": "stuck"}]})
    with pytest.raises(ProfileError, match="takes no target"):
        build(RigConfig, {"faults": [{"kind": "bus_silence", "target": "RIG_STATUS"}]})
    with pytest.raises(ProfileError, match="unknown key"):
        build(RigConfig, {"actuator": {"tau_s": 0.01}})
    with pytest.raises(ProfileError, match="expected one of"):
        build(RigConfig, {"actuator": {"model": "third_order"}})


def test_drive_goes_ready_enabled_and_back():
    drive = Drive(0.05)
    assert drive.update(0.0, True) == DriveState.OFF, "no heartbeat yet"
    drive.on_heartbeat(0.0)
    assert drive.update(0.01, True) == DriveState.READY
    drive.on_command(True, 100.0, 0.02)
    assert drive.state == DriveState.ENABLED and drive.enabled
    drive.on_command(False, 0.0, 0.03)
    assert drive.state == DriveState.READY


def test_drive_watchdog_trips_when_commands_stop_and_latches():
    drive = Drive(0.05)
    drive.on_heartbeat(0.0)
    drive.update(0.0, True)
    drive.on_command(True, 10.0, 0.0)
    for k in range(1, 10):  # heartbeats keep coming, commands stopped at t = 0
        drive.on_heartbeat(0.01 * k)
        assert drive.update(0.01 * k, True) == (DriveState.ENABLED if 0.01 * k <= 0.05 else DriveState.FAULT)
    assert drive.fault_code == FaultCode.COMMAND_WATCHDOG
    drive.on_heartbeat(1.0)
    drive.on_command(True, 10.0, 1.0)
    assert drive.update(1.0, True) == DriveState.FAULT, "latched until reset"
    drive.reset()
    assert drive.state == DriveState.OFF and drive.fault_code == FaultCode.NONE


def test_drive_heartbeat_loss_pressure_loss_injected_fault_and_estop():
    def ready(drive: Drive) -> Drive:
        drive.on_heartbeat(0.0)
        drive.update(0.0, True)
        return drive

    drive = ready(Drive(0.05))
    assert drive.update(0.06, True) == DriveState.FAULT and drive.fault_code == FaultCode.HEARTBEAT_WATCHDOG
    drive = ready(Drive(0.05))
    assert drive.update(0.01, False) == DriveState.FAULT and drive.fault_code == FaultCode.PRESSURE_LOST
    drive = ready(Drive(0.05))
    assert drive.update(0.01, True, injected_code=42) == DriveState.FAULT and drive.fault_code == 42
    drive = ready(Drive(0.05))
    drive.on_estop()
    assert drive.update(0.01, True) == DriveState.ESTOP and drive.fault_code == FaultCode.ESTOP


def test_the_shipped_profile_has_a_usable_rig_section():
    from harness.profile import load_profile
    from tests.conftest import PROFILES

    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    rig = profile.rig
    period = 1.0 / profile.control.rate_hz
    assert abs(period / rig.physics_substep_s - round(period / rig.physics_substep_s)) < 1e-9
    assert rig.actuator.model == "servo_hydraulic" and rig.table.model == "servo_hydraulic"
    assert rig.actuator.force_limit_N <= 30_000.0
    # The tracking check expects the velocity feedback the shipped servo controller leaves:
    # k_h / w_f, the share alpha its velocity feed-forward cancels and the orifice's A p_s (SPEC 7a').
    force, hydraulics = profile.safety.force, rig.actuator.hydraulics
    assert force.velocity_feedback_Ns_per_m == pytest.approx(hydraulics.loop_damping_Ns_per_m(), rel=0.01)
    assert force.velocity_feedforward_gain == hydraulics.feedforward.gain
    assert force.supply_force_N == pytest.approx(hydraulics.cylinder.force_capacity_N, rel=0.01)
    assert rig.sensors.displacement.noise_std_m > 0 and rig.faults == ()
