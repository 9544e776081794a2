"""Compile the numba kernels before anything runs in real time.

numba compiles a function on its first call (or loads it from the on-disk cache, which
a fresh checkout does not have yet). A compilation takes seconds and holds the
interpreter, so it must never happen inside a control loop or the virtual rig: a loop
that stalls for seconds trips on stale sensors (as it should). :func:`warm_up` calls
every compiled function once, with the argument types the loop and the rig use.
"""

from __future__ import annotations

import numpy as np

from harness.model.bearing import (
    advance_hysteretic,
    estimator_step,
    friction_coefficient,
    friction_force,
    hysteretic_rate,
)
from harness.model.integrator import advance, derivative, make_work, table_state
from harness.motions.online_tracking import accumulate_products

_warm = False


def warm_up() -> bool:
    """Compile (or load from the cache) every kernel; return True if this call did the work."""
    global _warm
    if _warm:
        return False
    params = np.array([0.06, 0.03, 90.0, 4.0e4, 1.0, 0.5, 0.5, 3.0, 2.5e-5])
    samples = np.zeros(4)
    size = 4
    a_matrix, b_vector = np.zeros((size, size)), np.zeros(size)
    y, out = np.zeros(size + 1), np.zeros(size + 1)
    atol = np.full(size + 1, 1e-9)
    no_rig = np.zeros(0)
    friction_coefficient(0.0, params)
    friction_force(0.0, 0.0, params)
    hysteretic_rate(0.0, 0.0, params)
    advance_hysteretic(0.0, 0.1, 1e-3, params)
    estimator_step(0.0, 0.1, 0.1, 1e-3, params)
    read_only = samples.copy()
    read_only.flags.writeable = False  # processed records are read-only: numba compiles them apart
    for table in (samples, read_only):
        table_state(0.0, table, table, table, 0.01)
        derivative(0.0, y, out, 0.0, a_matrix, b_vector, 0.0, params, table, table, table, 0.01, no_rig)
        advance(
            y, 0.0, 1e-3, 0.0, a_matrix, b_vector, 0.0, params, table, table, table, 0.01, atol, 1e-6, make_work(size + 1),
            no_rig,
        )
    accumulate_products(np.zeros(3), np.zeros(5), 1, 0.0)  # the table check's per-tick sums (harness/safety/table_record.py)
    _warm = True
    return True

