"""Fault-injection dry runs (lockstep, deterministic): each fault the rig injects trips the run
with the expected reason within the detector's stated bound (docs/SAFETY.md), and replays bit for bit
with that trip (``harness replay``, issue 34)."""

from __future__ import annotations

import json
import math

import pytest

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.recording import load_run
from tests.replay_checks import assert_trip_replayed

FAULT_AT_S = 1.0  # record time of the fault's onset
PERIOD_S = 0.002  # 500 Hz
VISIBLE_AFTER_S = 2 * PERIOD_S  # onset at the rig -> first affected frame seen by the loop (lockstep)
SAFETY = load_profile().safety

# fault spec -> (the trip reason, detection bound after onset in s); lockstep makes each deterministic
#: The E2E faults trip once more frames than ``max_e2e_rejects`` were refused, one a period.
E2E_BOUND_S = (SAFETY.comms.max_e2e_rejects + 1) * PERIOD_S
FAULTS = {
    "table_dropout": ("{kind: dropout, target: TABLE_SENSORS}", "sensor_stale", SAFETY.sensors.max_sensor_age_s),
    "base_dropout": ("{kind: dropout, target: BASE_SENSORS}", "sensor_stale", SAFETY.sensors.max_sensor_age_s),
    "status_stops": ("{kind: dropout, target: ACTUATOR_STATUS}", "actuator_status_stale", SAFETY.actuator.max_status_age_s),
    # frozen values while the table moves: the frozen velocity disagrees with the (now flat)
    # displacement before stuck_samples repeats (a stuck channel at rest: the test below)
    "table_stuck": ("{kind: stuck, target: TABLE_SENSORS}", "sensor_disagree",
                    max(SAFETY.sensors.stuck_samples * PERIOD_S,
                        SAFETY.sensors.disagree_time_s + 2 * SAFETY.sensors.disagree_filter_s)),
    # a negated velocity (polarity fault): the filtered velocity crosses -floor within
    # tau * ln(2 v / (v - floor)) <= tau * ln 4 for v >= 2 floor, then the signs must disagree for sign_flip_time_s
    "base_sign_flip": ("{kind: sign_flip, target: BASE_SENSORS, param: 1}", "sensor_sign_flip",
                       SAFETY.sensors.disagree_filter_s * math.log(4) + SAFETY.sensors.sign_flip_time_s),
    "table_sign_flip": ("{kind: sign_flip, target: TABLE_SENSORS, param: 1}", "sensor_sign_flip",
                        SAFETY.sensors.disagree_filter_s * math.log(4) + SAFETY.sensors.sign_flip_time_s),
    "table_spike": ("{kind: spike, target: TABLE_SENSORS, param: 0.02}", "sensor_jump", PERIOD_S),
    "base_noise_burst": ("{kind: noise_burst, target: BASE_SENSORS, param: 0.05}", "sensor_jump", PERIOD_S),
    "table_bad_crc": ("{kind: corrupt_crc, target: TABLE_SENSORS}", "e2e_rejects", E2E_BOUND_S),
    "base_repeated_counter": ("{kind: repeat_counter, target: BASE_SENSORS}", "e2e_rejects", E2E_BOUND_S),
    "table_skipped_counter": ("{kind: skip_counter, target: TABLE_SENSORS}", "e2e_rejects", E2E_BOUND_S),
    "drive_fault": ("{kind: drive_fault, param: 4}", "drive_fault", 2 * 0.004),
    # the servo faults its drive on pressure loss in the same status frame; drive_fault is checked
    # first (hydraulic_pressure alone: tests/unit/test_detectors.py)
    "pressure_lost": ("{kind: pressure_lost}", "drive_fault", 2 * 0.004),
    "estop": ("{kind: estop}", "estop", 2 * 0.004),
}


def _run_with_fault(tmp_path, spec: str, duration: float = 3.0, extra: tuple[str, ...] = ()):
    fault = spec[:-1] + f", start_s: {FAULT_AT_S}}}"
    status = main(["dry-run", "--log-dir", str(tmp_path), "--lockstep", "--quiet", "--duration", str(duration),
                   "--set", f"rig.faults=[{fault}]", *extra])
    folder = next(p for p in tmp_path.iterdir() if p.is_dir())
    return status, folder


def _onset_time(run) -> float:
    """Loop time at which the record (and so the fault schedule) started: the RUNNING transition."""
    running = next(e for e in run.events if e["name"] == "RUNNING")
    return float(running["t_s"]) + FAULT_AT_S


@pytest.mark.parametrize("case", sorted(FAULTS))
def test_injected_fault_trips_with_its_reason_within_its_bound(tmp_path, capsys, case):
    spec, reason, bound_s = FAULTS[case]
    status, folder = _run_with_fault(tmp_path, spec)
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED, metadata
    assert metadata["trip_reason"] == reason
    run = load_run(folder)
    trip = next(e for e in run.events if e["kind"] == "fault")
    latency = float(trip["t_s"]) - _onset_time(run)
    # the fault acts on the rig's frames: they reach the loop one step later, after the sensor's 1 ms
    # delay (a whole step in lockstep): two periods between the rig's onset and what the harness can see
    assert 0.0 <= latency <= bound_s + VISIBLE_AFTER_S + 1e-9, (
        f"{case}: detected after {latency * 1e3:.1f} ms, bound {bound_s * 1e3:.1f} ms"
    )
    assert run["force_command_N"][-1] == 0.0 and run["drive_enabled"][-1] == 0.0
    assert_trip_replayed(capsys, folder, reason)  # issue 34: each fault's run replays bit for bit, with its trip


def test_a_frozen_base_mat_sensor_at_rest_trips_sensor_stuck(tmp_path, capsys):
    """The safety review's reproduction: fresh frames (good CRC and counter) with y_b and ydot_b frozen,
    at PGA 0.03 g, where |xdot_0| stays near 0.01 m/s. It used to run to the end with the force commanded
    from frozen values; a healthy sensor's noise is never bit-for-bit constant, so it trips at rest too."""
    status, folder = _run_with_fault(tmp_path, "{kind: stuck, target: BASE_SENSORS}", extra=("--pga", "0.03"))
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED, metadata
    assert metadata["trip_reason"] == "sensor_stuck"
    run = load_run(folder)
    trip = next(e for e in run.events if e["kind"] == "fault")
    assert trip["name"] == "sensor_stuck" and "y_b" in trip["detail"]
    latency = float(trip["t_s"]) - _onset_time(run)
    bound_s = SAFETY.sensors.stuck_samples * PERIOD_S
    assert 0.0 <= latency <= bound_s + 3 * PERIOD_S, f"detected after {latency * 1e3:.1f} ms, bound {bound_s * 1e3:.1f} ms"
    assert run["force_command_N"][-1] == 0.0 and run["drive_enabled"][-1] == 0.0


def test_a_slow_sign_flip_that_sensor_disagree_never_sees_trips_sensor_sign_flip(tmp_path, capsys):
    """At PGA 0.03 g the base mat barely slides: 2 |ydot_b| stays below sensor_disagree's tolerance, so a
    negated ydot_b ran to the end before sensor_sign_flip; it trips once the wrong push moves the base."""
    status, folder = _run_with_fault(tmp_path, "{kind: sign_flip, target: BASE_SENSORS, param: 1}", extra=("--pga", "0.03"))
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED, metadata
    assert metadata["trip_reason"] == "sensor_sign_flip"
    trip = next(e for e in load_run(folder).events if e["kind"] == "fault")
    assert "sign flip on y_b/ydot_b" in trip["detail"]


def test_bus_silence_in_lockstep_trips_as_bus_gone(tmp_path, capsys):
    """The rig falls silent: in lockstep the step never comes, the wait times out and the run trips."""
    status, folder = _run_with_fault(tmp_path, "{kind: bus_silence}")
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED
    assert metadata["trip_reason"] in {"bus_gone", "sensor_stale"}


def test_extra_delay_alone_does_not_trip(tmp_path, capsys):
    """An extra 5 ms of sensor delay degrades control but is no fault: no check trips.

    The delay's phase lag sets off the shipped rig's force-loop limit cycle once the record's
    motion ends (44 Hz, 3 kN peak to peak in the tail): the run then completes, or
    ``force_oscillation`` stops it safely (issue 30) and says so; nothing trips.
    """
    status, folder = _run_with_fault(tmp_path, "{kind: extra_delay, param: 0.005}", duration=2.0)
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert (status, metadata["outcome"]) in ((exit_codes.OK, "completed"), (exit_codes.STOPPED, "stopped")), metadata
    if metadata["outcome"] == "stopped":
        assert metadata["trip_reason"] == "force_oscillation"
    assert not [e for e in load_run(folder).events if e["kind"] == "fault" and e["name"] != "force_oscillation"]


#: The slow sign flip under each way of closing the force loop: the harness's compensation
#: (``control.compensation``) and the servo controller's own velocity feed-forward (the shipped rig has it;
#: ``plain_loop`` takes it away, in the rig and in what the tracking check expects).
SLOW_FLIP_METHODS = {
    "none_rig_feedforward": (),
    "plain_loop": ("--set", "rig.actuator.hydraulics.feedforward.gain=0",
                   "--set", "safety.force.velocity_feedforward_gain=0", "--allow-weaker-safety"),
    "model": ("--set", "control.compensation=model"),
    "adaptive": ("--set", "control.compensation=adaptive"),
}


@pytest.mark.parametrize("method", sorted(SLOW_FLIP_METHODS))
def test_a_slow_sign_flip_trips_under_every_compensation_and_with_rig_side_feedforward(tmp_path, capsys, method):
    """The flip of ydot_b at 0.03 g ran untripped under ``model`` and ``adaptive``: the flow term on the wrong
    sensor damps the base mat below sensor_sign_flip's 2 mm/s floor (docs/SAFETY.md, "A sign flip held below
    the floor"). sensor_polarity sees it there; either check may be first, and the run trips before its end."""
    status, folder = _run_with_fault(tmp_path, "{kind: sign_flip, target: BASE_SENSORS, param: 1}",
                                     extra=("--pga", "0.03", *SLOW_FLIP_METHODS[method]))
    capsys.readouterr()
    metadata = json.loads((folder / "metadata.json").read_text())
    assert status == exit_codes.TRIPPED, metadata
    assert metadata["trip_reason"] in {"sensor_sign_flip", "sensor_polarity"}
    run = load_run(folder)
    trip = next(e for e in run.events if e["kind"] == "fault")
    assert "y_b/ydot_b" in trip["detail"]
    assert float(trip["t_s"]) > _onset_time(run)  # never before the flip
    # before the fault, neither check acted: the polarity check is quiet on the healthy base mat
    assert not [e for e in run.events if e["kind"] == "fault" and float(e["t_s"]) < _onset_time(run)]
