"""What a command runs, start to end: a simulation study, a session on a bus, a dry run, the rig service.

- :mod:`.options`: the command line's options resolved into the profile once
  (:func:`~harness.runs.options.resolve_profile`), and the record loaded from it
  (:func:`~harness.runs.options.prepare_motion`); every command uses them.
- :mod:`.simulate`: a passive and a controlled case simulated side by side (``harness simulate``);
  :mod:`.simulate_batch`: one study per record and controller, and their summary;
  :mod:`.simulate_output`: a study's cases written as run folders.
- :mod:`.session`: one control session on a bus (``harness run`` and the loop of a dry run);
  :mod:`.drive_reset`: ``--reset-drive``, sent once before arming.
- :mod:`.run`: a run of the real rig (``harness run``): its table link, which answers arm, its session.
- :mod:`.dry_run`: a session against the virtual rig, with the simulated twins to compare;
  :mod:`.run_context`: what its console printed, kept in the run folder for ``harness report``.
- :mod:`.rig_service` and :mod:`.rig_process`: the virtual rig serving a bus
  (``harness rig``, and the process a dry run starts).
- :mod:`.identify`: the actuator's frequency response, one session per condition (``harness identify actuator``).

Imports run one way: the commands import runs; runs import the loop and the
simulation, which import the rig, control and safety, then the model and CAN, then
configuration and errors.
"""
