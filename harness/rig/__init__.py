"""The virtual rig: the 4-DOF plant served on the CAN bus (``harness rig``, dry runs, tests).

Modules: :mod:`.config` (profile section ``rig``), :mod:`.truth` (the rig's own building and
bearing), :mod:`.parts` (what a rig is built from), :mod:`.table` (table and plant),
:mod:`.sensors`, :mod:`.actuator`, :mod:`.drive` (enable logic, watchdog), :mod:`.faults`
(fault ids), :mod:`.publish` (frames with faults), :mod:`.schedule` (message rates),
:mod:`.grid` (rounding to sub-steps and steps), :mod:`.history`, :mod:`.journal` (state changes
for a terminal), :mod:`.virtual_rig` (:class:`VirtualRig`), :mod:`.runner` (service thread).
Frames come in one at a time through :class:`drivers.rig_reader.RigReader`; ``harness rig``
is :mod:`harness.runs.rig_service`.

The lockstep contract (the harness's lockstep loop is written to it):

1. The rig has a step period ``T`` (the harness's control period) and a physics
   sub-step ``h`` dividing it (``rig.physics_substep_s``).
2. Lockstep is entered by RIG_CONTROL with ``lockstep = 1`` (any command) or by the
   constructor / ``harness rig --lockstep`` (then it is pinned: ``lockstep = 0``
   frames do not leave it). Entering resets ``step_index`` to 0.
3. On entering, after every step, and after every RIG_CONTROL frame handled in
   lockstep (same ``step_index``), the rig publishes in this order: TABLE_SENSORS,
   BASE_SENSORS, STORY_DRIFTS and FLOOR_ACCELS when ``step_index % k == 0``
   (``k = round(story period / T)``), ACTUATOR_STATUS, ESTOP (only while the rig's
   E-stop fault is active), and last RIG_STATUS with ``step_index`` = steps taken
   (modulo 2**24). Sensor values are those at the rig's current time, delayed by
   the sensor delays rounded to whole steps.
4. Every ACTUATOR_CMD frame (each frame, even several in one poll) is applied
   (enable bit to the drive, force through the actuator's delay, rounded to whole
   sub-steps, and dynamics) and advances the plant exactly ``T`` in ``T / h``
   sub-steps, the actuator force held constant over each sub-step; then the rig
   publishes as in 3. The harness's tick k reads RIG_STATUS(step_index = k), the
   sensors published before it, computes command k and sends it.
5. HEARTBEAT frames do not step. The drive watchdog runs on the wall clock in
   lockstep too: the service thread waits for frames with a short timeout and
   checks the watchdog after each wait; a drive-state change between steps is
   announced with one ACTUATOR_STATUS at once. While idle in lockstep the rig
   repeats ACTUATOR_STATUS (the last measured force, no new noise) and RIG_STATUS
   (same ``step_index``) at ``can.rig_status_rate_hz`` so a harness that joins late
   finds it and its drive's state.
7. DRIVE_RESET (the operator's reset of the drive's latched fault, before a run) is
   judged by the drive (:mod:`harness.rig.drive`); in lockstep the rig answers it with
   one ACTUATOR_STATUS at once (same ``step_index``).
6. RIG_CONTROL command 1 (start table) in lockstep starts the record with the next
   step: the step after it covers record time ``[0, T)``, and step ``k`` after the
   start reports record time ``k T``. In real time the record starts at the next
   sub-step. Command 2 holds the table where it is; 3 resets the plant to rest,
   clears latched drive faults and sets ``step_index`` to 0.

Import what you need from its module: :mod:`harness.rig.virtual_rig` (``VirtualRig``),
:mod:`harness.rig.parts`, :mod:`harness.rig.config`. The package imports nothing, so the
profile can import :mod:`harness.rig.config` without pulling in the rig.
"""
