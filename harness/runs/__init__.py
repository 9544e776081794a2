"""What a command runs, start to end: a simulation study, a session on a bus, a dry run, the rig service.

- :mod:`.simulate`: the command line's options resolved into the profile once
  (:func:`~harness.runs.simulate.resolve_profile`), and a passive and a controlled
  case simulated side by side (``harness simulate``).
- :mod:`.session`: one control session on a bus (``harness run`` and the loop of a dry run).
- :mod:`.dry_run`: a session against the virtual rig, with the simulated twins to compare.
- :mod:`.rig_service` and :mod:`.rig_process`: the virtual rig serving a bus
  (``harness rig``, and the process a dry run starts).
- :mod:`.simulate_output`: a study's cases written as run folders.

Imports run one way: the commands import runs; runs import the loop and the
simulation, which import the rig, control and safety, then the model and CAN, then
configuration and errors.
"""
