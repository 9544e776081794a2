"""The per-tick health inputs the loop hands to the supervisor.

One :class:`TickHealth` is allocated before a run and updated in place every tick
by the loop (from the drivers, the bus and its own timing). It holds plain
numbers and flags only; the supervisor never writes to it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from drivers.measurements import Measurements


@dataclass(slots=True)
class TickHealth:
    """Everything the safety checks look at, besides the raw controller force.

    Attributes
    ----------
    meas : Measurements
        The same object the controller reads (SI); referenced, not copied.
    table_fresh, base_fresh : bool
        A new table / base-mat sensor frame was accepted this tick (stuck, jump and
        disagreement checks only count fresh samples).
    table_age_s, base_age_s : float
        Age of the newest accepted table / base-mat sensor frame (s).
    e2e_ok : bool
        The newest frame of every safety-relevant message passed its counter and CRC check.
    e2e_rejects : int
        Cumulative count of frames rejected for counter or CRC (monotonic).
    error_frames : int
        Cumulative count of CAN error frames seen (monotonic).
    error_passive, bus_off, bus_gone : bool
        Controller error-passive; bus-off; the interface has disappeared or cannot be read.
    send_failures : int
        Cumulative count of failed sends (ENOBUFS and the like; monotonic).
    foreign_command : bool
        A frame with the actuator command ID was seen that this harness did not send.
    drive_ready, drive_fault, pressure_ok : bool
        From the newest actuator status frame.
    drive_fault_code : int
        The fault code of the newest actuator status frame (:class:`drivers.protocol.protocol_values.FaultCode`;
        0 none): why the drive faulted, e.g. its heartbeat watchdog.
    actuator_status_age_s : float
        Age of the newest actuator status frame (s).
    actuator_status_fresh : bool
        A new actuator status frame (the load cell's sample) was accepted this tick. The load cell
        comes at ``can.status_rate_hz`` (250 Hz), slower than a fast loop: between its samples
        :attr:`measured_force_N` holds the last one, and a check that filters it counts fresh samples.
    measured_force_N : float
        Force reported by the actuator's load cell (N).
    stall_s : float
        Time since the previous tick wrote its command (s); 0 in lockstep, where the
        rig waits for the loop. Above one period when deadlines were missed.
    missed_periods : int
        Whole periods missed before this tick (0 on time).
    estop : bool
        The operator E-stop frame is asserted.
    estop_panel_age_s : float
        Age of the newest intact ESTOP frame from the operator panel (source 3, s); infinity
        before the first, NaN for an unusable timestamp.
    operator_stop : bool
        The operator asked for a controlled stop (first Ctrl-C).
    operator_trip : bool
        The operator asked for an immediate trip (second Ctrl-C, SIGTERM).
    record_time_s : float
        Time since the record started on the table (s), set by the loop; NaN while no record
        plays (before RUNNING, or while the table has not yet reported running).
    compensation_pinned : bool
        The force-tracking compensator's bounded parameter (a correction, a coefficient) sits at
        its bound after this tick's update (:attr:`harness.control.compensation.Compensator.pinned`).
    compensation_diverged : bool
        The compensator's state is not finite (:attr:`harness.control.compensation.Compensator.diverged`).
    compensation_value : float
        The parameter pinned or diverged, for the event's detail (its own unit).
    """

    meas: Measurements = field(default_factory=Measurements)
    table_fresh: bool = True
    base_fresh: bool = True
    table_age_s: float = 0.0
    base_age_s: float = 0.0
    e2e_ok: bool = True
    e2e_rejects: int = 0
    error_frames: int = 0
    error_passive: bool = False
    bus_off: bool = False
    bus_gone: bool = False
    send_failures: int = 0
    foreign_command: bool = False
    drive_ready: bool = True
    drive_fault: bool = False
    drive_fault_code: int = 0
    pressure_ok: bool = True
    actuator_status_age_s: float = 0.0
    actuator_status_fresh: bool = True
    measured_force_N: float = 0.0
    stall_s: float = 0.0
    missed_periods: int = 0
    estop: bool = False
    estop_panel_age_s: float = 0.0
    operator_stop: bool = False
    operator_trip: bool = False
    record_time_s: float = math.nan
    compensation_pinned: bool = False
    compensation_diverged: bool = False
    compensation_value: float = 0.0
