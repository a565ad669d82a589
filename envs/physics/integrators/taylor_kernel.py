"""The ``taylor`` scheme's kernels: one expansion of the motion a substep
(:mod:`roller_gym.physics.taylor`), its size chosen from its own last terms after expanding
(``substep``, so no substep is rejected), run for a chunk of rollers in SIMD lanes
(``chunk``) or for one roller (``one``, bit for bit the same), on one core or all: made by
:func:`taylor_kernels` for each degree, compiled at their first call.
"""

from __future__ import annotations

import functools
import importlib
import math
import sys
import types
from dataclasses import dataclass

import numba
import numpy as np
from roller_gym.physics import equations as eq
from roller_gym.physics import taylor, trig
from roller_gym.physics.integrators.layout import (
    _C,
    _CF_DT,
    _CF_SHARE,
    _CF_SUBSTEPS,
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
    _SAFETY,
    CHUNK,
    FORCE_AFTER,
    FORCE_REST,
    _end_lanes,
    _finish,
    _finite,
    _jit,
    _parallel,
    _swap_lanes,
    _write,
)

#: ``"taylor"``: the share of ``tolerance`` float64 rounding may take: where its substeps'
#: rounding (TAYLOR_ROUNDING ε max(|φ|, |φ'|) each) adds up to more, the tolerance is
#: reported out of reach (``tol_met=False``).
ROUNDING_SHARE = 0.5
#: The rounding one ``"taylor"`` substep adds, in ε max(|φ|, |φ'|) of its end state: about
#: what was measured against 40-digit references (``docs/INTEGRATORS.md``).
TAYLOR_ROUNDING = 2.0

#: The reruns that check a step whose own estimates met ``tolerance`` (``check`` of
#: :func:`taylor_kernels`): every step of rk8 and rk4; a step of taylor whose float64
#: rounding (TAYLOR_ROUNDING ε max(|φ|, |φ'|) a substep) grown by the larger of
#: SHADOW_GROWTH and SHADOW_RATE times its substeps could reach ``tolerance`` /
#: SHADOW_MARGIN, or that took SHADOW_FROM substeps or more. It is taken again by the
#: taylor scheme at the first of SHADOW_SHARES of ``tolerance`` and, unless that settles it,
#: at the second; it reports the tolerance met only where its end lies within
#: ``tolerance`` / SHADOW_MARGIN of every rerun's, settled by one rerun within a
#: SHADOW_SURE-th of that or beyond it. A sensitive motion (a tight fit) grows the substeps'
#: rounding past what their estimates see; runs on other substeps round differently, so
#: their distance measures it (``docs/INTEGRATORS.md``: the growth measured, at most 3.2
#: times the substeps).
SHADOW_FROM = 1024
SHADOW_GROWTH = 1e3
SHADOW_RATE = 32.0
SHADOW_SHARES = (2e-3, 4e-4)
SHADOW_MARGIN = 4.0
SHADOW_SURE = 8.0


@numba.extending.register_jitable
def _checks(met, count, phi0, w0, phi, w, tol, longest):
    """True where a step from (φ0, φ'0) to (φ, φ') in ``count`` substeps whose estimates
    ``met`` ``tol`` is to be taken again: ``count`` at least ``longest`` (taylor's
    SHADOW_FROM; 0 for a Runge–Kutta pair: every step), or its substeps' rounding
    (TAYLOR_ROUNDING ε max(|φ|, |φ'|) each) grown by the larger of SHADOW_GROWTH and
    SHADOW_RATE · count past tol / SHADOW_MARGIN."""
    big = max(max(abs(phi0), abs(w0)), max(abs(phi), abs(w)))
    grown = count * TAYLOR_ROUNDING * _EPS * big * max(SHADOW_GROWTH, SHADOW_RATE * count)
    return met and ((count >= longest) | (SHADOW_MARGIN * grown > tol))


@numba.extending.register_jitable
def _far(spread, phi, w, p, v):
    """``spread`` [rad or rad/s] after one more rerun ending at (p, v) (NaN: failed): the
    larger of it and (φ, φ')'s distance from (p, v); inf where the rerun failed."""
    far = max(abs(phi - p), abs(w - v))
    return trig.select(_finite(far), max(spread, far), math.inf)


@numba.extending.register_jitable
def _doubt(spread, tol):
    """True where a step whose end lies ``spread`` from a rerun's is neither settled as
    met (within tol / (SHADOW_MARGIN · SHADOW_SURE)) nor as not (past tol /
    SHADOW_MARGIN): a second rerun decides."""
    return (SHADOW_MARGIN * SHADOW_SURE * spread > tol) & (SHADOW_MARGIN * spread <= tol)


@numba.extending.register_jitable
def _judged(err, spread, tol):
    """(tol_met, error estimate) of a step taken again: met only where SHADOW_MARGIN ·
    ``spread`` (its end's largest distance from its reruns') is within ``tol``; the estimate
    at least ``spread``."""
    return SHADOW_MARGIN * spread <= tol, max(err, spread)


_T_IN = ("phi", "phi_dot", "tau", "rest", "floor")  # the rows a substep reads, after the scene's
_T_OUT = ("phi", "phi_dot", "h", "err", "lift", "slip", "last", "rounding")  # what it gives
(_TI_PHI, _TI_W, _TI_TAU, _TI_REST, _TI_FLOOR) = (len(SCENE_FIELDS) + i for i in range(len(_T_IN)))
_T_WIDTH = 8  # elements per lane in the substep loop's output (its fields, padded)
assert len(_T_OUT) <= _T_WIDTH


@numba.extending.register_jitable
def _taylor_tick(fin, last, rounding, count, nfixed, t, h, err_sum, err, hforce, status,
                 round_sum, dt):
    """A roller's (status, clock [s], accepted count, error sum, hforce [s], rounding sum)
    after a substep (``fin``: it stayed finite): selects only. A substep that brings the
    clock to dt ends the step."""
    last = trig.select(nfixed > 0, count + 1.0 >= nfixed, (last != 0.0) | (t + h >= dt))
    ends = fin & last
    status = trig.select(ends, 1.0, trig.select(fin, status, 2.0))
    t = trig.select(ends, dt, t + h)
    count = count + trig.select(fin, 1.0, 0.0)
    # past FORCE_AFTER substeps, the rest in fewer than as many more
    start = (count == FORCE_AFTER) & (hforce == 0.0)
    hforce = trig.select(start, (dt - t) / FORCE_REST, hforce)
    return status, t, count, err_sum + err, hforce, round_sum + rounding


@dataclass(frozen=True)
class TaylorKernels:
    """One degree's compiled functions (each compiled, or loaded from numba's cache, at its
    first call): ``substep`` (one roller's substep), ``lanes`` (the substep of many, in SIMD
    lanes), ``chunk(io, lo, hi, tab, cfg)``, ``one(io, tab, cfg)``, and the batch kernels
    ``serial`` and ``parallel`` (``f(io, tab, cfg)``); ``namespace``, the module they reach
    each other through (what a kernel made elsewhere calls them by, for the same reason)."""

    degree: int
    namespace: types.ModuleType
    substep: numba.core.registry.CPUDispatcher
    lanes: numba.core.registry.CPUDispatcher
    chunk: numba.core.registry.CPUDispatcher
    one: numba.core.registry.CPUDispatcher
    serial: numba.core.registry.CPUDispatcher
    parallel: numba.core.registry.CPUDispatcher


@functools.cache
def taylor_kernels(degree: int) -> TaylorKernels:
    """The kernels of the expansion to ``degree`` (one of ``taylor.DEGREES``), made once; its
    generated module is imported here, so a degree no step uses is neither imported nor
    compiled.

    Each kernel reaches the others, and the series, through a module made for the degree
    (``ns``, named in ``sys.modules``): numba keys a cached kernel made here on its closure's
    contents, pickled, and a module pickles by its name, where a compiled function would
    pickle differently in every process (the kernel never loaded from the cache)."""
    if degree not in taylor.DEGREES:
        raise ValueError(f"degree={degree!r}: the taylor scheme offers {taylor.DEGREES}")
    ns = types.ModuleType(f"{__name__}.degree{degree}")
    sys.modules[ns.__name__] = ns
    series = importlib.import_module(taylor.module_name(degree))
    ns.coefficients, ns.value, ns.root, ns.power = (series.coefficients, series.value,
                                                    series.root, series.power)
    ns.ORDER = series.ORDER

    @numba.njit(cache=True, nogil=True, error_model="numpy", forceinline=True)
    def substep(phi, w, tau, m, r, kappa, e, k, g, c, mu, rest, floor, hfixed, rate):
        """One substep of ``"taylor"`` from (φ, φ'): (φ, φ', h [s], its error estimate, the
        lift-off and slip margins at its start, 1.0 if it reaches ``rest`` [s], the float64
        rounding of its state). The margins take the sines the expansion evaluated.

        The estimate is the size of the last two terms, t₁ h^(p−1) + t₂ hᵖ (p the degree, t
        the largest of |X| and |V| at that power): two terms, as one coefficient can vanish
        by accident where the next does not. With ``hfixed`` > 0 the substep is that long.
        Otherwise h is the largest size whose terms are each within ``rate`` · h (the error
        allowed per second): h₁ = (rate/t₁)^(1/(p−2)), and h₂ from t₂ h^(p−1) <= rate h
        with h^(p−1) taken as min(h₁, rest) h^(p−2); then 0.9 of the smaller, at least
        ``floor``, at most ``rest``.

        The size goes as the (p−2)th root of ``rate``, so a tolerance far below float64's
        reach costs only a few more substeps, never a runaway count; the rounding the
        substep adds, TAYLOR_ROUNDING ε max(|φ|, |φ'|) at its end, is returned so that the
        step can report such a tolerance (``tol_met``). No branch: the batch runs it in SIMD
        lanes.
        """
        X, V, (sin_t, cos_t, sin_psi, cos_psi) = ns.coefficients(phi, w, tau, m, r, kappa, e,
                                                                  k, g, c)
        p = ns.ORDER
        t1 = max(abs(X[p - 1]), abs(V[p - 1]))
        t2 = max(abs(X[p]), abs(V[p]))
        h1 = trig.select(t1 > 0.0, ns.root(rate / t1), math.inf)
        near = min(h1, rest)
        h2 = trig.select(t2 * near > 0.0, ns.root(rate / (t2 * near)), math.inf)
        free = max(_SAFETY * min(h1, h2), floor)
        fixed = hfixed > 0.0
        h = trig.select(fixed, hfixed, min(free, rest))
        # t1 h^(p−1) + t2 h^p; 0 where the series ends before them (h^(p−1) may overflow)
        err = trig.select(t1 + t2 > 0.0, (t1 + t2 * h) * ns.power(h) * h, 0.0)
        last = trig.select(free >= rest, 1.0, 0.0)
        phin, wn = ns.value(X, h), ns.value(V, h)
        rounding = TAYLOR_ROUNDING * _EPS * max(abs(phin), abs(wn))
        normal, friction = eq.forces(sin_t, cos_t, sin_psi, cos_psi, w, V[1], m, r, kappa, e,
                                     g)
        lift, slip = eq.margins(normal, friction, m, g, mu)
        return phin, wn, h, err, lift, slip, last, rounding

    ns.substep = substep

    @_jit
    def lanes(x, na, hfixed, rate, out):
        """``substep`` of lanes 0..na−1: the scene and state from the rows of ``x``, the
        results lane by lane into ``out`` (_T_WIDTH elements a lane). Reading one table and
        writing another, laid out so, is what lets LLVM vectorize a body this long: it needs
        just one overlap check."""
        for i in range(na):
            o = np.uint64(i) * np.uint64(_T_WIDTH)  # unsigned: no wraparound check
            (out[o], out[o + np.uint64(1)], out[o + np.uint64(2)], out[o + np.uint64(3)],
             out[o + np.uint64(4)], out[o + np.uint64(5)], out[o + np.uint64(6)],
             out[o + np.uint64(7)]) = ns.substep(
                x[_TI_PHI, i], x[_TI_W, i], x[_TI_TAU, i], x[0, i], x[1, i], x[2, i],
                x[3, i], x[4, i], x[5, i], x[6, i], x[7, i], x[_TI_REST, i], x[_TI_FLOOR, i],
                hfixed, rate)

    ns.lanes = lanes

    @_jit
    def rerun(x0, start, nc, dt, rate, end):
        """end[:, j] = (φ, φ') at the end of the step of the roller in column j < nc of
        ``x0`` (its scene and τ rows as ``lanes`` reads them) from start[:, j], allowing
        ``rate`` error per second, in SIMD lanes (on a copy, the running ones in lanes
        0..na−1, as ``chunk`` keeps them); NaN where it failed."""
        x = x0.copy()
        out = np.empty(_T_WIDTH * nc)
        t, count, hforce, status = (np.zeros(nc), np.zeros(nc), np.zeros(nc),
                                    np.zeros(nc))
        slot = np.arange(nc)
        for j in range(nc):
            x[_TI_PHI, j], x[_TI_W, j] = start[0, j], start[1, j]
            end[0, j], end[1, j] = math.nan, math.nan
        na = nc
        for _attempt in range(_MAX_ATTEMPTS):
            if na == 0:
                break
            for i in range(na):
                x[_TI_REST, i], x[_TI_FLOOR, i] = dt - t[i], max(1e-12 * dt, hforce[i])
            ns.lanes(x, na, 0.0, rate, out)
            for i in range(na):
                o = _T_WIDTH * i
                fin = _finite(out[o]) & _finite(out[o + 1]) & _finite(out[o + 3])
                status[i], t[i], count[i], _, hforce[i], _ = _taylor_tick(
                    fin, out[o + 6], 0.0, count[i], 0.0, t[i], out[o + 2], 0.0, out[o + 3],
                    hforce[i], status[i], 0.0, dt)
                x[_TI_PHI, i] = trig.select(fin, out[o], x[_TI_PHI, i])
                x[_TI_W, i] = trig.select(fin, out[o + 1], x[_TI_W, i])
            i = 0
            while i < na:
                if status[i] != 0.0:
                    na -= 1
                    if status[i] == 1.0:
                        end[0, slot[i]], end[1, slot[i]] = x[_TI_PHI, i], x[_TI_W, i]
                    _swap_lanes(x, i, na)
                    t[i], t[na] = t[na], t[i]
                    count[i], count[na] = count[na], count[i]
                    hforce[i], hforce[na] = hforce[na], hforce[i]
                    status[i], status[na] = status[na], status[i]
                    slot[i], slot[na] = slot[na], slot[i]
                else:
                    i += 1

    @_jit
    def check(io, lo, slot, par, tau, phi, w, count, met, est, n, dt, tol, longest):
        """The rollers in lanes 0..n−1 of a finished chunk (lane i: column lo + slot[i] of
        ``io``; ``met`` 1.0 where its estimates met ``tol``, ``est`` its estimate, both
        rewritten): those ``_checks`` picks taken again (``rerun``) at the first of
        SHADOW_SHARES, those then in doubt (``_doubt``) at the second; each ``_judged`` by
        its end's larger distance from the reruns'."""
        pick = np.empty(n, np.int64)
        nc = 0
        for i in range(n):
            col = lo + int(slot[i])
            if _checks(met[i] != 0.0, count[i], io[_PHI_IN, col], io[_W_IN, col], phi[i], w[i],
                       tol, longest):
                pick[nc] = i
                nc += 1
        if nc == 0:
            return
        x = np.empty((len(SCENE_FIELDS) + len(_T_IN), nc + _PAD))
        start, again, far = np.empty((2, nc)), np.empty((2, nc)), np.zeros(nc)
        for j in range(nc):
            i = pick[j]
            col = lo + int(slot[i])
            for f in range(len(SCENE_FIELDS)):
                x[f, j] = par[f, i]
            x[_TI_TAU, j] = tau[i]
            start[0, j], start[1, j] = io[_PHI_IN, col], io[_W_IN, col]
        rerun(x, start, nc, dt, tol * SHADOW_SHARES[0] / dt, again)
        keep = np.empty(nc, np.int64)  # the rollers still in doubt, to columns 0..m−1
        m = 0
        for j in range(nc):
            far[j] = _far(0.0, phi[pick[j]], w[pick[j]], again[0, j], again[1, j])
            if _doubt(far[j], tol):  # (loops: a slice assignment compiles slowly)
                for f in range(x.shape[0]):
                    x[f, m] = x[f, j]
                start[0, m], start[1, m], keep[m] = start[0, j], start[1, j], j
                m += 1
        if m > 0:
            rerun(x, start, m, dt, tol * SHADOW_SHARES[1] / dt, again)
            for q in range(m):
                j = keep[q]
                far[j] = _far(far[j], phi[pick[j]], w[pick[j]], again[0, q], again[1, q])
        for j in range(nc):
            ok, judged = _judged(est[pick[j]], far[j], tol)
            met[pick[j]], est[pick[j]] = (1.0 if ok else 0.0), judged

    @_jit
    def check_one(io, phi, w, err, dt, tol):
        """(tol_met, error estimate) of the step of ``io``'s column 0 (its scene, start and
        τ) to (φ, φ'), whose estimates met ``tol`` (``err``): taken again as ``check``
        does, in scalar code (a one-roller kernel's, compiled without the lanes)."""
        m, r, kappa, e = io[_M, 0], io[_RR, 0], io[_KAPPA, 0], io[_E, 0]
        k, g, c, mu = io[_K, 0], io[_G, 0], io[_C, 0], io[_MU, 0]
        tau, far = io[_TAU, 0], 0.0
        for part in SHADOW_SHARES:
            if part != SHADOW_SHARES[0] and not _doubt(far, tol):
                break
            p, v = io[_PHI_IN, 0], io[_W_IN, 0]
            t, count, hforce, status = 0.0, 0.0, 0.0, 0.0
            for _attempt in range(_MAX_ATTEMPTS):
                if status != 0.0:
                    break
                pn, vn, h, estimate, _, _, last, _ = ns.substep(
                    p, v, tau, m, r, kappa, e, k, g, c, mu, dt - t, max(1e-12 * dt, hforce),
                    0.0, tol * part / dt)
                fin = _finite(pn) & _finite(vn) & _finite(estimate)
                status, t, count, _, hforce, _ = _taylor_tick(
                    fin, last, 0.0, count, 0.0, t, h, 0.0, estimate, hforce, status, 0.0, dt)
                p, v = trig.select(fin, pn, p), trig.select(fin, vn, v)
            done = status == 1.0
            far = _far(far, phi, w, trig.select(done, p, math.nan),
                       trig.select(done, v, math.nan))
        return _judged(err, far, tol)

    ns.check, ns.check_one = check, check_one

    @_jit
    def chunk(io, lo, hi, tab, cfg):
        """Advance rollers (columns) lo..hi−1 of ``io`` over one control step (``cfg`` as
        for :func:`_rk_chunk`; ``tab`` unused): the running rollers in lanes 0..na−1, as
        there."""
        n = hi - lo
        dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOLERANCE], cfg[_CF_SUBSTEPS]
        share = tol * cfg[_CF_SHARE]
        hfixed = dt / nfixed if nfixed > 0 else 0.0
        nf = len(SCENE_FIELDS)
        x = np.empty((nf + len(_T_IN), n + _PAD))  # what the substep loop reads
        par = x[:nf]
        phi, w, tau, rest, floor = x[_TI_PHI], x[_TI_W], x[_TI_TAU], x[_TI_REST], x[_TI_FLOOR]
        out = np.empty(_T_WIDTH * n)
        rows = np.empty((17, n + _PAD))
        phin, wn, hh, err, lift_at, slip_at = rows[0], rows[1], rows[2], rows[3], rows[4], rows[5]
        t, count, err_sum, hforce, status, slot = (rows[6], rows[7], rows[8], rows[9], rows[10],
                                                   rows[11])
        lift, slip, rounding, round_sum, last = rows[12], rows[13], rows[14], rows[15], rows[16]
        for i in range(n):
            col = lo + i
            for f in range(nf):
                par[f, i] = io[f, col]
            tau[i], phi[i], w[i] = io[_TAU, col], io[_PHI_IN, col], io[_W_IN, col]
            t[i], count[i], err_sum[i], hforce[i], status[i], slot[i] = (0.0, 0.0, 0.0, 0.0,
                                                                          0.0, i)
            lift[i], slip[i], round_sum[i] = np.inf, np.inf, 0.0
        na = n
        for _attempt in range(_MAX_ATTEMPTS):
            if na == 0:
                break
            for i in range(na):
                rest[i], floor[i] = dt - t[i], max(1e-12 * dt, hforce[i])
            ns.lanes(x, na, hfixed, share / dt, out)
            for i in range(na):
                o = _T_WIDTH * i
                phin[i], wn[i], hh[i], err[i], lift_at[i], slip_at[i], last[i], rounding[i] = (
                    out[o], out[o + 1], out[o + 2], out[o + 3], out[o + 4], out[o + 5],
                    out[o + 6], out[o + 7])
            for i in range(na):
                lift[i], slip[i] = min(lift[i], lift_at[i]), min(slip[i], slip_at[i])
                fin = _finite(phin[i]) & _finite(wn[i]) & _finite(err[i])
                status[i], t[i], count[i], err_sum[i], hforce[i], round_sum[i] = _taylor_tick(
                    fin, last[i], rounding[i], count[i], nfixed, t[i], hh[i], err_sum[i],
                    err[i], hforce[i], status[i], round_sum[i], dt)
                phi[i] = trig.select(fin, phin[i], phi[i])
                w[i] = trig.select(fin, wn[i], w[i])
            i = 0
            while i < na:
                if status[i] != 0.0:
                    na -= 1
                    _swap_lanes(par, i, na)
                    for v in (tau, phi, w, t, count, err_sum, hforce, status, slot, lift, slip,
                              round_sum):
                        v[i], v[na] = v[na], v[i]
                else:
                    i += 1
        end = np.empty((6, n + _PAD))
        for i in range(n):  # (a loop: a slice assignment compiles numba's shape-mismatch text)
            end[4, i], end[5, i] = lift[i], slip[i]
        _end_lanes(phi, w, tau, par, n, end)
        met, estimate = rows[3], rows[16]  # (err and last: free now)
        for i in range(n):
            ok = (err_sum[i] <= share) & (round_sum[i] <= ROUNDING_SHARE * tol)
            met[i], estimate[i] = trig.select(ok, 1.0, 0.0), err_sum[i]
        ns.check(io, lo, slot, par, tau, phi, w, count, met, estimate, n, dt, tol, SHADOW_FROM)
        for i in range(n):
            col = lo + int(slot[i])
            io[_H_NEXT, col] = 0.0
            _write(io, col, status[i] == 1.0, phi[i], w[i], count[i], end[0, i], end[1, i],
                   end[2, i], end[3, i], end[4, i], end[5, i], estimate[i], met[i] != 0.0)

    ns.chunk = chunk

    @_jit
    def one(io, tab, cfg):
        """One roller (column 0 of ``io``): ``chunk``'s arithmetic without lanes (bit for bit
        the same result)."""
        dt, tol, nfixed = cfg[_CF_DT], cfg[_CF_TOLERANCE], cfg[_CF_SUBSTEPS]
        share = tol * cfg[_CF_SHARE]
        hfixed = dt / nfixed if nfixed > 0 else 0.0
        m, r, kappa, e = io[_M, 0], io[_RR, 0], io[_KAPPA, 0], io[_E, 0]
        k, g, c, mu = io[_K, 0], io[_G, 0], io[_C, 0], io[_MU, 0]
        tau, phi, w = io[_TAU, 0], io[_PHI_IN, 0], io[_W_IN, 0]
        t, count, err_sum, hforce, status, round_sum = 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
        lift, slip = np.inf, np.inf
        for _attempt in range(_MAX_ATTEMPTS):
            if status != 0.0:
                break
            phin, wn, h, err, li, si, last, rounding = ns.substep(
                phi, w, tau, m, r, kappa, e, k, g, c, mu, dt - t, max(1e-12 * dt, hforce),
                hfixed, share / dt)
            lift, slip = min(lift, li), min(slip, si)
            fin = _finite(phin) & _finite(wn) & _finite(err)
            status, t, count, err_sum, hforce, round_sum = _taylor_tick(
                fin, last, rounding, count, nfixed, t, h, err_sum, err, hforce, status,
                round_sum, dt)
            phi, w = trig.select(fin, phin, phi), trig.select(fin, wn, w)
        io[_H_NEXT, 0] = 0.0
        met, estimate = (err_sum <= share) & (round_sum <= ROUNDING_SHARE * tol), err_sum
        if _checks(met, count, io[_PHI_IN, 0], io[_W_IN, 0], phi, w, tol, SHADOW_FROM):
            met, estimate = ns.check_one(io, phi, w, estimate, dt, tol)
        _finish(io, 0, status == 1.0, phi, w, tau, count, lift, slip, estimate, met)

    ns.one = one

    @_jit
    def serial(io, tab, cfg):  # the loop of rules.CHUNK's comment, written out
        n = io.shape[1]
        if n == 1:
            ns.one(io, tab, cfg)
            return
        for lo in range(0, n, CHUNK):
            ns.chunk(io, lo, min(lo + CHUNK, n), tab, cfg)

    @numba.njit(cache=True, parallel=True, nogil=True, error_model="numpy")
    def parallel(io, tab, cfg):
        _parallel(io, tab, cfg, ns.chunk)

    ns.serial, ns.parallel = serial, parallel
    return TaylorKernels(degree, ns, substep, lanes, chunk, one, serial, parallel)


# The default degree's kernels, by the names the episode kernels and the benchmark call.
_DEFAULT = taylor_kernels(taylor.ORDER)
_taylor_substep, _taylor_lanes, _taylor_chunk = _DEFAULT.substep, _DEFAULT.lanes, _DEFAULT.chunk
_taylor_check, _taylor_check_one = _DEFAULT.namespace.check, _DEFAULT.namespace.check_one
_taylor_one, _taylor_serial, _taylor_parallel = _DEFAULT.one, _DEFAULT.serial, _DEFAULT.parallel
