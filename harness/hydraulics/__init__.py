"""The servo-hydraulic model in one place: the cylinders' equations, their force loop linearised, the servo controller.

Modules:

- :mod:`.cylinder`: the servo-valve driven cylinders (SPEC 7a, 7b), their configuration
  sections (``rig.actuator.hydraulics``, ``rig.table``) and the compiled rates the plant's
  kernel (:mod:`harness.model.integrator`) evaluates, with the parameters packed for it;
- :mod:`.linear`: the force loop linearised, ``k_h``, ``w_f``, ``K_p``, ``k_h / w_f`` and
  ``(1 - alpha) k_h / w_f``, the one place the design models, the compensators and the
  identification take them from;
- :mod:`.servo_controller`: the control actuator's servo controller, velocity feed-forward
  from its stroke LVDT (SPEC 7a').

The rig's objects built on them, the actuator on the sub-step grid
(:mod:`harness.rig.actuator`) and the table with the plant on it (:mod:`harness.rig.table`),
stay with the virtual rig: the plant they advance (:mod:`harness.model.plant`) is the
building's, and its kernel calls these equations, so the package sits below the model
and the rig (docs/ARCHITECTURE.md, "How to add ...", "a rig component").

The package imports nothing: import what you need from its module.
"""
