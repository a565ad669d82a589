"""The proof, over a box of scenes, that Balance's target exists: the nearest unstable rest
position φ_b > 0 (:func:`roller_gym.task.unstable_rest_positions`), where the roller rests,
enclosed on intervals (:mod:`roller_gym.intervals`) for every scene of the box
(:func:`unstable_rest_enclosure`); used by :meth:`BalanceTask.scene_proven
<roller_gym.balance.BalanceTask.scene_proven>` in the proofs over ``randomize`` ranges
(:mod:`roller_gym.feasibility`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from roller_gym.bounds import Params
from roller_gym.intervals import Interval
from roller_gym.physics import Scene, equations
from roller_gym.physics.analysis import MAX_TURNS, nearest_unstable_rests
from roller_gym.task import unstable_rest_positions

__all__ = ["MAX_PIECES", "rolls_proven", "unstable_rest_enclosure"]

#: The most pieces of (0, φ_b) examined when excluding a nearer unstable rest position.
MAX_PIECES = 4096


def unstable_rest_enclosure(p: Params, estimates: Sequence[Scene]) -> Interval | None:
    """An interval Φ [rad] that holds φ_b of every scene of the box ``p``, where it is proven
    that for every such scene the nearest unstable rest position φ_b > 0 of
    :func:`roller_gym.task.unstable_rest_positions` exists and the roller rests there
    (N > 0, |F| <= μN at φ = φ_b, φ' = 0, τ = 0), as :meth:`BalanceTask.default_target`
    requires; None where it is not proven. Shown on intervals, with Φ = [a, b] around the
    estimate of φ_b over the box (from the rest position of each scene of ``estimates`` in
    turn, refined by Newton's method at the box's corners):

    * dV/dφ(a) > 0 > dV/dφ(b) and d²V/dφ² < 0 on Φ: exactly one rest position in Φ, and it
      is unstable (d²V/dφ² < 0, as the rule asks);
    * b inside the window :func:`roller_gym.physics.equilibria` searches (|ψ| < π, and
      |φ| < MAX_TURNS turns);
    * no unstable rest position in (0, a): (0, a] is covered by pieces on each of which
      dV/dφ ≠ 0, or d²V/dφ² >= 0 (a rest position there is not unstable), or (a piece
      starting at 0, where dV/dφ = 0) d²V/dφ² ≠ 0, so dV/dφ is strictly monotone from 0;
    * N > 0 and μN − |F| >= 0 at rest on Φ (:func:`equations.margins`). At rest (φ' = 0)
      under τ = 0, φ'' ∝ g and N, F ∝ m g, so these margins N/(m g) and (μN − |F|)/(m g)
      do not depend on m or g: they are evaluated at the box's least m and g, which keeps
      the intervals from counting m's and g's range twice.

    The mirror image −φ_b counts as well and is not needed: the rule takes the positive one.
    Where the rule gives φ_b = 0 instead (no unstable rest position > 0, an unstable one at
    0), :func:`_unstable_bottom_proven` shows that (Φ = [0, 0]); on the floor, where the
    unstable rest position is at the window's edge (φ = −π), :func:`_floor_top_proven`
    (Φ holds π).
    A box where any of this fails is not proven (split, or refused where that does not end).
    """
    for scene in estimates:
        nearest = float(nearest_unstable_rests(scene.r, scene.kappa, scene.e)[0])
        near = _unstable_rest_near(p, nearest) if nearest > 0 else None  # (None for NaN)
        if near is not None:
            return near
        if not math.isnan(nearest):
            continue
        estimate = unstable_rest_positions(scene)  # the rule's other cases
        if estimate == (0.0,) and _unstable_bottom_proven(p):
            return Interval(0.0)
        if estimate and estimate[0] < 0 and _floor_top_proven(p):
            return FLOOR_TOP
    return None


def _floor_top_proven(p: Params) -> bool:
    """The rule on the floor (κ = 0), whose window is φ in [−π, π): dV/dφ = m g e sin φ
    vanishes at 0 (stable: d²V/dφ² = m g e > 0) and at −π (unstable), and at no unstable
    point of (0, π) (shown as in :func:`unstable_rest_enclosure`; by symmetry none in
    (−π, 0) either), so the rule takes φ_b = |−π| = π, the mass center above the axle,
    where the roller is checked to rest."""
    m, r, kappa, e, g = p.m, p.r, p.kappa, p.e, p.g
    if not (kappa.lo == kappa.hi == 0.0
            and equations.d2potential(Interval(0.0), m, r, kappa, e, g).lo > 0):
        return False
    return _nearer_excluded(p, math.pi * (1.0 - 1e-9)) and _rests(p, FLOOR_TOP)


#: An interval [rad] that holds π.
FLOOR_TOP = Interval(math.pi, float(np.nextafter(math.pi, 4.0)))


def _window(p: Params) -> tuple[Interval, float]:
    """(dψ/dφ as an interval, the largest φ [rad] the search window of
    :func:`roller_gym.physics.equilibria` reaches over the box)."""
    rate = abs(p.r * p.kappa / (1.0 - p.r * p.kappa))
    if rate.hi == 0.0:  # the floor
        return rate, math.pi
    if not rate.lo > 0:
        return rate, math.inf
    return rate, math.pi * min(1.0 / float(rate.lo), MAX_TURNS) * (1.0 + 1e-9)  # rounded up


def _unstable_bottom_proven(p: Params) -> bool:
    """The rule's other case: φ_b = 0 (the rule then takes the unstable rest position at
    φ = 0, as on top of a drum with the mass center high): d²V/dφ² < 0 at 0 and no
    unstable rest position in (0, the window's end] (as in :func:`unstable_rest_enclosure`);
    the roller rests at 0 (N = m g, F = 0) and is checked as well."""
    m, r, kappa, e, g = p.m, p.r, p.kappa, p.e, p.g
    zero = Interval(0.0)
    _, end = _window(p)
    if not (equations.d2potential(zero, m, r, kappa, e, g).hi < 0 and math.isfinite(end)
            and _nearer_excluded(p, end)):
        return False
    return _rests(p, zero)


def _rests(p: Params, phi: Interval) -> bool:
    """N > 0 and μN − |F| >= 0 at rest under τ = 0 at every φ of ``phi``, for every scene
    of the box; m and g at their least values (the margins do not depend on them, see
    :func:`unstable_rest_enclosure`)."""
    return bool(rolls_proven(p._replace(m=Interval(p.m.lo), g=Interval(p.g.lo)), phi, 0.0,
                             0.0).all())


def rolls_proven(p: Params, phi: Any, phi_dot: Any, tau: Any) -> np.ndarray:
    """Elementwise: N > 0 and μN − |F| >= 0 at every state of the intervals (or numbers)
    φ [rad], φ' [rad/s] under the torque τ [N·m], for every scene of the box ``p``."""
    acc = equations.accel(phi, phi_dot, tau, p.m, p.r, p.kappa, p.e, p.k, p.g, p.c)
    normal, friction = equations.contact_forces(phi, phi_dot, acc, p.m, p.r, p.kappa, p.e, p.g)
    liftoff, slip = equations.margins(normal, friction, p.m, p.g, p.mu)
    return np.asarray((liftoff.lo > 0) & (slip.lo >= 0))


def _unstable_rest_near(p: Params, estimate: float) -> Interval | None:
    phi = _roots_at_corners(p, estimate)
    if phi is None:
        return None
    m, r, kappa, e, g = p.m, p.r, p.kappa, p.e, p.g
    spread = float(phi.max() - phi.min())
    for pad in (0.5 * spread, 2.0 * spread):
        pad += 1e-9 * max(1.0, float(phi.max()))
        a, b = float(phi.min()) - pad, float(phi.max()) + pad
        if a <= 0:
            return None
        if (equations.dpotential(Interval(a), m, r, kappa, e, g).lo > 0
                and equations.dpotential(Interval(b), m, r, kappa, e, g).hi < 0
                and equations.d2potential(Interval(a, b), m, r, kappa, e, g).hi < 0):
            break
    else:
        return None
    big = Interval(b)
    rate, _ = _window(p)
    if rate.hi == 0.0:  # the floor: |φ| < π
        inside = big.hi < math.pi * (1.0 - 2e-9)
    else:  # |ψ| < π and |φ| < MAX_TURNS turns
        inside = (big.hi < MAX_TURNS * math.pi * (1.0 - 2e-9)
                  and (big * rate).hi < math.pi * (1.0 - 2e-9))
    whole = Interval(a, b)
    return whole if inside and _nearer_excluded(p, a) and _rests(p, whole) else None


def _roots_at_corners(p: Params, start: float) -> np.ndarray | None:
    """The root of dV/dφ near ``start`` at each corner of the box (Newton's method), or None
    where it does not converge to an unstable one: an estimate, checked by the proof."""
    ends = [(x.lo, x.hi) for x in (p.m, p.r, p.kappa, p.e, p.g)]
    m, r, kappa, e, g = (np.asarray(c, float) for c in zip(*itertools.product(*ends),
                                                            strict=True))
    phi = np.full(m.shape, start)
    for _ in range(30):
        step = (equations.dpotential(phi, m, r, kappa, e, g)
                / equations.d2potential(phi, m, r, kappa, e, g))
        phi = phi - step
        if np.all(np.abs(step) <= 1e-14 * np.abs(phi)):
            break
    if not (np.all(np.isfinite(phi)) and np.all(phi > 0)
            and np.all(equations.d2potential(phi, m, r, kappa, e, g) < 0)):
        return None
    return phi


def _nearer_excluded(p: Params, a: float) -> bool:
    """No unstable rest position in (0, a] for any scene of the box (see
    :func:`unstable_rest_enclosure`), by bisecting pieces of it."""
    m, r, kappa, e, g = p.m, p.r, p.kappa, p.e, p.g
    edges = np.linspace(0.0, a, 33)
    lo, hi = edges[:-1], edges[1:]
    examined = 0
    while lo.size:
        examined += lo.size
        if examined > MAX_PIECES:
            return False
        piece = Interval(lo, hi)
        slope = equations.dpotential(piece, m, r, kappa, e, g)
        curvature = equations.d2potential(piece, m, r, kappa, e, g)
        ok = (slope.lo > 0) | (slope.hi < 0) | (curvature.lo >= 0)
        ok |= (lo == 0.0) & ((curvature.lo > 0) | (curvature.hi < 0))
        half = 0.5 * (lo + hi)
        lo, hi = np.concatenate([lo[~ok], half[~ok]]), np.concatenate([half[~ok], hi[~ok]])
    return True
