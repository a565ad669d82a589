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
    _TAU,
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


@numba.extending.register_jitable
def _rate(speed, m, r, kappa, e, k, g, c, sweep_exponent):
    """λ [1/s], the fastest rate of a roller's motion at |φ'| = ``speed`` [rad/s]: the small
    oscillation's frequency, the sweep of θ = φ/s (weighted by the scene's eccentricity) and
    the damping's rate: the prediction's (:func:`_substeps`)."""
    s = 1.0 - r * kappa
    j_min = m * (k * k + (r - e) * (r - e))
    omega = math.sqrt(m * g * (r * r * abs(kappa) / s + e) / j_min)
    sweep = speed / s * (1.0 + (r * e / (k * k + (r - e) * (r - e))) ** sweep_exponent)
    return omega + sweep + c / j_min


@numba.extending.register_jitable
def _largest_size(speed, r, kappa, jp0, jq0, jp1, jq1, stable):
    """The largest substep [s] an error-controlled Runge–Kutta scheme takes: ``stable`` /
    λ, λ the motion's local rate at the substep's two ends, from the derivatives of φ''
    (∂φ''/∂φ = jp, ∂φ''/∂φ' = jq: the linearized motion's rate, at most √|jp| + |jq|) and
    the turn rate of the fastest angle at |φ'| = ``speed`` [rad/s]
    (:func:`~roller_gym.physics.equations.fastest_turn`); inf at rest."""
    lam = (math.sqrt(max(abs(jp0), abs(jp1))) + max(abs(jq0), abs(jq1))
           + speed * eq.fastest_turn(r, kappa))
    ok = (lam > 0.0) & _finite(lam)
    return trig.select(ok, stable / trig.select(ok, lam, 1.0), math.inf)


@_jit
def _substeps(speed, m, r, kappa, e, k, g, c, dt, tol, order, constant, stable, sweep_exponent):
    """The predicted substeps (see :func:`predicted_substeps`)."""
    lam = _rate(speed, m, r, kappa, e, k, g, c, sweep_exponent) * dt
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
def _accel_jac_lanes(phi, w, tau, par, na, out, dp, dw):
    """:func:`_accel_lanes`, and the derivatives of φ'' into dp[i] (∂/∂φ) and dw[i] (∂/∂φ')."""
    for i in range(na):
        out[i], dp[i], dw[i] = eq.accel_jacobian(phi[i], w[i], tau[i], par[0, i], par[1, i],
                                                 par[2, i], par[3, i], par[4, i], par[5, i],
                                                 par[6, i])


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


@_jit  # as the schemes' one-roller kernels: their flags, so _finish compiles once for both
def at_rest(io, col):
    """One roller's outputs for no step at all (an episode's start): its inputs' own fields,
    as a step ending there writes them (no substeps, no error, the tolerance met)."""
    _finish(io, col, True, io[_PHI_IN, col], io[_W_IN, col], io[_TAU, col], 0.0, math.inf,
            math.inf, 0.0, True)


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


#: Rollers advanced together (each with its own step size) by one task. A scheme's serial
#: batch kernel (``taylor_kernel._taylor_serial``, ``rk._rk_serial``) runs its ``one`` for a
#: batch of one roller (a Stepper: the same arithmetic without lanes), else its ``chunk``
#: over chunks of CHUNK rollers; each scheme writes that loop out, calling its kernels by
#: their global names: through a shared function taking them as arguments, the serial
#: kernel's first compile took twice as long.
CHUNK = 512

_SAFETY, _MIN_FACTOR, _MAX_FACTOR = 0.9, 0.2, 10.0
#: Attempts (accepted or rejected substeps) after which a roller still running is failed.
_MAX_ATTEMPTS = 4 * MAX_SUBSTEPS


@numba.extending.register_jitable
def _swap_lanes(par, i, j):
    """Swap lanes i and j of a chunk's scene rows ``par`` (one row per scene field): how a
    kernel moves a finished roller out of the running lanes."""
    for f in range(par.shape[0]):
        par[f, i], par[f, j] = par[f, j], par[f, i]


@numba.extending.register_jitable(inline="always")
def _parallel(io, tab, cfg, chunk):
    """A batch kernel on all cores: ``chunk`` over chunks of CHUNK rollers."""
    n = io.shape[1]
    for c in numba.prange((n + CHUNK - 1) // CHUNK):
        lo = c * CHUNK
        chunk(io, lo, min(lo + CHUNK, n), tab, cfg)




#: Batches at least this large are advanced on all cores.
PARALLEL_THRESHOLD = 2048


# -- the error carried along a step ---------------------------------------------------------------

#: Times an error-controlled Runge–Kutta step may be taken again with a smaller share of tol
#: when its propagated estimate passes ``propagated_limit · tolerance``.
RETRIES = 2


@numba.extending.register_jitable
def _propagate(s00, s01, s10, s11, h, p0, q0, p1, q1, ep, ew):
    """The accepted substeps' error estimates carried to the end of one more of size h [s]:
    S ← M S + diag(ep, ew), with M = (I − h A1/2)⁻¹ (I + h A0/2) the trapezoidal rule's map
    of the linearized motion over it, A = [[0, 1], [p, q]] from
    :func:`~roller_gym.physics.equations.accel_jacobian` at its start (p0, q0) and end
    (p1, q1). Where the substep is too long for the rule (the determinant of I − h A1/2
    below 1/2), S is inf: the estimate is not trusted."""
    a01, a10, a11 = -0.5 * h, -0.5 * h * p1, 1.0 - 0.5 * h * q1  # I − h A1/2 (a00 = 1)
    det = a11 - a01 * a10
    b01, b10, b11 = 0.5 * h, 0.5 * h * p0, 1.0 + 0.5 * h * q0  # I + h A0/2 (b00 = 1)
    inv = 1.0 / trig.select(det >= 0.5, det, 1.0)
    m00, m01 = (a11 - a01 * b10) * inv, (a11 * b01 - a01 * b11) * inv
    m10, m11 = (b10 - a10) * inv, (b11 - a10 * b01) * inv
    bad = trig.select(det >= 0.5, 0.0, math.inf)
    return (m00 * s00 + m01 * s10 + ep + bad, m00 * s01 + m01 * s11,
            m10 * s00 + m11 * s10, m10 * s01 + m11 * s11 + ew + bad)


@numba.extending.register_jitable
def _propagated(s00, s01, s10, s11):
    """The propagated estimate [rad or rad/s]: the largest row sum of |S| (the error in φ or
    φ' that the substeps' estimates, each at its own substep, grow into by the end; inf where
    not finite)."""
    r0, r1 = abs(s00) + abs(s01), abs(s10) + abs(s11)
    return trig.select((r0 - r0 == 0.0) & (r1 - r1 == 0.0), max(r0, r1), math.inf)


@numba.extending.register_jitable
def _again(status, fixed, g, limit, retries, hforce, count, order):
    """True if a step that has just ended is to be taken again: error-controlled, not forced
    to its end, its propagated estimate g above ``limit`` (or not finite), retries left, and
    room for the retry before substeps are forced (forced substeps could end it further off
    than this pass): its ``count`` substeps so far plus twice as many again as the smaller
    share asks for at the scheme's ``order`` (count · (g / (limit/2))^(1/order)) at most
    FORCE_AFTER."""
    growth = (2.0 * g / limit) ** (1.0 / order)
    room = count + 2.0 * count * growth <= FORCE_AFTER
    return ((status == 1.0) & (not fixed) & (not g <= limit) & (retries < RETRIES)
            & (hforce == 0.0) & room)


@numba.extending.register_jitable
def _smaller_share(share, g, limit):
    """The share of tol a step taken again aims at: enough smaller that its propagated
    estimate lands near half the limit (at least halved; local errors scale with the share)."""
    return share * min(0.5, 0.5 * limit / g) if g - g == 0.0 else share * 0.01
