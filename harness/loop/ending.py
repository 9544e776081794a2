"""How a run ended, read off its supervisor: one rule for the loop and the twin.

A run that reached DONE completed, unless the operator asked it to stop or a check's safe stop
ended it (``Supervisor.stop_reason`` names the check); a run whose supervisor latched a trip
tripped. The reason is the trip's, or the safe stop's when it was a check that stopped the run.
"""

from __future__ import annotations

from dataclasses import dataclass

from harness.recording.layout import Outcome
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor

_OUTCOME_OF: dict[State, Outcome] = {State.DONE: "completed", State.TRIPPED: "tripped"}


@dataclass(frozen=True)
class RunEnding:
    """The outcome of a run, the name of what ended it ("" for none) and its detail."""

    outcome: Outcome
    reason: str
    detail: str


def run_ending(supervisor: Supervisor, stop_requested: bool = False, *, record_ended: bool = False) -> RunEnding:
    """The ending of a run whose supervisor is ``supervisor``, after its last tick.

    Parameters
    ----------
    supervisor : Supervisor
        The run's supervisor, in its final state.
    stop_requested : bool
        True if the operator asked the run to stop (Ctrl-C, the stop key, an E-stop request).
    record_ended : bool
        True when the caller ran the whole record with no stopping ramp after it (the twin): a
        supervisor still RUNNING then completed.

    Returns
    -------
    RunEnding
        "tripped" with the trip's reason; "stopped" with the safe stop's check (or the trip
        reason a stop carried, or "" for the operator's stop); "completed" otherwise. A
        supervisor not yet DONE nor TRIPPED (the loop left early) counts as stopped.
    """
    state = State.DONE if record_ended and supervisor.state is State.RUNNING else supervisor.state
    outcome = _OUTCOME_OF.get(state, "stopped")
    if outcome == "completed" and (stop_requested or supervisor.stop_reason):
        outcome = "stopped"
    if outcome == "stopped" and not supervisor.command.trip_reason:
        return RunEnding(outcome, supervisor.stop_reason, supervisor.stop_detail)
    return RunEnding(outcome, supervisor.command.trip_reason, supervisor.trip_detail)
