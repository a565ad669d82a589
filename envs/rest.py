"""The scene's rates (ψ = qφ, :func:`psi_rate`, :func:`angle_rate`, :func:`wrap_rate`) and
the rest positions a task may target: the holdable range around the bottom
(:func:`hold_ranges`, one compiled call for a batch of scenes) and the unstable rest positions
(:func:`unstable_rest_positions`); :func:`per_scene` evaluates a function of a scalar scene
once per distinct scene of a batch.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import numba
import numpy as np
from roller_gym.physics import Scene, equations, equilibria
from roller_gym.physics.compiling import inlined
from roller_gym.physics.integrators import SCENE_FIELDS, scene_arrays
from roller_gym.physics.scene import finite_real, require_scene, shown

__all__ = [
    "HOLD_FRICTION_SHARE",
    "HOLD_TORQUE_SHARE",
    "START_TURNS",
    "angle_rate",
    "barrier_energy",
    "cached_per_scene",
    "hold_range",
    "hold_ranges",
    "last_within",
    "orbit_mean_speed",
    "orbit_speed",
    "per_scene",
    "psi_rate",
    "reach",
    "reach_at_rate",
    "unstable_rest_positions",
    "wrap_rate",
]


def psi_rate(scene: Scene) -> float | np.ndarray:
    """dψ/dφ = rκ/(1 − rκ) [-]: ψ = psi_rate · φ (0 on the floor, where ψ stays 0); a float
    for a scalar scene, an array for a batch."""
    scene = require_scene(scene)
    kappa = np.asarray(scene.kappa, dtype=float)
    rate = scene.r * kappa / (1.0 - scene.r * kappa)
    return float(rate) if np.ndim(rate) == 0 else rate


def angle_rate(scene: Scene) -> float | np.ndarray:
    """The rate [-] of the angle a task's ranges and targets are stated in, per rad of φ:
    :func:`psi_rate` (ψ = qφ), except on the floor, where ψ stays 0 and φ itself is used
    (1)."""
    rate = psi_rate(scene)
    if np.ndim(rate) == 0:
        return rate if rate != 0.0 else 1.0
    return np.where(rate == 0.0, 1.0, rate)


#: The most turns of φ a start state or a held target lies from the bottom: on a nearly flat
#: surface (R of hundreds of r and more), ψ = ±π lies further (see :func:`hold_ranges`).
START_TURNS = 64

#: The points of each side's grid :func:`hold_ranges` walks.
HOLD_POINTS = 2001

#: The share of max_torque a held rest position may need (:func:`hold_ranges`); the rest is
#: left for moving, e.g. along RollerTrack's target.
HOLD_TORQUE_SHARE = 0.8
#: The share of μN the friction at a held rest position may need (:func:`hold_ranges`).
HOLD_FRICTION_SHARE = 0.9

#: How close to a whole number 1/|q| or |q| must be to count as one (relative).
WHOLE_TOLERANCE = 1e-9


def wrap_rate(scene: Scene) -> float | np.ndarray:
    """The rate q [-] by which position errors are wrapped: 2π/|q| [rad of φ] is the period
    of the roller's pose (the contact point and the eccentric mass both where they were),
    the least turn of φ that turns both φ and ψ = :func:`psi_rate` · φ by whole turns.
    That is :func:`psi_rate` where 1/|psi_rate| is a whole number (the roller turns that
    many times while the contact goes once around); 1 where |psi_rate| is whole, the floor
    (0) included (one turn of φ: on the floor, the same pose a circumference along); else 0,
    no period the error is wrapped by (:func:`roller_gym.task.position_error`)."""
    q = np.asarray(psi_rate(scene), dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        turns = np.abs(1.0 / q)  # inf on the floor
        rate = np.where(_whole(turns) & np.isfinite(turns), q,
                        np.where(_whole(np.abs(q)), 1.0, 0.0))
    return float(rate) if rate.ndim == 0 else rate


def _whole(x: np.ndarray) -> np.ndarray:
    """Whether x >= 0 is a whole number, to :data:`WHOLE_TOLERANCE` (0 is; inf is not)."""
    return np.abs(x - np.round(x)) <= WHOLE_TOLERANCE * x


def per_scene(function, scene: Scene) -> np.ndarray:
    """``function(scalar scene)`` for each roller of a batch scene, computed once per
    distinct scene (float results, as an array of the batch's size; of 1 for a scalar
    scene)."""
    if scene.batch_size is None:
        return np.array([function(scene)], dtype=float)
    n = scene.batch_size
    rows = np.stack([np.broadcast_to(np.asarray(getattr(scene, f.name), float), (n,))
                     for f in dataclasses.fields(Scene)], axis=1)
    unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    names = [f.name for f in dataclasses.fields(Scene)]
    values = np.array([function(Scene(**dict(zip(names, row, strict=True))))
                       for row in unique], dtype=float)
    return values[np.asarray(inverse).reshape(-1)]


def cached_per_scene(function):
    """Memoize ``function(scene, *args)`` on the scene's values (resets call it per episode;
    ``args`` hashable, else uncached)."""

    @functools.lru_cache(maxsize=1024)
    def cached(values: tuple[tuple[str, float], ...], *args):
        return function(Scene(**dict(values)), *args)

    @functools.wraps(function)
    def wrapper(scene: Scene, *args):
        scene = require_scene(scene)
        try:
            hash(args)
        except TypeError:  # not a key (a list...): uncached, for the function's own checks
            return function(scene, *args)
        return cached(tuple(scene.as_dict().items()), *args)

    return wrapper


def hold_ranges(scene: Scene, max_torque: float, torque_share: float = HOLD_TORQUE_SHARE,
                friction_share: float = HOLD_FRICTION_SHARE, points: int = HOLD_POINTS,
                rising: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """The intervals [low, high] of rest positions φ [rad] around 0 that can be held at rest,
    one per roller of the batch ``scene`` (arrays of the batch's size; of 1 for a scalar
    scene), in one compiled call whatever the batch's size.

    Contiguous around φ = 0, within ψ = ±π (|φ| <= π/|q|, q from :func:`angle_rate`) and
    :data:`START_TURNS` turns of φ (so that the grid below resolves sin φ), where
    the holding torque is at most ``torque_share``·max_torque [N·m] and the contact holds
    with margin: N > 0 and |F| <= ``friction_share``·μN (at rest N = m g cos ψ,
    F = m g sin ψ); with ``rising``, also where the potential rises away from the bottom
    (φ·dV/dφ > 0: a swing from the bottom turns back there, before any barrier of the
    potential). Each side is a grid of ``points`` values of φ from 0 to ±:func:`reach`
    (those of ``np.linspace``, bit for bit), walked outward from φ = 0: the bound is the last
    grid point before the first one that fails (φ = 0 if that one fails, the end if none
    does), so the cost is proportional to the range's width, not to ``points``.
    """
    scene = require_scene(scene)
    if not (finite_real(max_torque) or max_torque == math.inf) or not max_torque > 0:
        raise ValueError(f"max_torque={shown(max_torque)} [N·m] must be a real number > 0 "
                         "(math.inf: no torque limit)")
    for name, share in (("torque_share", torque_share), ("friction_share", friction_share)):
        if not (finite_real(share) and 0 < share <= 1):
            raise ValueError(f"{name}={shown(share)} must be a real number in (0, 1]")
    if not (isinstance(points, int | np.integer) and not isinstance(points, bool)
            and 1 <= points <= 10**7):
        raise ValueError(f"points={shown(points)} must be an integer in [1, 10**7]")
    if not isinstance(rising, bool | np.bool_):
        raise ValueError(f"rising={shown(rising)} must be True or False")
    if not all(isinstance(getattr(scene, f.name), float | np.ndarray)
               for f in dataclasses.fields(Scene)):  # e.g. an int or float32 number
        scene = Scene(**{f.name: np.asarray(getattr(scene, f.name), float)[()]
                         for f in dataclasses.fields(Scene)})  # float64, as hold_range's floats
    rows = dict(zip(SCENE_FIELDS, scene_arrays(scene), strict=True))  # each of n rollers
    numbers = [rows[name] for name in ("m", "r", "kappa", "e", "k", "g", "damping", "mu")]
    half = np.empty_like(numbers[0])
    half[...] = np.reshape(reach(scene), -1)
    low, high = np.empty_like(half), np.empty_like(half)
    _hold_bounds(*numbers, half, float(torque_share * max_torque), float(friction_share),
                 int(points), bool(rising), low, high)
    return low, high


def reach(scene: Scene, angle: float = math.pi) -> float | np.ndarray:
    """How far [rad of φ] from φ = 0 the angle ``angle`` [rad] of ψ reaches (of φ itself on
    the floor): angle/|q| with q from :func:`angle_rate` (q < 0 on a drum), at most
    :data:`START_TURNS` turns of φ. With the default ψ = ±π: how far a held target may lie
    (:func:`hold_ranges`); a task's start ranges are stated as smaller angles.

    Raises:
        ValueError: ``angle`` is not a real number > 0.
    """
    if not (finite_real(angle) and angle > 0):
        raise ValueError(f"angle={shown(angle)} [rad] must be a real number > 0")
    return reach_at_rate(np.abs(angle_rate(scene)), angle)


def reach_at_rate(rate: Any, angle: float) -> Any:
    """:func:`reach` at the rate |q| = ``rate`` [-] (numbers or arrays): angle/rate [rad of
    φ], at most :data:`START_TURNS` turns (inf, then the cap, where the rate is 0)."""
    with np.errstate(over="ignore", divide="ignore"):  # inf for |R| near float64's top
        return np.minimum(angle / rate, 2.0 * math.pi * START_TURNS)


@cached_per_scene
def hold_range(scene: Scene, max_torque: float, torque_share: float = HOLD_TORQUE_SHARE,
               friction_share: float = HOLD_FRICTION_SHARE, points: int = HOLD_POINTS,
               rising: bool = False) -> tuple[float, float]:
    """The interval (low, high) of rest positions φ [rad] around 0 that can be held at rest
    in the scalar ``scene``: :func:`hold_ranges` of it (the same compiled walk), memoized."""
    low, high = hold_ranges(scene, max_torque, torque_share, friction_share, points, rising)
    return float(low[0]), float(high[0])


@inlined
def _holds(phi, m, r, kappa, e, k, g, c, mu, torque_limit, friction_share, rising):
    """Whether the roller can be held at rest at φ [rad] (:func:`hold_ranges`' condition): its
    holding torque τ = dV/dφ [N·m] within ``torque_limit``, and under τ at rest N > 0 and
    |F| <= ``friction_share``·μN; with ``rising``, also φ·τ > 0 (or φ = 0)."""
    tau = equations.dpotential(phi, m, r, kappa, e, g)
    phi_ddot = equations.accel(phi, 0.0, tau, m, r, kappa, e, k, g, c)
    normal, friction = equations.contact_forces(phi, 0.0, phi_ddot, m, r, kappa, e, g)
    return ((abs(tau) <= torque_limit) & (normal > 0)
            & (abs(friction) <= friction_share * mu * normal)
            & ((not rising) | (phi * tau > 0) | (phi == 0.0)))


@inlined
def _linspace_at(i, div, step, stop):
    """Point i of ``np.linspace(0.0, stop, div + 1)``, bit for bit, as NumPy computes it:
    i·step + 0.0 with step = (stop − 0.0)/div (where step underflows to 0,
    (i/div)·(stop − 0.0) + 0.0), and ``stop`` itself at i = div > 0."""
    delta = stop - 0.0
    if div == 0:
        return 0.0 * delta + 0.0
    if i == div:
        return stop
    if step == 0.0:
        return i / div * delta + 0.0
    return i * step + 0.0


#: How many grid points :func:`_hold_bounds` checks at once (a loop in SIMD lanes): the walk
#: overshoots the first failure by fewer than this many points.
_HOLD_BLOCK = 16


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _hold_bounds(m, r, kappa, e, k, g, c, mu, half, torque_limit, friction_share, points,
                 rising, low, high):
    """low[j], high[j] of :func:`hold_ranges` for roller j (scene numbers as rows, ``half``
    :func:`reach` [rad]): each side's grid walked outward from φ = 0, a block of
    :data:`_HOLD_BLOCK` points at a time, up to the first point that fails :func:`_holds`."""
    div = points - 1
    phi = np.empty(_HOLD_BLOCK)
    ok = np.empty(_HOLD_BLOCK, dtype=np.bool_)
    for j in range(m.size):
        stop = half[j]
        step = (stop - 0.0) / div if div > 0 else np.nan  # NumPy's (stop − start)/div
        for side in range(2):
            sign = 1.0 if side == 0 else -1.0
            bound = sign * _linspace_at(0, div, step, stop)
            start = 0
            while start < points:
                count = min(_HOLD_BLOCK, points - start)
                for b in range(count):  # a loop without exits: SIMD lanes
                    phi[b] = sign * _linspace_at(start + b, div, step, stop)
                    ok[b] = _holds(phi[b], m[j], r[j], kappa[j], e[j], k[j], g[j], c[j], mu[j],
                                   torque_limit, friction_share, rising)
                failed = False
                for b in range(count):
                    if not ok[b]:
                        failed = True
                        break
                    bound = phi[b]
                if failed:
                    break
                start += count
            if side == 0:
                high[j] = bound
            else:
                low[j] = bound


@cached_per_scene
def unstable_rest_positions(scene: Scene) -> tuple[float, ...]:
    """The unstable rest positions φ [rad] at zero torque nearest to φ = 0 on each side
    (d²V/dφ² < 0: neutral ones, as everywhere for a uniform disc on the floor, do not count)."""
    m, r, kappa, e, _, g, _ = scene.params
    unstable = [p.phi for p in equilibria(scene, 0.0)
                if not p.stable and equations.d2potential(p.phi, m, r, kappa, e, g) < 0]
    out = []
    positive = [p for p in unstable if p > 0]
    negative = [p for p in unstable if p <= 0]
    if positive:
        out.append(min(positive))
    if negative:
        out.append(max(negative))
    return tuple(out)


@cached_per_scene
def barrier_energy(scene: Scene) -> float:
    """The potential energy [J] of the scalar ``scene``'s first barrier away from the bottom:
    V at the end of the run over which V rises from φ = 0 (at most :func:`reach`, ψ = ±π: a
    cylinder's top; :data:`START_TURNS` turns on a nearly flat surface), on a grid of 20,001
    points; a swing with more energy passes over it. Memoized."""
    m, r, kappa, e, _, g, _ = scene.params
    potential = equations.potential(np.linspace(0.0, float(reach(scene)), 20001), m, r, kappa,
                                    e, g)
    falls = np.flatnonzero(np.diff(potential) <= 0.0)
    return float(potential[falls[0]] if falls.size else potential[-1])


def last_within(exceeds, below: np.ndarray, above: np.ndarray, halvings: int = 60
                ) -> np.ndarray:
    """Bisection, elementwise: from ``below`` (where ``exceeds`` is False) and ``above`` (where
    it is True), the last point found where ``exceeds(x)`` is still False, after ``halvings``
    halvings; ``exceeds`` monotone between them (e.g. a potential rising past a level)."""
    for _ in range(halvings):
        middle = 0.5 * (below + above)
        higher = exceeds(middle)
        below, above = np.where(higher, below, middle), np.where(higher, middle, above)
    return below


def orbit_speed(scene: Scene, phi: np.ndarray, level: np.ndarray) -> np.ndarray:
    """|φ'| [rad/s] of the unforced motion of energy ``level`` [J] of the scalar ``scene`` at
    each φ [rad] of ``phi`` (broadcast together): sqrt(2 (level − V(φ)) / J_I(φ)), 0 where V
    is above the level (the motion does not come there)."""
    m, r, kappa, e, k, g, _ = scene.params
    return np.sqrt(np.maximum(2.0 * (level - equations.potential(phi, m, r, kappa, e, g))
                              / equations.inertia(phi, m, r, kappa, e, k), 0.0))


def orbit_mean_speed(scene: Scene, top: float, level: float, points: int = 512) -> float:
    """The mean of |φ'| [rad/s] over φ in [0, ``top``] [rad] of the unforced motion of energy
    ``level`` [J] of the scalar ``scene`` (:func:`orbit_speed`), by the midpoint rule on
    ``points`` pieces: with the damping c, the mean torque c·|φ'| it takes along the way."""
    phi = (np.arange(points) + 0.5) * (top / points)
    return float(np.mean(orbit_speed(scene, phi, level)))
