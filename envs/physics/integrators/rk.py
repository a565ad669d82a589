"""The explicit Runge–Kutta pairs (``rk8``: Dormand–Prince 8(5,3); ``rk4``: Bogacki–Shampine
5(4), classical RK4 with fixed substeps): their coefficients (:func:`_tableau`), one
roller's accept/reject rule and next size (:func:`_judge`, :func:`_tick`), and the kernels
that run any pair: a chunk of rollers in SIMD lanes (:func:`_rk_chunk`) and one roller
(:func:`_rk_one`, the same arithmetic in the same order), on one core or all.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics import trig
from roller_gym.physics.integrators.layout import (
    _C,
    _CF_CONSTANT,
    _CF_DT,
    _CF_HALVINGS,
    _CF_ORDER,
    _CF_PROPAGATED,
    _CF_SHARE,
    _CF_STABLE,
    _CF_SUBSTEPS,
    _CF_SWEEP,
    _CF_TOLERANCE,
    _E,
    _G,
    _H_NEXT,
    _K,
    _KAPPA,
    _M,
    _MU,
    _PAD,
    _PHI_IN,
    _RR,
    _TAU,
    _W_IN,
    SCENE_FIELDS,
)
from roller_gym.physics.integrators.rules import (
    _EPS,
    _MAX_ATTEMPTS,
    _MAX_FACTOR,
    _MIN_FACTOR,
    _SAFETY,
    CHUNK,
    FORCE_AFTER,
    FORCE_REST,
    ROUNDOFF_FACTOR,
    _accel_jac_lanes,
    _accel_lanes,
    _again,
    _end_lanes,
    _finish,
    _finite,
    _jit,
    _largest_size,
    _margin_lanes,
    _margins,
    _parallel,
    _propagate,
    _propagated,
    _smaller_share,
    _substeps,
    _swap_lanes,
    _write,
)
from roller_gym.physics.integrators.taylor_kernel import (
    _checks,
    _taylor_check,
    _taylor_check_one,
)
from scipy.integrate._ivp import dop853_coefficients


def _tableau(a: np.ndarray, b: np.ndarray, e3: np.ndarray, e5: np.ndarray) -> np.ndarray:
    """An explicit Runge–Kutta pair as one array of shape (s + 3, s + 1): rows 0..s−1 the
    matrix A, row s the weights b, rows s + 1 and s + 2 the error weights E3 and E5 over the s
    stages and the stage f(y_new) (E3 = 0: a single estimator E5)."""
    s = b.shape[0]
    out = np.zeros((s + 3, s + 1))
    out[:s, :s] = a[:s, :s]
    out[s, :s] = b
    out[s + 1] = e3
    out[s + 2] = e5
    return out


_N8 = dop853_coefficients.N_STAGES
_DOP853 = _tableau(dop853_coefficients.A, dop853_coefficients.B, dop853_coefficients.E3,
                   dop853_coefficients.E5)
_RK4 = _tableau(  # classical RK4: rk4 with fixed substeps (their reported error_estimate)
    np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1.0, 0]]),
    np.array([1 / 6, 1 / 3, 1 / 3, 1 / 6]),
    np.zeros(5),
    np.array([0, 0, 0, 1 / 6, -1 / 6]),  # RK4 − the embedded 3rd-order (1/6, 1/3, 1/3, 0, 1/6)
)


#: Bogacki–Shampine 5(4) (P. Bogacki and L. F. Shampine, "An efficient Runge–Kutta (4,5)
#: pair", Comput. Math. Appl. 32(6) (1996) 15–28; the paper's rational coefficients, each
#: rounded once to float64 by Python's division): rk4 under error control. Eight stages, the
#: last the first of the next substep (7 evaluations a substep); the 5th-order solution
#: (weights b) is carried on and E = b̂ − b estimates the error of the embedded 4th-order one
#: (weights b̂, over all eight stages). Why this pair: ``docs/INTEGRATORS.md``.
_BS5 = _tableau(
    np.array([
        [0, 0, 0, 0, 0, 0, 0],
        [1 / 6, 0, 0, 0, 0, 0, 0],
        [2 / 27, 4 / 27, 0, 0, 0, 0, 0],
        [183 / 1372, -162 / 343, 1053 / 1372, 0, 0, 0, 0],
        [68 / 297, -4 / 11, 42 / 143, 1960 / 3861, 0, 0, 0],
        [597 / 22528, 81 / 352, 63099 / 585728, 58653 / 366080, 4617 / 20480, 0, 0],
        [174197 / 959244, -30942 / 79937, 8152137 / 19744439, 666106 / 1039181,
         -29421 / 29068, 482048 / 414219, 0],
    ]),
    np.array([587 / 8064, 0, 4440339 / 15491840, 24353 / 124800, 387 / 44800, 2152 / 5985,
              7267 / 94080]),
    np.zeros(8),
    np.array([-3817 / 1959552, 0, 140181 / 15491840, -4224731 / 272937600, 8557 / 403200,
              -57928 / 4363065, -23930231 / 4366535040, 3293 / 556956]),
)


#: The largest error of the embedded 3rd-order solution (|h E3·K|, rad or rad/s) at which a
#: DOP853 substep is judged by its blended estimate: that estimate (the 5th-order one times
#: its ratio to the 3rd-order one) assumes both in their asymptotic range, and past this it
#: was measured to miss the error 60-fold. A larger one is rejected and at least halved.
E3_LIMIT = 1e-2
#: With fixed substeps (``substeps=n``), the share of the largest error-controlled substep
#: (:func:`~roller_gym.physics.integrators.rules._largest_size`) up to which a substep's
#: estimate is trusted: a step with a longer one reports tol_met False. At the full size,
#: classical RK4's estimate (against its embedded 3rd order) missed the error 650-fold on the
#: paper scene (one substep of 0.05 s at 7.4 rad/s).
FIXED_TRUSTED = 0.5


@numba.extending.register_jitable
def _first_size(io, col, phi_dot, dt, tol, nfixed, cfg):
    """The size [s] a roller's first substep wants: the fixed one; else where the last step's
    controller left off, split even over what is left; else the prediction."""
    if nfixed > 0:
        return dt / nfixed
    if io[_H_NEXT, col] > 0.0:
        return dt / math.ceil(dt / io[_H_NEXT, col] * (1.0 - 1e-9))
    guess = _substeps(abs(phi_dot), io[_M, col], io[_RR, col], io[_KAPPA, col], io[_E, col],
                      io[_K, col], io[_G, col], io[_C, col], dt, tol, cfg[_CF_ORDER],
                      cfg[_CF_CONSTANT], cfg[_CF_STABLE], cfg[_CF_SWEEP])
    return dt / guess


@numba.extending.register_jitable
def _attempt_size(fixed, nfixed, hdes, count, t, dt):
    """(h [s], last): the size of a roller's next attempt, and 1.0 if it would end the step."""
    if fixed:
        return hdes, 1.0 if count + 1 >= nfixed else 0.0
    rest = dt - t
    return min(hdes, rest), 1.0 if hdes >= rest else 0.0


@numba.extending.register_jitable
def _blend(h, e5, e3):
    """A substep's error estimate of one component (φ or φ'), scipy's DOP853 form:
    h E5² / sqrt(E5² + 0.01 E3²) from its error sums E5·K and E3·K (E3 = 0: |h E5·K|)."""
    d = e5 * e5 + 0.01 * e3 * e3
    return h * e5 * e5 / math.sqrt(trig.select(d > 0.0, d, 1.0))


@numba.extending.register_jitable
def _estimates(h, e5p, e5w, e3p, e3w):
    """(φ's estimate, φ''s estimate, the 3rd-order estimate max |h E3·K|) of an attempt of
    size h from its error sums: what :func:`_judge` decides on."""
    return _blend(h, e5p, e3p), _blend(h, e5w, e3w), h * max(abs(e3p), abs(e3w))


@numba.extending.register_jitable
def _judge(h, ep, ew, e3, phi, w, phin, wn, a_new, count, hforce, t, hdes, rejected, last,
           status, dt, share, fixed, halvings, hmax):
    """Accept or reject one roller's attempt of size h, from its estimates
    (:func:`_estimates`), and the size of its next, at most ``hmax`` [s] (the scheme's
    largest at the speed reached, :func:`~roller_gym.physics.integrators.rules._largest_size`:
    past it the embedded estimate was measured to miss the error 16-fold): selects only, no
    branch.

    Returns (accepted, the next size [s], the roller's status, hforce); its error estimate is
    max(ep, ew).
    """
    err = max(ep, ew)
    # past E3_LIMIT the blend is not trusted (E3 = 0: never)
    wide = (e3 > E3_LIMIT) & (not fixed)
    fin = _finite(phin) & _finite(wn) & _finite(a_new) & _finite(err)
    # past FORCE_AFTER accepted substeps, the rest in fewer than as many more
    start = (count == FORCE_AFTER) & (hforce == 0.0)
    hforce = trig.select(start, (dt - t) / FORCE_REST, hforce)
    floor = max(1e-12 * dt, hforce)
    # the error a substep aims at: its share of tol, or float64's rounding of the state if
    # that is larger (a smaller substep would only add rounding)
    big = max(max(abs(phi), abs(w)), max(abs(phin), abs(wn)))
    aim = max(share * h / dt, _EPS * big)
    ratio = trig.select(aim > 0.0, err / trig.select(aim > 0.0, aim, 1.0), 0.0)
    # an estimate at the level of float64 rounding is accepted: no smaller substep does better
    # (a non-finite trial never is: it is rejected and shrunk, failing only at the floor)
    forced = (h <= floor) | (fin & (err <= ROUNDOFF_FACTOR * _EPS * big) & (not wide))
    accept = trig.select(fixed, fin, fin & (((ratio <= 1.0) & (not wide)) | forced))
    fail = (not fin) & (fixed | forced)
    ends = accept & (last != 0.0)
    status = trig.select(ends, 1.0, trig.select(fail, 2.0, status))
    # the next size: h · clip(0.9 ratio^(−1/order), 0.2, 10), the root as square roots
    q = math.sqrt(math.sqrt(ratio))
    q = trig.select(halvings >= 3, math.sqrt(q), q)
    factor = min(_MAX_FACTOR, max(_MIN_FACTOR, _SAFETY / q))  # ratio 0: the largest
    factor = trig.select(fin, factor, _MIN_FACTOR)
    factor = trig.select(rejected != 0.0, min(factor, 1.0), factor)
    factor = trig.select(wide, min(factor, 0.5), factor)
    h_new = trig.select(fixed, hdes, max(min(h * factor, hmax), floor))
    return accept, h_new, status, hforce


@numba.extending.register_jitable
def _tick(accept, last, t, h, count, err_sum, err, hwant, h_new, carry, dt):
    """A roller's clock [s], accepted count, error sum, rejected flag and carried size [s]
    after an attempt of size h (the size carried on is the size wanted, not the last one cut
    short at dt)."""
    ends = accept & (last != 0.0)
    t = trig.select(ends, dt, trig.select(accept, t + h, t))
    taken = trig.select(accept, 1.0, 0.0)
    return (t, count + taken, err_sum + trig.select(accept, err, 0.0), 1.0 - taken,
            trig.select(ends, max(hwant, h_new), carry))


@_jit
def _rk_chunk(io, lo, hi, tab, cfg):
    """Advance rollers (columns) lo..hi−1 of ``io`` over one control step.

    ``tab``: the pair (see :func:`_tableau`); ``cfg``: the stepper's settings
    (:data:`CFG_FIELDS`).
    """
    n = hi - lo
    s = tab.shape[0] - 3
    dt, tol = cfg[_CF_DT], cfg[_CF_TOLERANCE]
    nfixed, halvings = int(cfg[_CF_SUBSTEPS]), int(cfg[_CF_HALVINGS])
    share = tol * cfg[_CF_SHARE]  # the error the accepted substeps' estimates may add up to
    limit = tol * cfg[_CF_PROPAGATED]  # the error they may grow into by the step's end
    order = cfg[_CF_ORDER]
    stable = cfg[_CF_STABLE]
    fixed = nfixed > 0
    # one scratch block: the stages, then one row per per-roller quantity
    nf = len(SCENE_FIELDS)
    scratch = np.empty((2 * (s + 1) + nf + 43, n + _PAD))
    kp = scratch[: s + 1]  # stage velocities φ'
    kw = scratch[s + 1: 2 * (s + 1)]  # stage accelerations φ''
    par = scratch[2 * (s + 1): 2 * (s + 1) + nf]
    rows = scratch[2 * (s + 1) + nf:]
    acc_p, acc_w, e5p, e5w, e3p, e3w = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
    tau, phi, w, hh, hdes, t = rows[6], rows[7], rows[8], rows[9], rows[10], rows[11]
    phin, wn, lift, slip, err_sum = rows[12], rows[13], rows[14], rows[15], rows[16]
    hforce, count, last = rows[17], rows[18], rows[19]
    status = rows[20]  # 0 running, 1 done, 2 failed
    rejected = rows[21]  # 0 or 1
    slot = rows[22]  # the roller (column lo + slot) whose numbers are in this lane
    hwant, carry = rows[29], rows[30]  # the size wanted this attempt; the size carried on
    # the propagated estimate S (2 × 2), ∂φ''/∂φ and ∂φ''/∂φ' at the substep's start and end,
    # the roller's share of tol and its retries
    s00, s01, s10, s11 = rows[31], rows[32], rows[33], rows[34]
    jp0, jq0, jp1, jq1 = rows[35], rows[36], rows[37], rows[38]
    lshare, retries = rows[39], rows[40]  # (lshare: the share this pass aims at)
    hmax = rows[41]  # the largest next substep at the speed reached
    beyond = rows[42]  # 1.0 once a fixed substep was past FIXED_TRUSTED of that
    for i in range(n):
        hforce[i], count[i], status[i], rejected[i], slot[i] = 0.0, 0.0, 0.0, 0.0, i
        carry[i], lshare[i], retries[i], beyond[i] = 0.0, share, 0.0, 0.0
        s00[i], s01[i], s10[i], s11[i] = 0.0, 0.0, 0.0, 0.0
    # The running rollers are kept in lanes 0..na−1 (a finished one swaps places with the last
    # running one), so every per-lane loop runs over contiguous lanes.
    na = n
    for i in range(n):
        col = lo + i
        for f in range(len(SCENE_FIELDS)):
            par[f, i] = io[f, col]
        tau[i] = io[_TAU, col]
        phi[i], w[i] = io[_PHI_IN, col], io[_W_IN, col]
        kp[0, i] = w[i]
        t[i], lift[i], slip[i], err_sum[i] = 0.0, np.inf, np.inf, 0.0
        hdes[i] = _first_size(io, col, w[i], dt, tol, nfixed, cfg)
    _accel_jac_lanes(phi, w, tau, par, n, kw[0], jp0, jq0)
    for _attempt in range(_MAX_ATTEMPTS):
        if na == 0:
            break
        # this attempt's sizes, and the margins at the start of the substep
        for i in range(na):
            hh[i], last[i] = _attempt_size(fixed, nfixed, hdes[i], count[i], t[i], dt)
            hwant[i] = hdes[i]
        _margin_lanes(phi, w, kw[0], par, na, lift, slip)
        # the stages
        for st in range(1, s + 1):
            for i in range(na):
                acc_p[i], acc_w[i] = 0.0, 0.0
            for j in range(st):
                a = tab[st, j]
                if a != 0.0:
                    for i in range(na):
                        acc_p[i] += a * kp[j, i]
                        acc_w[i] += a * kw[j, i]
            for i in range(na):
                phin[i] = phi[i] + hh[i] * acc_p[i]
                kp[st, i] = w[i] + hh[i] * acc_w[i]
            if st < s:
                _accel_lanes(phin, kp[st], tau, par, na, kw[st])
            else:  # the new state: its derivatives too
                _accel_jac_lanes(phin, kp[st], tau, par, na, kw[st], jp1, jq1)
        # the last stage's weights are b: its state is the new state
        for i in range(na):
            wn[i] = kp[s, i]
        # the error sums
        for i in range(na):
            e5p[i], e5w[i], e3p[i], e3w[i] = 0.0, 0.0, 0.0, 0.0
        for j in range(s + 1):
            a3, a5 = tab[s + 1, j], tab[s + 2, j]
            for i in range(na):
                e3p[i] += a3 * kp[j, i]
                e3w[i] += a3 * kw[j, i]
                e5p[i] += a5 * kp[j, i]
                e5w[i] += a5 * kw[j, i]
        # Accept or reject, and the next size, per roller: selects only, in loops that each
        # touch few rows, so that LLVM can vectorize them (it gives up on a loop whose rows it
        # would have to check pairwise for overlap too many times). The estimates replace the
        # error sums in their rows, the next size the 3rd-order estimate's.
        ep, ew, e3, accepted = e5p, e5w, e3p, acc_p  # (acc_p: free until the next attempt)
        for i in range(na):
            ep[i], ew[i], e3[i] = _estimates(hh[i], e5p[i], e5w[i], e3p[i], e3w[i])
        for i in range(na):
            hmax[i] = _largest_size(max(abs(w[i]), abs(wn[i])), par[1, i], par[2, i], jp0[i],
                                    jq0[i], jp1[i], jq1[i], stable)
        for i in range(na):
            accept, e3[i], status[i], hforce[i] = _judge(
                hh[i], ep[i], ew[i], e3[i], phi[i], w[i], phin[i], wn[i], kw[s, i], count[i],
                hforce[i], t[i], hdes[i], rejected[i], last[i], status[i], dt, lshare[i],
                fixed, halvings, hmax[i])
            accepted[i] = trig.select(accept, 1.0, 0.0)
            long = fixed & accept & (hh[i] > FIXED_TRUSTED * hmax[i])
            beyond[i] = trig.select(long, 1.0, beyond[i])
        h_new = e3
        for i in range(na):  # the accepted estimates carried to the new state
            accept = accepted[i] != 0.0
            n00, n01, n10, n11 = _propagate(s00[i], s01[i], s10[i], s11[i], hh[i], jp0[i],
                                            jq0[i], jp1[i], jq1[i], ep[i], ew[i])
            s00[i] = trig.select(accept, n00, s00[i])
            s01[i] = trig.select(accept, n01, s01[i])
            s10[i] = trig.select(accept, n10, s10[i])
            s11[i] = trig.select(accept, n11, s11[i])
            jp0[i] = trig.select(accept, jp1[i], jp0[i])
            jq0[i] = trig.select(accept, jq1[i], jq0[i])
        for i in range(na):  # the state of the accepted
            accept = accepted[i] != 0.0
            phi[i] = trig.select(accept, phin[i], phi[i])
            w[i] = trig.select(accept, wn[i], w[i])
            kp[0, i] = trig.select(accept, kp[s, i], kp[0, i])
            kw[0, i] = trig.select(accept, kw[s, i], kw[0, i])
        for i in range(na):  # the clocks and counts
            t[i], count[i], err_sum[i], rejected[i], carry[i] = _tick(
                accepted[i] != 0.0, last[i], t[i], hh[i], count[i], err_sum[i],
                max(ep[i], ew[i]), hwant[i], h_new[i], carry[i], dt)
            hdes[i] = h_new[i]
        for i in range(na):  # a step whose estimates grew past the limit: again, aiming lower
            g = _propagated(s00[i], s01[i], s10[i], s11[i])
            if _again(status[i], fixed, g, limit, retries[i], hforce[i], count[i], order):
                col = lo + int(slot[i])
                phi[i], w[i] = io[_PHI_IN, col], io[_W_IN, col]
                kp[0, i] = w[i]
                kw[0, i], jp0[i], jq0[i] = eq.accel_jacobian(
                    phi[i], w[i], tau[i], par[0, i], par[1, i], par[2, i], par[3, i],
                    par[4, i], par[5, i], par[6, i])
                t[i], err_sum[i], status[i], rejected[i], carry[i] = 0.0, 0.0, 0.0, 0.0, 0.0
                s00[i], s01[i], s10[i], s11[i] = 0.0, 0.0, 0.0, 0.0
                lshare[i] = _smaller_share(lshare[i], g, limit)
                retries[i] += 1.0
                hdes[i] = _first_size(io, col, w[i], dt, tol, nfixed, cfg)
        i = 0
        while i < na:
            if status[i] != 0.0:
                na -= 1
                _swap_lanes(par, i, na)
                for x in (kp[0], kw[0], tau, phi, w, hdes, t, lift, slip, err_sum, hforce, count,
                          status, rejected, slot, carry, s00, s01, s10, s11, jp0, jq0, lshare,
                          retries, beyond):  # what outlives an attempt
                    x[i], x[na] = x[na], x[i]
            else:
                i += 1
    # the end states' fields, all lanes at once, then each roller's outputs to its column
    end = rows[23:29]
    for i in range(n):  # (a loop: a slice assignment compiles numba's shape-mismatch message)
        end[4, i], end[5, i] = lift[i], slip[i]
    _end_lanes(phi, w, tau, par, n, end)
    met, estimate = rows[2], rows[3]  # (e5p, e5w: free now)
    for i in range(n):
        g = _propagated(s00[i], s01[i], s10[i], s11[i])
        ok = (err_sum[i] <= share) & (g <= limit) & (beyond[i] == 0.0)
        met[i], estimate[i] = trig.select(ok, 1.0, 0.0), max(err_sum[i], g)
    _taylor_check(io, lo, slot, par, tau, phi, w, count, met, estimate, n, dt, tol, 0)
    for i in range(n):
        io[_H_NEXT, lo + int(slot[i])] = 0.0 if fixed or status[i] != 1.0 else carry[i]
        _write(io, lo + int(slot[i]), status[i] == 1.0, phi[i], w[i], count[i], end[0, i],
               end[1, i], end[2, i], end[3, i], end[4, i], end[5, i], estimate[i], met[i] != 0.0)


@_jit
def _rk_one(io, tab, cfg):
    """One roller (column 0 of ``io``) over one control step: :func:`_rk_chunk`'s arithmetic
    in the same order, without its lanes (bit for bit the same result, at a fraction of the
    latency). What :class:`Stepper` runs."""
    s = tab.shape[0] - 3
    dt, tol = cfg[_CF_DT], cfg[_CF_TOLERANCE]
    nfixed, halvings = int(cfg[_CF_SUBSTEPS]), int(cfg[_CF_HALVINGS])
    share = tol * cfg[_CF_SHARE]
    aim = share  # the share this pass aims at (smaller in a retry)
    limit = tol * cfg[_CF_PROPAGATED]
    order = cfg[_CF_ORDER]
    stable = cfg[_CF_STABLE]
    fixed = nfixed > 0
    m, r, kappa, e = io[_M, 0], io[_RR, 0], io[_KAPPA, 0], io[_E, 0]
    k, g, c, mu = io[_K, 0], io[_G, 0], io[_C, 0], io[_MU, 0]
    tau, phi, w = io[_TAU, 0], io[_PHI_IN, 0], io[_W_IN, 0]
    kp, kw = np.empty(s + 1), np.empty(s + 1)  # the stages' φ' and φ''
    kp[0] = w
    kw[0], jp0, jq0 = eq.accel_jacobian(phi, w, tau, m, r, kappa, e, k, g, c)
    jp1, jq1 = jp0, jq0
    t, lift, slip, err_sum, hforce, count = 0.0, np.inf, np.inf, 0.0, 0.0, 0.0
    status, rejected, carry, retries, beyond = 0.0, 0.0, 0.0, 0.0, 0.0
    s00, s01, s10, s11 = 0.0, 0.0, 0.0, 0.0
    hdes = _first_size(io, 0, w, dt, tol, nfixed, cfg)
    for _attempt in range(_MAX_ATTEMPTS):
        if status != 0.0:
            break
        h, last = _attempt_size(fixed, nfixed, hdes, count, t, dt)
        li, si = _margins(phi, w, kw[0], m, r, kappa, e, g, mu)
        lift, slip = min(lift, li), min(slip, si)
        phin = phi
        for st in range(1, s + 1):
            acc_p, acc_w = 0.0, 0.0
            for j in range(st):
                a = tab[st, j]
                if a != 0.0:
                    acc_p += a * kp[j]
                    acc_w += a * kw[j]
            phin = phi + h * acc_p
            kp[st] = w + h * acc_w
            if st < s:
                kw[st] = eq.accel(phin, kp[st], tau, m, r, kappa, e, k, g, c)
            else:
                kw[st], jp1, jq1 = eq.accel_jacobian(phin, kp[st], tau, m, r, kappa, e, k, g, c)
        wn = kp[s]
        e5p, e5w, e3p, e3w = 0.0, 0.0, 0.0, 0.0
        for j in range(s + 1):
            a3, a5 = tab[s + 1, j], tab[s + 2, j]
            e3p += a3 * kp[j]
            e3w += a3 * kw[j]
            e5p += a5 * kp[j]
            e5w += a5 * kw[j]
        ep, ew, e3 = _estimates(h, e5p, e5w, e3p, e3w)
        hmax = _largest_size(max(abs(w), abs(wn)), r, kappa, jp0, jq0, jp1, jq1, stable)
        accept, h_new, status, hforce = _judge(
            h, ep, ew, e3, phi, w, phin, wn, kw[s], count, hforce, t, hdes, rejected, last,
            status, dt, aim, fixed, halvings, hmax)
        err = max(ep, ew)
        beyond = trig.select(fixed & accept & (h > FIXED_TRUSTED * hmax), 1.0, beyond)
        if accept:
            phi, w, kp[0], kw[0] = phin, wn, kp[s], kw[s]
            s00, s01, s10, s11 = _propagate(s00, s01, s10, s11, h, jp0, jq0, jp1, jq1, ep, ew)
            jp0, jq0 = jp1, jq1
        t, count, err_sum, rejected, carry = _tick(accept, last, t, h, count, err_sum, err,
                                                   hdes, h_new, carry, dt)
        hdes = h_new
        grown = _propagated(s00, s01, s10, s11)
        if _again(status, fixed, grown, limit, retries, hforce, count, order):
            phi, w = io[_PHI_IN, 0], io[_W_IN, 0]
            kp[0] = w
            kw[0], jp0, jq0 = eq.accel_jacobian(phi, w, tau, m, r, kappa, e, k, g, c)
            t, err_sum, status, rejected, carry = 0.0, 0.0, 0.0, 0.0, 0.0
            s00, s01, s10, s11 = 0.0, 0.0, 0.0, 0.0
            aim = _smaller_share(aim, grown, limit)
            retries += 1.0
            hdes = _first_size(io, 0, w, dt, tol, nfixed, cfg)
    io[_H_NEXT, 0] = 0.0 if fixed or status != 1.0 else carry
    grown = _propagated(s00, s01, s10, s11)
    met, estimate = (err_sum <= share) & (grown <= limit) & (beyond == 0.0), max(err_sum, grown)
    if _checks(met, count, io[_PHI_IN, 0], io[_W_IN, 0], phi, w, tol, 0):  # taylor's reruns
        met, estimate = _taylor_check_one(io, phi, w, estimate, dt, tol)
    _finish(io, 0, status == 1.0, phi, w, tau, count, lift, slip, estimate, met)



# Each chunked scheme's kernels: the loops around its functions, a function of its own per
# scheme so that numba caches it (as the fixed-substep kernels, in ``fixed``). The serial one
# is the loop of rules.CHUNK's comment, written out.
@_jit
def _rk_serial(io, tab, cfg):
    n = io.shape[1]
    if n == 1:
        _rk_one(io, tab, cfg)
        return
    for lo in range(0, n, CHUNK):
        _rk_chunk(io, lo, min(lo + CHUNK, n), tab, cfg)


@numba.njit(cache=True, parallel=True, nogil=True, error_model="numpy")
def _rk_parallel(io, tab, cfg):
    _parallel(io, tab, cfg, _rk_chunk)
