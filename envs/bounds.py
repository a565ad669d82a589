"""Bounds over boxes of scenes: the scene's fields as intervals, the potential's enclosure,
and the least time [s] a roller needs to come to rest at the bottom.

A box is :class:`Params` (:func:`box_params`); a scalar scene is a box of one point, so a
check on one scene and the proof over a ``randomize`` range (:mod:`roller_gym.feasibility`)
are the same computation. The least times are lower bounds, each from the power balance
dE/dt = τφ' − cφ'² (``docs/PHYSICS.md``) with J_min <= J_I <= J_max and V >= V_min
(:func:`least_times`); each is monotone in its inputs, so it is evaluated at their ends.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np
from roller_gym.intervals import Interval
from roller_gym.physics import Scene, equations
from roller_gym.physics.scene import shown
from roller_gym.rest import HOLD_FRICTION_SHARE, HOLD_POINTS, HOLD_TORQUE_SHARE, reach_at_rate

__all__ = ["LEAST_TIMES", "Params", "box_params", "energy_time", "held_unaided_time",
           "holds_past", "least_times", "potential_enclosure", "pump_time", "reach_proven",
           "too_slow",
           "unaided_time"]


class Params(NamedTuple):
    """A box of scenes as intervals: the equations' ``m, r, kappa, e, k, g, c`` and μ."""

    m: Interval
    r: Interval
    kappa: Interval
    e: Interval
    k: Interval
    g: Interval
    c: Interval
    mu: Interval


def box_params(scene: Scene, box: Mapping[str, tuple[float, float]]) -> Params:
    """The intervals of a box: each field of ``box`` over its (low, high), the others at
    ``scene``'s values; κ = 1/R enclosed on intervals (exactly ``scene.kappa`` if R is fixed)."""
    def field(name: str) -> Interval:
        return Interval(*box[name]) if name in box else Interval(float(getattr(scene, name)))

    kappa = 1.0 / field("R") if "R" in box else Interval(float(scene.kappa))
    return Params(field("m"), field("r"), kappa, field("e"), field("k"), field("g"),
                  field("damping"), field("mu"))


def potential_enclosure(p: Any, phi: Any) -> Interval:
    """V [J] (:func:`equations.potential`) on intervals, over the box ``p`` and φ in the
    interval ``phi`` (elementwise) inside the search window (|ψ| < π): V = m g [A sinc(ψ/2)
    + 2 e sin²(φ/2)] with A = r φ sin(ψ/2) and sinc(ψ/2) in [sinc(max |ψ|/2), 1] (sinc
    falls on [0, π/2]; the equations' own sinc has no enclosure on intervals at ψ = 0)."""
    _, psi, _ = equations.shape_factors(phi, p.r, p.kappa)
    x = 0.5 * np.maximum(np.abs(psi.lo), np.abs(psi.hi))
    with np.errstate(invalid="ignore", divide="ignore"):
        least = np.where(x > 0, np.sin(x) / x, 1.0) * (1.0 - 1e-12)  # (rounded down)
    half = np.sin(0.5 * phi)
    rolled = p.r * phi * np.sin(0.5 * psi) * Interval(least, 1.0)
    return p.m * p.g * (rolled + 2.0 * p.e * half * half)


def _potential_floor(p: Params) -> Interval:
    """A lower bound of V [J] over every φ: 0 inside a cylinder and on the floor (κ >= 0,
    where V >= 0), else 2 m g (R − r) (the first term's least, e >= 0)."""
    drum = p.m * p.g * 2.0 * (1.0 / p.kappa - p.r)
    return Interval(np.where(p.kappa.lo >= 0, 0.0, drum.lo),
                    np.where(p.kappa.lo >= 0, 0.0, np.minimum(drum.hi, 0.0)))


def _monotone(f: Callable[..., Any], *args: tuple[Interval, int]) -> Interval:
    """f on intervals, f monotone in each argument (+1 rising, −1 falling): its values at
    the ends, widened by a relative 1e-9 for the float formula's rounding."""
    lo = f(*(a.lo if sign > 0 else a.hi for a, sign in args))
    hi = f(*(a.hi if sign > 0 else a.lo for a, sign in args))
    return Interval(lo * (1.0 - 1e-9), hi * (1.0 + 1e-9))


def _removal(start, goal, torque, damping, inertia):
    """The least time [s] to bring E − V_min from ``start`` down to ``goal`` [J] (0 where
    start <= goal): with u = sqrt(E − V_min), |φ'| <= sqrt(2/J_min) u, so dE/dt >= −(a u +
    b u²), a = τ sqrt(2/J_min), b = 2c/J_min, whose integral is (2/b) ln((a + b u₀)/(a +
    b u₁)), written with log1p (→ 2 (u₀ − u₁)/a as b → 0)."""
    with np.errstate(all="ignore"):
        u0, u1 = np.sqrt(np.maximum(start, 0.0)), np.sqrt(np.maximum(goal, 0.0))
        a, b = torque * np.sqrt(2.0 / inertia), 2.0 * damping / inertia
        gap = np.maximum(u0 - u1, 0.0)
        rate = a + b * u1
        x = b * gap / rate
        factor = np.where(x > 1e-12, np.log1p(x) / np.where(x > 0, x, 1.0), 1.0)
        # (no torque and no energy left to reach: the decay never gets there)
        return np.where(gap > 0, np.where(rate > 0, 2.0 * gap / rate * factor, np.inf), 0.0)


def energy_time(start: Any, goal: Any, torque: float, inertia: Any) -> Any:
    """The least time [s] to bring E − V_min from ``start`` to ``goal`` [J], either way,
    with |τ| <= ``torque`` [N·m] (damping only slows a gain: left out): |dE/dt| <= τ|φ'| and
    |φ'| <= sqrt(2 (E − V_min)/J_min), ``inertia`` = J_min [kg·m²], so sqrt(2 J_min)
    |sqrt(goal) − sqrt(start)|/τ (:func:`_removal` without damping)."""
    high, low = np.maximum(start, goal), np.minimum(start, goal)
    return _removal(high, low, torque, 0.0, inertia)


def pump_time(scene: Scene, start: float, goal: float, torque: float) -> float:
    """:func:`energy_time` [s] to pump the scalar ``scene``'s roller from the energy
    ``start`` up to ``goal`` [J] (none where goal <= start), with V >= 0 and J_I >= J_I(0) on
    the way (a swing about the bottom)."""
    m, r, kappa, e, k, _, _ = scene.params
    least = float(equations.inertia(0.0, m, r, kappa, e, k))
    return float(energy_time(start, max(goal, start), torque, least))


def _travel(distance, excess, torque, inertia):
    """The least time [s] to roll ``distance`` [rad] from rest with ``excess`` = V(start) −
    V_min [J]: the kinetic energy is at most excess + τ s after s rad (damping only takes),
    so |φ'| <= sqrt(2 (excess + τ s)/J_min), and the time is at least sqrt(2 J_min) ·
    distance / (sqrt(excess + τ distance) + sqrt(excess))."""
    with np.errstate(all="ignore"):
        d, excess = np.maximum(distance, 0.0), np.maximum(excess, 0.0)
        return np.sqrt(2.0 * inertia) * d / (np.sqrt(excess + torque * d) + np.sqrt(excess))


def _damped_travel(distance, damping, drive, least, most):
    """The least time [s] to roll ``distance`` [rad] from rest against the damping: the
    kinetic energy falls wherever |φ'| > (τ + max |V'|)/c = ``drive``/c, so it stays within
    ½ J_max (drive/c)², and |φ'| <= sqrt(J_max/J_min) drive/c."""
    with np.errstate(all="ignore"):
        return np.maximum(distance, 0.0) * damping * np.sqrt(least / most) / drive


def _lifted_travel(distance, period, top, slope, inertia):
    """The least time [s] to roll ``distance`` [rad] past the points where the eccentric
    mass is on top (θ = π, one each ``period`` = 2π|s| [rad] of φ). There N/m = g cos ψ +
    (r²κ/s − e) φ'², so the roller passes them below ω² = g/(e − r²κ/s) or leaves the
    surface. ``x`` rad past one, its kinetic energy is at most ``top`` + ``slope`` x: top =
    ½ J_max ω² + 2 m g e (and the eccentric mass's fall), slope = τ + m g r (the torque's work
    and the fall along the wall, |dV₁/dφ| = m g r |sin ψ|). So a period takes at least
    sqrt(2 J_min) period/(sqrt(top + slope period) + sqrt(top)), and the way past the first
    point, at least distance − period, at least its share of that (the pace is slowest just
    past a point)."""
    with np.errstate(all="ignore"):
        pace = np.sqrt(2.0 * inertia) / (np.sqrt(top + slope * period) + np.sqrt(top))
        return np.where(np.isfinite(top), np.maximum(distance - period, 0.0) * pace, 0.0)


def _levels(p: Params, start: Interval, band: float, speed: float):
    """(V − V_min [J] at the start, at rest at |φ| = ``start`` [rad]; V − V_min [J] of the
    most energetic success state, |φ| <= ``band``, |φ'| <= ``speed``; J_min; J_max) as
    intervals over the box."""
    least = p.m * equations.inertia_per_mass(0.0, p.r, p.e, p.k)
    most = p.m * equations.inertia_per_mass(1.0, p.r, p.e, p.k)
    base = _potential_floor(p)
    energy = potential_enclosure(p, start) - base
    kept = potential_enclosure(p, Interval(-band, band)) - base + 0.5 * most * speed * speed
    return energy, kept, least, most


#: The least times of :func:`least_times` by name: (what takes the time, what to change).
LEAST_TIMES: dict[str, tuple[str, str]] = {
    "energy": ("taking out the energy of the start (at most "
               "max_torque·|φ'| + damping·φ'² a second)", "a larger max_torque or a scene "
               "with less energy at the start (smaller m, g, e or R)"),
    "travel": ("rolling from the start to the bottom at the speeds its energy "
               "allows", "a larger max_torque, or a scene with less inertia (smaller m, k, "
               "e) or a nearer start (smaller R)"),
    "lifted travel": ("rolling from the start to the bottom past the points "
                      "where the eccentric mass is on top, below the speed at which it lifts "
                      "off there, sqrt(g/(e − r²κ/(1 − rκ)))", "a nearer start (smaller R) or "
                      "a smaller e"),
    "damped travel": ("rolling from the start to the bottom against the "
                      "damping", "less damping or a larger max_torque"),
}


def least_times(p: Params, max_torque: float, start: Interval, band: float,
                speed: float) -> dict[str, Interval]:
    """Lower bounds [s] of the time to bring the roller from a start at rest at |φ| =
    ``start`` [rad] (intervals, elementwise: each holding a start in every scene of the box
    ``p``) to rest at the bottom (|φ| <= ``band`` [rad], |φ'| <= ``speed`` [rad/s]) with
    |τ| <= ``max_torque`` [N·m], as intervals over the box:

    * ``"lifted travel"``: the way rolled past the points it must pass below its lift-off
      speed (:func:`_lifted_travel`);
    * ``"energy"``: its energy taken out, at most τ|φ'| + cφ'² a second (:func:`_removal`);
    * ``"travel"``: the way rolled at the speeds its energy allows (:func:`_travel`);
    * ``"damped travel"``: the way rolled at the speeds the damping allows
      (:func:`_damped_travel`).
    """
    with np.errstate(all="ignore"):  # (inf and NaN prove nothing: see intervals)
        return _least_times(p, max_torque, start, band, speed)


def _least_times(p, max_torque, at, band, speed):
    start, kept, least, most = _levels(p, at, band, speed)
    torque = Interval(float(max_torque))
    drive = torque + p.m * p.g * (p.r + p.e)  # max |V'| <= m g (r + e)
    way = at - band
    s = 1.0 - p.r * p.kappa
    lift = p.e - p.r * p.r * p.kappa / s  # > 0: the roller lifts off a point fast enough
    fall = 2.0 * p.m * p.g * p.e
    top = Interval(np.where(lift.hi > 0, 0.5 * most.lo * p.g.lo / lift.hi + fall.lo, np.inf),
                   np.where(lift.lo > 0, 0.5 * most.hi * p.g.hi / lift.lo + fall.hi, np.inf))
    return {"lifted travel": _monotone(_lifted_travel, (way, 1), (2.0 * math.pi * abs(s), -1),
                                       (top, -1), (torque + p.m * p.g * p.r, -1), (least, 1)),
            "energy": _monotone(_removal, (start, 1), (kept, -1), (torque, -1), (p.c, -1),
                                (least, 1)),
            "travel": _monotone(_travel, (way, 1), (start, -1), (torque, -1), (least, 1)),
            "damped travel": _monotone(_damped_travel, (way, 1), (p.c, 1), (drive, -1),
                                       (least, 1), (most, -1))}


def unaided_time(p: Params, farthest: Interval, band: float, speed: float) -> Interval:
    """A lower bound [s] of the time the free motion (τ = 0) needs to bring the roller from
    the farthest start to rest at the bottom (as :func:`least_times`): its
    energy decays at most at 2c/J_min, so (J_min/2c) ln(E₀/E₁); inf without damping (the
    energy is kept)."""
    with np.errstate(all="ignore"):
        start, kept, least, _ = _levels(p, farthest, band, speed)
    seconds = _monotone(_removal, (start, 1), (kept, -1), (Interval(0.0), -1), (p.c, -1),
                        (least, 1))
    return Interval(np.where(p.c.hi > 0, seconds.lo, np.inf),
                    np.where(p.c.lo > 0, seconds.hi, np.inf))


def holds_past(p: Params, torque_limit: float, friction_share: float,
               band: float) -> np.ndarray:
    """Whether, in every scene of each box of ``p``, the range of rest positions that can be
    held (:func:`roller_gym.rest.hold_ranges`: |dV/dφ| <= ``torque_limit`` [N·m], and at
    rest N > 0 and |F| <= ``friction_share``·μN, i.e. cos ψ > 0 and |sin ψ| <= share·μ
    cos ψ) reaches past ``band`` [rad]: every position of [0, band + its grid's spacing]
    holds (V' is odd and ψ = qφ, so the other side holds alike)."""
    with np.errstate(all="ignore"):
        q = abs(p.r * p.kappa / (1.0 - p.r * p.kappa))
        floor = (p.kappa.lo == 0) & (p.kappa.hi == 0)  # (the floor's rate is 1)
        reach = np.where(floor, np.pi, reach_at_rate(q.lo, np.pi))
        phi = Interval(0.0, band + reach / (HOLD_POINTS - 1))
        psi = p.r * p.kappa / (1.0 - p.r * p.kappa) * phi
        # dV/dφ = m g (r sin ψ + e sin φ) (equations.dpotential), NumPy's sines on intervals
        torque = abs(p.m * p.g * (p.r * np.sin(psi) + p.e * np.sin(phi)))
        cos, sin = np.cos(psi), abs(np.sin(psi))
        return ((torque.hi <= torque_limit) & (cos.lo > 0)
                & (sin.hi <= friction_share * (p.mu * cos).lo))


def held_unaided_time(p: Params, farthest: Interval, max_torque: float, band: float,
                      speed: float) -> Interval:
    """:func:`unaided_time` where half the targets a task holds (uniform over
    :func:`roller_gym.rest.hold_ranges`) or more may lie within ``band`` of the bottom, so
    that the damping alone, bringing the roller to rest there, succeeds for them; inf where
    the held range reaches past twice the band (:func:`holds_past`)."""
    seconds = unaided_time(p, farthest, band, speed)
    wide = holds_past(p, HOLD_TORQUE_SHARE * max_torque, HOLD_FRICTION_SHARE, 2.0 * band)
    return Interval(np.where(wide, np.inf, seconds.lo), np.where(wide, np.inf, seconds.hi))


def too_slow(task: Any, scene: Scene, dt: float) -> str | None:
    """Why the target is out of reach within an episode of steps of ``dt`` [s] in the
    scalar ``scene`` for ``task`` (:meth:`Task.least_times`, from any of its
    :meth:`Task.accepted_starts`, past :attr:`Task.reach_share` of it), or reached with no
    torque (:meth:`Task.unaided_time`, from the farthest, within it); None if neither (and
    for a task that does not :attr:`~Task.descends`: a pump bounds its own time)."""
    if not task.descends:
        return None
    starts = task.accepted_starts(scene)
    if not starts.size:
        return None
    p, far = box_params(scene, {}), float(np.max(starts))
    farthest = Interval(far)
    episode = task.max_episode_steps * dt
    length = f"episodes of {task.max_episode_steps} steps of dt={dt:g} s ({episode:.3g} s)"
    for name, seconds in task.least_times(p, Interval(starts)).items():
        j = int(np.argmax(seconds.lo))  # the start that takes longest
        least = float(seconds.lo[j])
        if least > task.reach_share * episode:
            what, remedy = LEAST_TIMES[name]
            return (f"{task.name} cannot be solved in {shown(scene)} with max_torque="
                    f"{task.max_torque:g} N·m in {length}: {what} takes at least "
                    f"{least:.3g} s (the start at rest at |phi| = {starts[j]:.4g} rad), "
                    f"more than {task.reach_share:g} of the episode; use {remedy}, or a "
                    "longer dt")
    unaided = task.unaided_time(p, farthest)
    if unaided is not None and not float(np.min(unaided.lo)) > episode:
        least = float(np.min(unaided.lo))
        return (f"damping={scene.damping:g} N·m·s/rad of {shown(scene)} may bring the "
                f"roller to rest at the bottom, a success for (half or more of) the "
                f"targets of {task.name} with max_torque={task.max_torque:g} N·m, with no "
                f"torque at all in {length}: its "
                f"energy decays at up to 2 damping/J_min, from the farthest start (at rest "
                f"at |phi| = {far:.4g} rad) to the success band's in as little as "
                f"{least:.3g} s; use damping <= {scene.damping * least / episode * 0.95:.3g}"
                " (or 0), or a shorter dt (or, holding a target, a larger max_torque)")
    return None


def reach_proven(task: Any, p: Params, dt: float, farthest: Interval) -> np.ndarray:
    """Whether :func:`too_slow` is proven None for ``task`` over each box of ``p`` (arrays of
    intervals; ``farthest``: intervals holding each box's farthest accepted start): every
    least time's upper end, over every start (|φ| in [0, farthest's upper end]), within
    :attr:`Task.reach_share` of the episode, and the unaided time's lower end past it."""
    episode = task.max_episode_steps * dt
    ok = np.ones(np.shape(p.m.lo), bool)
    every = Interval(np.zeros_like(farthest.hi), farthest.hi)  # (every start's |φ| lies here)
    for seconds in task.least_times(p, every).values():
        ok &= seconds.hi <= task.reach_share * episode
    unaided = task.unaided_time(p, farthest)
    if unaided is not None:
        ok &= unaided.lo > episode
    return ok
