"""The reference scheme ``dop853``: scipy's ``solve_ivp(method="DOP853")`` on a whole batch
as one system, its outcome written to ``io`` as the compiled kernels write theirs (slow: for
checking the others).
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
from roller_gym.physics.integrators.rules import _EPS, _finish
from scipy.integrate import solve_ivp


def _dop853_kernel(io: np.ndarray, tab: None, cfg: np.ndarray) -> None:
    """scipy's DOP853 on the whole batch as one system (margins at the start and the end)."""
    dt, tol = float(cfg[_CF_DT]), float(cfg[_CF_TOLERANCE])
    n = io.shape[1]
    m, r, kappa, e, k, g, c, mu = (io[_ROW[f]] for f in SCENE_FIELDS)
    phi, w, tau = io[_PHI_IN], io[_W_IN], io[_TAU]

    def rhs(_t, y):
        return np.concatenate((y[n:], eq.accel(y[:n], y[n:], tau, m, r, kappa, e, k, g, c)))

    with np.errstate(all="ignore"):
        sol = solve_ivp(rhs, (0.0, dt), np.concatenate((phi, w)), method="DOP853", rtol=tol,
                        atol=tol)
        y = sol.y[:, -1] if sol.success else np.full(2 * n, np.nan)
        # scipy raises an rtol below 100 ε to 100 ε (and warns): tol is then not what it met
        met = bool(sol.success) and tol >= 100.0 * _EPS
        a0 = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi, w, a0, m, r, kappa, e, g)
        lift, slip = eq.margins(normal, friction, m, g, mu)
    for col in range(n):
        _finish_py(io, col, bool(sol.success), float(y[col]), float(y[n + col]),
                   float(tau[col]), sol.t.size - 1, float(lift[col]), float(slip[col]),
                   math.nan, met)


_finish_py = _finish  # register_jitable leaves it a Python function too
