"""A trip reaches the devices on the virtual rig: the drive sees the ESTOP and the table stops.

Lockstep dry runs on python-can's in-process bus, with the virtual rig in this process so
its state can be read after the run (what it received, not what the harness meant to send).
"""

from __future__ import annotations

import json

import pytest

from drivers.protocol.protocol_values import DriveState
from harness.loop.runner import ArmTimeout
from harness.profile import load_profile
from harness.recording import load_run
from harness.rig.virtual_rig import VirtualRig
from harness.runs.dry_run import DryRunOptions, dry_run
from harness.runs.options import StudyOptions

FAULT_AT_S = 1.0
PERIOD_S = 0.002


class WatchedRig(VirtualRig):
    """The virtual rig, with a snapshot of what it saw taken just before it is stopped."""

    made: list[WatchedRig] = []
    unplug_panel = False

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.panel_connected = not self.unplug_panel
        self.seen: dict = {}
        WatchedRig.made.append(self)

    def stop(self, timeout_s: float = 2.0) -> None:
        self._stop_event.set()
        if self._thread is not None:
            self._thread.join(timeout_s)
        self.seen = {
            "drive_state": self.drive.state, "running": self.table.running, "started": self.table.started,
            "record_time_s": self.table.record_time_s, "panel_sent": self.publisher.panel_sent,
        }
        super().stop(timeout_s)


@pytest.fixture
def watched(monkeypatch):
    import harness.rig.virtual_rig

    WatchedRig.made = []
    WatchedRig.unplug_panel = False
    monkeypatch.setattr(harness.rig.virtual_rig, "VirtualRig", WatchedRig)
    return WatchedRig


def _dry_run(tmp_path, overrides: tuple[str, ...]):
    profile = load_profile(None, overrides=list(overrides))
    options = DryRunOptions(
        study=StudyOptions(duration_s=3.0), interface="virtual", log_dir=str(tmp_path), lockstep=True,
        show_console=False, compare=False,
    )
    return dry_run(profile, options)


def test_a_trip_stops_the_table_and_the_rig_sees_the_estop(tmp_path, watched):
    fault = f"{{kind: spike, target: TABLE_SENSORS, param: 0.02, start_s: {FAULT_AT_S}}}"
    result = _dry_run(tmp_path, (f"rig.faults=[{fault}]",))
    assert result.session.outcome == "tripped" and result.session.trip_reason == "sensor_jump"
    seen = watched.made[0].seen
    assert seen["drive_state"] == DriveState.ESTOP, "the servo latched the harness's ESTOP frame"
    assert seen["started"] and not seen["running"], "the table was stopped"
    # lockstep: every tick after the trip still steps the rig, so a running table would have moved on
    run = load_run(result.session.run_path)
    running_t = next(float(e["t_s"]) for e in run.events if e["name"] == "RUNNING")
    trip_t = next(float(e["t_s"]) for e in run.events if e["kind"] == "fault")
    assert seen["record_time_s"] == pytest.approx(trip_t - running_t, abs=3 * PERIOD_S)
    assert float(run["t_s"][-1]) - trip_t >= load_profile(None).loop.after_s - PERIOD_S
    assert seen["panel_sent"] > 0


def test_with_disable_alone_the_table_runs_on_and_no_estop_reaches_the_drive(tmp_path, watched):
    fault = f"{{kind: spike, target: TABLE_SENSORS, param: 0.02, start_s: {FAULT_AT_S}}}"
    result = _dry_run(tmp_path, (f"rig.faults=[{fault}]", "safety.trip_actions.sensor=[disable]"))
    assert result.session.outcome == "tripped"
    seen = watched.made[0].seen
    assert seen["drive_state"] != DriveState.ESTOP and seen["running"]


def test_an_unplugged_panel_refuses_to_arm(tmp_path, watched):
    watched.unplug_panel = True
    with pytest.raises(ArmTimeout, match="estop_panel_live"):
        _dry_run(tmp_path, ("loop.arm_timeout_s=0.3",))


def test_a_run_without_a_required_panel_is_recorded_as_such(tmp_path, watched):
    watched.unplug_panel = True
    result = _dry_run(tmp_path, ("safety.estop.panel_required=false", "rig.faults=[]"))
    assert result.session.outcome == "completed"
    metadata = json.loads((result.session.run_path / "metadata.json").read_text())
    assert metadata["estop_panel_required"] is False
    assert any(e["name"] == "estop_panel_not_required" for e in load_run(result.session.run_path).events)
