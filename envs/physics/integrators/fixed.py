"""The fixed-substep schemes (``euler``: semi-implicit Euler; ``midpoint``: implicit midpoint
on (φ, J_I φ')): each a substep function and a kernel, the shared loop :func:`_fixed_steps`
around it, which takes n equal substeps (n given, or predicted from the scene and the speed)
and checks the result against the same step in half as many (Richardson's estimate).
"""

from __future__ import annotations

import math

import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics.compiling import inlined
from roller_gym.physics.integrators.layout import (
    _C,
    _CF_CONSTANT,
    _CF_DT,
    _CF_ORDER,
    _CF_STABLE,
    _CF_SUBSTEPS,
    _CF_SWEEP,
    _CF_TOLERANCE,
    _E,
    _G,
    _K,
    _KAPPA,
    _M,
    _MU,
    _PHI_IN,
    _RR,
    _TAU,
    _W_IN,
)
from roller_gym.physics.integrators.rules import (
    MAX_SUBSTEPS,
    _finish,
    _jit,
    _margins,
    _substeps,
)


@_jit
def _euler_substep(phi, w, tau, m, r, kappa, e, k, g, c, h):
    """Semi-implicit Euler: φ' first, then φ with the new φ'."""
    w = w + h * eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
    return phi + h * w, w


@_jit
def _midpoint_substep(phi, w, tau, m, r, kappa, e, k, g, c, h):
    """One implicit-midpoint step on (φ, p = J_I φ'); Newton's method on the midpoint."""
    p0 = eq.inertia(phi, m, r, kappa, e, k) * w
    pm_phi, pm_p = phi + 0.5 * h * w, p0  # initial guess
    converged = False
    for _ in range(50):
        j = eq.inertia(pm_phi, m, r, kappa, e, k)
        jp = eq.dinertia(pm_phi, m, r, kappa, e)
        jpp = eq.d2inertia(pm_phi, m, r, kappa, e)
        f1 = pm_p / j
        f2 = pm_p * pm_p * jp / (2.0 * j * j) - eq.dpotential(pm_phi, m, r, kappa, e, g)
        f2 += tau - c * pm_p / j
        g1 = pm_phi - phi - 0.5 * h * f1
        g2 = pm_p - p0 - 0.5 * h * f2
        d11 = 1.0 + 0.5 * h * pm_p * jp / (j * j)
        d12 = -0.5 * h / j
        df2 = pm_p * pm_p * (jpp / (2.0 * j * j) - jp * jp / (j * j * j))
        df2 += -eq.d2potential(pm_phi, m, r, kappa, e, g) + c * pm_p * jp / (j * j)
        d21 = -0.5 * h * df2
        d22 = 1.0 - 0.5 * h * (pm_p * jp / (j * j) - c / j)
        det = d11 * d22 - d12 * d21
        dphi = (g1 * d22 - g2 * d12) / det
        dp = (g2 * d11 - g1 * d21) / det
        pm_phi -= dphi
        pm_p -= dp
        if abs(dphi) <= 1e-15 * (1.0 + abs(pm_phi)) and abs(dp) <= 1e-15 * (1.0 + abs(pm_p)):
            converged = True
            break
    if not converged:  # no midpoint solution found from here: non-finite, so the step splits
        return math.nan, math.nan
    phi1 = 2.0 * pm_phi - phi
    return phi1, (2.0 * pm_p - p0) / eq.inertia(phi1, m, r, kappa, e, k)


# -- the fixed-substep kernel ------------------------------------------------------------------


@inlined
def _fixed_steps(io, cfg, substep):
    """The loop of a fixed-substep scheme around its ``substep`` function: each roller on its
    own, n equal substeps."""
    dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOLERANCE], int(cfg[_CF_SUBSTEPS])
    for col in range(io.shape[1]):
        m, r, kappa, e = io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col]
        k, g, c, mu = io[_K, col], io[_G, col], io[_C, col], io[_MU, col]
        phi0, w0, tau = io[_PHI_IN, col], io[_W_IN, col], io[_TAU, col]
        n = nfixed if nfixed > 0 else _substeps(abs(w0), m, r, kappa, e, k, g, c, dt, tol,
                                               cfg[_CF_ORDER], cfg[_CF_CONSTANT],
                                               cfg[_CF_STABLE], cfg[_CF_SWEEP])
        phi, w, needed = phi0, w0, n
        lift, slip = np.inf, np.inf
        for _attempt in range(20):
            h = dt / n
            phi, w, top = phi0, w0, abs(w0)
            lift, slip = np.inf, np.inf
            for _ in range(n):
                a = eq.accel(phi, w, tau, m, r, kappa, e, k, g, c)
                li, si = _margins(phi, w, a, m, r, kappa, e, g, mu)
                lift, slip = min(lift, li), min(slip, si)
                phi, w = substep(phi, w, tau, m, r, kappa, e, k, g, c, h)
                if not (math.isfinite(phi) and math.isfinite(w)):
                    break
                top = max(top, abs(w))
            finite = math.isfinite(phi) and math.isfinite(w)
            if not finite and n >= MAX_SUBSTEPS:
                needed = 2 * n
                break
            needed = (_substeps(top, m, r, kappa, e, k, g, c, dt, tol, cfg[_CF_ORDER],
                                cfg[_CF_CONSTANT], cfg[_CF_STABLE], cfg[_CF_SWEEP])
                      if finite else 2 * n)
            if nfixed > 0 or needed <= n or _attempt == 19:  # fixed: the prediction judges
                break
            n = min(needed, MAX_SUBSTEPS)
        # the tolerance is met where the prediction says so (the substeps taken, n, are as
        # many as it asks for over the speeds met, fixed ones too, and it asked for fewer
        # than MAX_SUBSTEPS, its cap: "at least that many") and a check confirms it: the
        # same step in v = n/2 substeps (2 for n = 1) gives Richardson's estimate of the
        # error of the n-substep result, |y_n − y_v| / |1 − (n/v)^order| (the prediction
        # alone undercounted on stiff scenes, g = 1e6: 37× tol)
        err = math.nan
        predicted = needed <= n and needed < MAX_SUBSTEPS
        if predicted and math.isfinite(phi) and math.isfinite(w):
            v = n // 2 if n >= 2 else 2
            phi_v, w_v = phi0, w0
            for _ in range(v):
                phi_v, w_v = substep(phi_v, w_v, tau, m, r, kappa, e, k, g, c, dt / v)
            err = (max(abs(phi - phi_v), abs(w - w_v))
                   / abs(1.0 - (n / v) ** cfg[_CF_ORDER]))
        _finish(io, col, True, phi, w, tau, n, lift, slip, err, predicted and err <= tol)


# Each fixed-substep scheme's kernel: the shared loop around its substep function. A function
# of its own per scheme, so that numba caches it on disk (a kernel made by a factory closes
# over its substep, and numba cannot cache such closures).
@_jit
def _euler_kernel(io, tab, cfg):
    _fixed_steps(io, cfg, _euler_substep)


@_jit
def _midpoint_kernel(io, tab, cfg):
    _fixed_steps(io, cfg, _midpoint_substep)
