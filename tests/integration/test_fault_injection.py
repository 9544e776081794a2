"""Fault-injection dry runs (lockstep, deterministic): each fault the rig injects trips the run
with the expected reason within the detector's stated bound (docs/SAFETY.md)."""

from __future__ import annotations

import json

import pytest

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.record import load_run

FAULT_AT_S = 1.0  # record time of the fault's onset
PERIOD_S = 0.002  # 500 Hz
SAFETY = load_profile().safety

# fault spec -> (accepted trip reasons, detection bound after onset in s)
FAULTS = {
    "table_dropout": ("{kind: dropout, target: TABLE_SENSORS}", {"sensor_stale"}, SAFETY.sensors.max_sensor_age_s),
    "base_dropout": ("{kind: dropout, target: BASE_SENSORS}", {"sensor_stale"}, SAFETY.sensors.max_sensor_age_s),
    "status_stops": ("{kind: dropout, target: ACTUATOR_STATUS}", {"actuator_status_stale"}, SAFETY.actuator.max_status_age_s),
    # frozen values: the stuck counter fires after stuck_samples, unless the frozen velocity
    # disagrees with the (now flat) displacement first
    "table_stuck": ("{kind: stuck, target: TABLE_SENSORS}", {"sensor_stuck", "sensor_disagree"},
                    max(SAFETY.sensors.stuck_samples * PERIOD_S, SAFETY.sensors.disagree_time_s + 2 * SAFETY.sensors.disagree_filter_s)),
    "table_spike": ("{kind: spike, target: TABLE_SENSORS, param: 0.02}", {"sensor_jump"}, PERIOD_S),
    "base_noise_burst": ("{kind: noise_burst, target: BASE_SENSORS, param: 0.05}", {"sensor_jump", "sensor_invalid"}, PERIOD_S),
    "table_bad_crc": ("{kind: corrupt_crc, target: TABLE_SENSORS}", {"e2e_rejects"}, (SAFETY.comms.max_e2e_rejects + 1) * PERIOD_S),
    "base_repeated_counter": ("{kind: repeat_counter, target: BASE_SENSORS}", {"e2e_rejects"}, (SAFETY.comms.max_e2e_rejects + 1) * PERIOD_S),
    "table_skipped_counter": ("{kind: skip_counter, target: TABLE_SENSORS}", {"e2e_rejects"}, (SAFETY.comms.max_e2e_rejects + 1) * PERIOD_S),
    "drive_fault": ("{kind: drive_fault, param: 4}", {"drive_fault"}, 2 * 0.004),
    "pressure_lost": ("{kind: pressure_lost}", {"hydraulic_pressure", "drive_fault"}, 2 * 0.004),
    "estop": ("{kind: estop}", {"estop"}, 2 * 0.004),
}


def _run_with_fault(tmp_path, spec: str, duration: float = 3.0):
    fault = spec[:-1] + f", start_s: {FAULT_AT_S}}}"
    status = main(["dry-run", "--log-dir", str(tmp_path), "--lockstep", "--quiet", "--duration", str(duration),
                   "--set", f"rig.faults=[{fault}]"])
    folder = next(p for p in tmp_path.iterdir() if p.is_dir())
    return status, folder


def _onset_time(run) -> float:
    """Loop time at which the record (and so the fault schedule) started: the RUNNING transition."""
    running = next(e for e in run.events if e["name"] == "RUNNING")
    return float(running["t_s"]) + FAULT_AT_S


@pytest.mark.parametrize("case", sorted(FAULTS))
def test_injected_fault_trips_with_its_reason_within_its_bound(tmp_path, capsys, case):
    spec, reasons, bound_s = FAULTS[case]
    status, folder = _run_with_fault(tmp_path, spec)
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED, metadata
    assert metadata["trip_reason"] in reasons
    run = load_run(folder)
    trip = next(e for e in run.events if e["kind"] == "fault")
    latency = float(trip["t_s"]) - _onset_time(run)
    assert 0.0 <= latency <= bound_s + 3 * PERIOD_S, f"{case}: detected after {latency * 1e3:.1f} ms, bound {bound_s * 1e3:.1f} ms"
    assert run["force_command_N"][-1] == 0.0 and run["drive_enabled"][-1] == 0.0


def test_bus_silence_in_lockstep_trips_as_bus_gone(tmp_path, capsys):
    """The rig falls silent: in lockstep the step never comes, the wait times out and the run trips."""
    status, folder = _run_with_fault(tmp_path, "{kind: bus_silence}")
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED
    assert metadata["trip_reason"] in {"bus_gone", "sensor_stale"}


def test_extra_delay_alone_does_not_trip(tmp_path, capsys):
    """An extra 5 ms of sensor delay degrades control but is no fault: the run completes."""
    status, folder = _run_with_fault(tmp_path, "{kind: extra_delay, param: 0.005}", duration=2.0)
    capsys.readouterr()
    assert status == exit_codes.OK
    assert json.loads((folder / "metadata.json").read_text())["outcome"] == "completed"
