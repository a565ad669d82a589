"""The reference scheme ``dop853``: scipy's DOP853 (as ``solve_ivp(method="DOP853")`` runs it,
at most MAX_SUBSTEPS steps) on a whole batch as one system, checked by a second run at a
tighter tolerance, its outcome written to ``io`` as the compiled kernels write theirs (slow:
for checking the others).
"""

from __future__ import annotations

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


#: The tolerance of the second, reference run of a dop853 step, against the step's: the
#: step's tolerance counts as met where the two runs agree within it. scipy's error control is
#: local and relative to its own norm; this checks the step itself.
CHECK_FACTOR = 1e-3


def _dop853_kernel(io: np.ndarray, tab: None, cfg: np.ndarray) -> None:
    """scipy's DOP853 on the whole batch as one system (margins at the start and the end),
    checked against a second run at CHECK_FACTOR times the tolerance: each roller's
    ``error_estimate`` is the larger difference of φ and φ' between the two, and ``tol_met``
    holds where it is within the tolerance (never where the second run cannot be tighter
    than a tenth of it: scipy raises an rtol below 100 ε to 100 ε)."""
    dt, tol = float(cfg[_CF_DT]), float(cfg[_CF_TOLERANCE])
    n = io.shape[1]
    m, r, kappa, e, k, g, c, mu = (io[_ROW[f]] for f in SCENE_FIELDS)
    phi, w, tau = io[_PHI_IN], io[_W_IN], io[_TAU]

    def rhs(_t, y):
        return np.concatenate((y[n:], eq.accel(y[:n], y[n:], tau, m, r, kappa, e, k, g, c)))

    def solve(rtol: float) -> tuple[bool, np.ndarray, int]:
        # scipy's solve_ivp has no step budget: its solver, stepped at most MAX_SUBSTEPS times
        # (past it, the step fails as the compiled schemes' do), and given up early where
        # its pace so far would need PACE_MARGIN times the budget (it runs in Python, about a
        # millisecond a step: the full budget takes minutes)
        solver = DOP853(rhs, 0.0, np.concatenate((phi, w)), dt, rtol=rtol, atol=rtol)
        taken = 0
        while solver.status == "running" and taken < MAX_SUBSTEPS:
            solver.step()
            taken += 1
            if taken % 1000 == 0 and taken * dt > PACE_MARGIN * MAX_SUBSTEPS * solver.t:
                break
        success = solver.status == "finished"
        return success, solver.y if success else np.full(2 * n, np.nan), taken

    with np.errstate(all="ignore"):
        success, y, taken = solve(tol)
        estimate = np.full(n, np.nan)
        check_tol = max(CHECK_FACTOR * tol, 100.0 * _EPS)
        if success and check_tol <= 0.1 * tol:
            checked, y_ref, _ = solve(check_tol)
            if checked:
                estimate = np.maximum(np.abs(y[:n] - y_ref[:n]), np.abs(y[n:] - y_ref[n:]))
        met = estimate <= tol  # (False where NaN: not checked)
        a0 = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi, w, a0, m, r, kappa, e, g)
        lift, slip = eq.margins(normal, friction, m, g, mu)
    for col in range(n):
        _finish_py(io, col, success, float(y[col]), float(y[n + col]), float(tau[col]), taken,
                   float(lift[col]), float(slip[col]), float(estimate[col]), bool(met[col]))


_finish_py = _finish  # register_jitable leaves it a Python function too
