"""A tight-tolerance reference integrator built on ``scipy.integrate.solve_ivp``.

:class:`ReferencePlant` is a :class:`~harness.model.plant.Plant` whose ``advance``
integrates the same right-hand side with an implicit scipy solver at rtol 1e-9 (by
default), one hold interval at a time. It is slow; it exists to check the compiled
kernel (tests, ``benchmarks/``).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp

from harness.errors import ModelError
from harness.model.integrator import derivative
from harness.model.plant import Plant


class ReferencePlant(Plant):
    """Plant advanced by ``solve_ivp`` (``method``, ``rtol``) instead of the compiled kernel."""

    def __init__(self, *args, method: str = "LSODA", reference_rtol: float = 1e-9, **kwargs):
        super().__init__(*args, **kwargs)
        self.method = method
        self.reference_rtol = reference_rtol
        self.reference_atol = self.atol * (reference_rtol / self.rtol)
        self._out = np.zeros_like(self.y)

    def _rhs(self, t: float, y: np.ndarray, force_N: float) -> np.ndarray:
        m, table = self.model, self.table
        out = np.empty_like(y)
        derivative(
            t, y, out, force_N, m.A, m.B, m.restoring_stiffness_N_per_m, self.bearing_params,
            table.accel_m_s2, table.velocity_m_s, table.displacement_m, table.dt_s, self.rig_params,
        )
        return out

    def advance(self, t0: float, t1: float, force_N: float) -> None:
        """Integrate ``[t0, t1]`` with ``solve_ivp`` at the reference tolerance."""
        if t1 <= t0:
            return
        solution = solve_ivp(
            self._rhs, (t0, t1), self.y, method=self.method, args=(force_N,),
            rtol=self.reference_rtol, atol=self.reference_atol,
        )
        if not solution.success:
            raise ModelError(f"reference integration failed on [{t0:g}, {t1:g}] s: {solution.message}")
        self.y[:] = solution.y[:, -1]
        self.steps += solution.t.size - 1
