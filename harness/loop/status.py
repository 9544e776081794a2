"""What the live console shows: the loop's status, each field declared once, in shared memory.

The control loop overwrites a :class:`LoopStatus` in place every tick; the live console
runs in a child process (:mod:`harness.console.view`) that attaches to the same block and
draws it, so rendering never holds the loop process's interpreter lock. The block's file,
its layout and the sequence lock of its text are :mod:`harness.loop.status_block`'s.
"""

from __future__ import annotations

from harness.loop.status_block import FloatField, IntField, StateField, StatusBlock, TextField

#: The run states by code; the same names and values as :class:`harness.safety.lifecycle.State`
#: (not imported here so the console's child process starts without the safety layer).
STATE_NAMES = ("IDLE", "ARMED", "RUNNING", "STOPPING", "DONE", "TRIPPED")
#: The table check's verdicts by code; the same names and values as
#: :class:`harness.safety.table_record.TableVerdict` (not imported, as for :data:`STATE_NAMES`).
TABLE_VERDICT_NAMES = ("OFF", "WAITING", "MATCH", "MARGINAL", "MISMATCH")


class LoopStatus(StatusBlock):
    """The loop's status for the live console, in shared memory.

    ``LoopStatus(**fields)`` creates a new block (this object owns it and removes it at
    :meth:`close`); :meth:`attach` maps an existing one (read-only by default) in another
    process. After :meth:`close` the object keeps its last values in private memory and
    stays readable and writable. The fields are the class attributes below, each with what
    it holds; ``finished`` (set by the loop's side when the run is over: the console's child
    then draws its last frame), the lateness ring, the stories and the event lines are
    :class:`~harness.loop.status_block.StatusBlock`'s.

    Parameters
    ----------
    **fields
        Initial values of any of the fields.
    """

    __slots__ = ()

    state = StateField(STATE_NAMES, "run state")  # set from the name or a lifecycle State
    t_s = FloatField("loop time of the last tick (s)")
    run_t_s = FloatField("time since RUNNING began (s); 0 before")
    duration_s = FloatField("seconds of record to run (s)")
    stroke_m = FloatField("sliding displacement x_b (m)")
    force_N = FloatField("commanded actuator force (N)")
    sliding_variable = FloatField("the controller's sliding variable S (m/s)")
    e2e_rejects = IntField("frames rejected by the end-to-end protection")
    error_frames = IntField("CAN error frames seen")
    send_failures = IntField("frames that could not be sent")
    stalls = IntField("stalls: ticks with at least one missed period, ridden through or past the budget "
                      "(harness.signals.timing_counts)")
    gaps_past_budget = IntField("gaps between two ticks' starts longer than the stall budget, in any phase (each an event)")
    longest_stall_s = FloatField("longest time between the starts of two consecutive ticks in a stall (s)")
    missed_periods = IntField("missed periods in total: the sum of the overrun column (harness.signals.timing_counts)")
    fault_code = IntField(
        "the servo's fault code in the latest ACTUATOR_STATUS (drivers.protocol.protocol_values.FaultCode); 0 none"
    )
    n_stories = IntField("stories whose drift and floor acceleration are published (set_story); 0 none")
    table_verdict = IntField("the table against its record: a code of TABLE_VERDICT_NAMES")
    table_correlation = FloatField("the table check's latest correlation (NaN before its first evaluation)")
    table_delay_s = FloatField("the table check's latest delay of the table behind its record (s)")
    table_amplitude_ratio = FloatField("the table check's latest amplitude ratio, achieved over told")
    phase = TextField(64, "starting")
    last_event = TextField(256)
    trip_reason = TextField(128)

    def stories(self) -> list[tuple[float, float]]:
        """``(drift_m, floor_acceleration_m_s2)`` of stories 1 .. :attr:`n_stories`, bottom up."""
        return self.story_values(self.n_stories)
