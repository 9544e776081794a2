"""Sampled-data simulation faster than real time: a case (plant, estimator, controller) and the rig's twin.

- :mod:`.case`: one case with an ideal controller (``run_case``, ``SamplingSettings``).
- :mod:`.twin`: the controlled case through the rig's sensor, actuator and safety models.
- :mod:`.sampled`: what both share: the per-sample arrays, the sample loop, ``CaseResult``.
"""
