"""The reference scheme ``dop853``: scipy's DOP853 (as ``solve_ivp(method="DOP853")`` runs it,
at most MAX_SUBSTEPS steps) on a whole batch as one system, its outcome written to ``io`` as the
compiled kernels write theirs (slow: for checking the others).
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics.integrators.layout import (
    _CF_DT,
    _CF_TOLERANCE,
    _PHI_IN,
    _ROW,
    _TAU,
    _W_IN,
    SCENE_FIELDS,
)
from roller_gym.physics.integrators.rules import _EPS, MAX_SUBSTEPS, _finish
from scipy.integrate import DOP853

#: How far past MAX_SUBSTEPS the steps a dop853 step has taken so far may project (their count
#: times the step's length over the time covered) before it is given up: room for its step
#: sizes to grow.
PACE_MARGIN = 4.0


def _dop853_kernel(io: np.ndarray, tab: None, cfg: np.ndarray) -> None:
    """scipy's DOP853 on the whole batch as one system (margins at the start and the end)."""
    dt, tol = float(cfg[_CF_DT]), float(cfg[_CF_TOLERANCE])
    n = io.shape[1]
    m, r, kappa, e, k, g, c, mu = (io[_ROW[f]] for f in SCENE_FIELDS)
    phi, w, tau = io[_PHI_IN], io[_W_IN], io[_TAU]

    def rhs(_t, y):
        return np.concatenate((y[n:], eq.accel(y[:n], y[n:], tau, m, r, kappa, e, k, g, c)))

    with np.errstate(all="ignore"):
        # scipy's solve_ivp has no step budget: its solver, stepped at most MAX_SUBSTEPS times
        # (past it, the step fails as the compiled schemes' do), and given up early where
        # its pace so far would need PACE_MARGIN times the budget (it runs in Python, about a
        # millisecond a step: the full budget takes minutes)
        solver = DOP853(rhs, 0.0, np.concatenate((phi, w)), dt, rtol=tol, atol=tol)
        taken = 0
        while solver.status == "running" and taken < MAX_SUBSTEPS:
            solver.step()
            taken += 1
            if taken % 1000 == 0 and taken * dt > PACE_MARGIN * MAX_SUBSTEPS * solver.t:
                break
        success = solver.status == "finished"
        y = solver.y if success else np.full(2 * n, np.nan)
        # scipy raises an rtol below 100 ε to 100 ε (and warns): tol is then not what it met
        met = success and tol >= 100.0 * _EPS
        a0 = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi, w, a0, m, r, kappa, e, g)
        lift, slip = eq.margins(normal, friction, m, g, mu)
    for col in range(n):
        _finish_py(io, col, success, float(y[col]), float(y[n + col]), float(tau[col]), taken,
                   float(lift[col]), float(slip[col]), math.nan, met)


_finish_py = _finish  # register_jitable leaves it a Python function too
