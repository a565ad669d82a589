"""What the schemes' kernels share: the compile options, the substep budget and the rounding
rule, the predicted count of substeps, the loops over lanes that evaluate the equations, a
roller's end fields and the writing of its outcome (or its failure) to ``io``, and the loops
that hand chunks of rollers to one core or all (see ``docs/INTEGRATORS.md``, *Batch kernels*).
"""

from __future__ import annotations

import math

import numba
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics import trig
from roller_gym.physics.compiling import inlined
from roller_gym.physics.integrators.layout import (
    _ACC,
    _C,
    _E,
    _ENERGY,
    _ERR,
    _FINITE,
    _FRICTION,
    _G,
    _K,
    _KAPPA,
    _LIFT,
    _M,
    _MU,
    _NORMAL,
    _NSUB,
    _PHI,
    _PHI_IN,
    _RR,
    _SLIP,
    _TOL_MET,
    _W,
    _W_IN,
)

# error_model="numpy": a division by zero gives inf or NaN (reported as a failed step) instead
# of raising, so that the loops have no hidden branch and vectorize.
_jit = numba.njit(cache=True, fastmath=False, nogil=True, error_model="numpy")

# -- the substep rule (the first step-size guess of the adaptive schemes) ------------------------

#: The most substeps one control step may take: the fixed-substep schemes' (the smallest
#: substep is dt / MAX_SUBSTEPS), and the error-controlled schemes' budget (after half as
#: many accepted substeps, the rest of the control step is taken in fewer than as many more,
#: of at least its length over FORCE_REST each, accepted whatever their estimates).
MAX_SUBSTEPS = 200_000
FORCE_AFTER = MAX_SUBSTEPS // 2
FORCE_REST = float(MAX_SUBSTEPS - FORCE_AFTER - 2)  # one spare for a rounded-off end
#: A substep whose error estimate is below ROUNDOFF_FACTOR · ε · max(|φ|, |φ'|) (float64
#: rounding) is accepted even above its share of tol: no smaller substep would do better.
ROUNDOFF_FACTOR = 8.0
_EPS = float(np.finfo(float).eps)


@_jit
def _substeps(speed, m, r, kappa, e, k, g, c, dt, tol, order, constant, stable, sweep_exponent):
    """The predicted substeps (see :func:`predicted_substeps`)."""
    s = 1.0 - r * kappa
    j_min = m * (k * k + (r - e) * (r - e))
    omega = math.sqrt(m * g * (r * r * abs(kappa) / s + e) / j_min)
    sweep = speed / s * (1.0 + (r * e / (k * k + (r - e) * (r - e))) ** sweep_exponent)
    lam = (omega + sweep + c / j_min) * dt
    n = (constant * lam ** (order + 1) / tol) ** (1.0 / order)
    n = max(n, lam / stable)
    if not n < MAX_SUBSTEPS:  # also inf or nan at an absurd speed: the most, not int overflow
        return MAX_SUBSTEPS
    return max(1, math.ceil(n))



@numba.extending.register_jitable
def _finite(x):
    """True where x is finite (a comparison, no call)."""
    return x - x == 0.0


@inlined
def _margins(phi, w, a, m, r, kappa, e, g, mu):
    """(N/(m g), (μN − |F|)/(m g)): the lift-off and slip margins at a state."""
    normal, friction = eq.contact_forces(phi, w, a, m, r, kappa, e, g)
    return eq.margins(normal, friction, m, g, mu)


# The loops over lanes that evaluate the equations: no branch and no call in their bodies (the
# sines are trig's, inlined), so that LLVM runs them in SIMD lanes. They are functions of their
# own so that the inlining stays within a few lines.


@_jit
def _accel_lanes(phi, w, tau, par, na, out):
    """out[i] = φ'' of lane i at (phi[i], w[i]) under tau[i], for lanes 0..na−1."""
    for i in range(na):
        out[i] = eq.accel(phi[i], w[i], tau[i], par[0, i], par[1, i], par[2, i], par[3, i],
                          par[4, i], par[5, i], par[6, i])


@_jit
def _margin_lanes(phi, w, a, par, na, lift, slip):
    """Lower lift[i] and slip[i] to lane i's margins at (phi[i], w[i], a[i]) if smaller."""
    for i in range(na):
        li, si = _margins(phi[i], w[i], a[i], par[0, i], par[1, i], par[2, i], par[3, i],
                          par[5, i], par[7, i])
        lift[i], slip[i] = min(lift[i], li), min(slip[i], si)


@inlined
def _end_fields(phi, w, tau, m, r, kappa, e, k, g, c, mu):
    """(φ'', N, F, E, N/(m g), (μN − |F|)/(m g)) at the end state (no branch)."""
    lhs, d, sin_t, cos_t, sin_psi, cos_psi, _ = eq.accel_terms(phi, w, tau, m, r, kappa, e, k,
                                                               g, c)
    a = lhs / d  # eq.accel; the forces and the energy from its sines and J_I/m
    normal, friction = eq.forces(sin_t, cos_t, sin_psi, cos_psi, w, a, m, r, kappa, e, g)
    energy = eq.energy_at(d, phi, w, m, r, kappa, e, g)
    lift, slip = eq.margins(normal, friction, m, g, mu)
    return a, normal, friction, energy, lift, slip


@numba.extending.register_jitable
def _write(io, col, ok, phi, w, nsub, a, normal, friction, energy, lift, slip, err, tol_met):
    """Write one roller's outputs: the end state's fields, or the failure's (``StepResult``)."""
    ok = ok and math.isfinite(a) and math.isfinite(energy) and math.isfinite(w)
    ok = ok and abs(phi) <= trig.DOMAIN  # (False for NaN) past it, sin φ would be NaN
    io[_NSUB, col] = nsub
    if ok:
        io[_PHI, col], io[_W, col], io[_ACC, col] = phi, w, a
        io[_FINITE, col] = 1.0
        io[_NORMAL, col], io[_FRICTION, col], io[_ENERGY, col] = normal, friction, energy
        io[_LIFT, col], io[_SLIP, col] = lift, slip
        io[_ERR, col], io[_TOL_MET, col] = err, 1.0 if tol_met else 0.0
    else:
        io[_PHI, col], io[_W, col] = io[_PHI_IN, col], io[_W_IN, col]
        io[_FINITE, col], io[_TOL_MET, col] = 0.0, 0.0
        for row in (_ACC, _NORMAL, _FRICTION, _ENERGY, _LIFT, _SLIP, _ERR):
            io[row, col] = math.nan


@numba.extending.register_jitable
def _finish(io, col, ok, phi, w, tau, nsub, lift, slip, err, tol_met):
    """One roller's end fields and outputs (lift, slip: the smallest margins met before)."""
    m, r, kappa, e = io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col]
    k, g, c, mu = io[_K, col], io[_G, col], io[_C, col], io[_MU, col]
    a, normal, friction, energy, lift_end, slip_end = _end_fields(phi, w, tau, m, r, kappa, e,
                                                                  k, g, c, mu)
    _write(io, col, ok, phi, w, nsub, a, normal, friction, energy, min(lift, lift_end),
           min(slip, slip_end), err, tol_met)


@_jit
def _end_lanes(phi, w, tau, par, n, out):
    """_end_fields of lanes 0..n−1 into the rows of ``out`` (lift and slip: the smaller of
    out[4], out[5] and the end's)."""
    for i in range(n):
        a, normal, friction, energy, li, si = _end_fields(
            phi[i], w[i], tau[i], par[0, i], par[1, i], par[2, i], par[3, i], par[4, i],
            par[5, i], par[6, i], par[7, i])
        out[0, i], out[1, i], out[2, i], out[3, i] = a, normal, friction, energy
        out[4, i], out[5, i] = min(out[4, i], li), min(out[5, i], si)


#: Rollers advanced together (each with its own step size) by one task.
CHUNK = 512

_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
#: Attempts (accepted or rejected substeps) after which a roller still running is failed.
_MAX_ATTEMPTS = 4 * MAX_SUBSTEPS


@inlined
def _serial(io, tab, cfg, one, chunk):
    """A batch kernel on one core: ``one`` for a batch of one roller (a Stepper: the same
    arithmetic without lanes), else ``chunk`` over chunks of CHUNK rollers."""
    n = io.shape[1]
    if n == 1:
        one(io, tab, cfg)
        return
    for lo in range(0, n, CHUNK):
        chunk(io, lo, min(lo + CHUNK, n), tab, cfg)


@numba.extending.register_jitable(inline="always")
def _parallel(io, tab, cfg, chunk):
    """A batch kernel on all cores: ``chunk`` over chunks of CHUNK rollers."""
    n = io.shape[1]
    for c in numba.prange((n + CHUNK - 1) // CHUNK):
        lo = c * CHUNK
        chunk(io, lo, min(lo + CHUNK, n), tab, cfg)




#: Batches at least this large are advanced on all cores.
PARALLEL_THRESHOLD = 2048
