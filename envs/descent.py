"""The forced descent from a start: where no torque holds the roller, it rolls on toward the
bottom at a speed the torque cannot take away, and there it may have to slip or lift off.

From a start at |φ| = φs (at rest, or moving in at the draw's speed) to a target near the
bottom, wherever dV/d|φ| > max_torque the roller cannot stop; by the power balance
(``docs/PHYSICS.md``) its kinetic energy at φ is then at least V(φa) − V(φ) −
max_torque·(φa − φ) − the damping's work, φa the last point where it could have stopped
(plus the start's own kinetic energy, where φa = φs). N and F are affine in (φ'², τ − cφ'),
so whether some speed above that and some torque roll at φ is a linear program in two
variables (:func:`fastest_rolling`). A start where one has none is doomed: every episode
from it ends in a slip or a lift-off, whatever the policy. :func:`doomed` finds the nearest
such start of those a task's draw may accept in a scalar scene (:mod:`roller_gym.start_set`),
and :func:`fixed_scene_problem` refuses a fixed scene with one (and cautions where one is
near). Over ``randomize`` ranges, :func:`range_problem` refuses a box with a doomed start at
its middle, a corner or a scene drawn from it; between them nothing is proven
(``docs/MAINTAINERS.md``).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import numpy as np
from roller_gym import start_set, validation
from roller_gym.physics import Scene, equations
from roller_gym.physics.scene import require_scene, shown
from roller_gym.rest import reach

__all__ = ["DRAWS", "DRAWS_PER_FIELD", "DRUM_SEEN", "NEAR", "Doom", "Verdict", "doomed",
           "fastest_rolling", "fixed_scene_problem", "range_caution", "range_problem"]

#: Points of the scalar check's grid of |φ| from the bottom to the farthest start (and as
#: many on from there to ψ = π).
GRID_POINTS = 2001
#: A fixed cylinder or floor the rule would refuse with max_torque divided by NEAR is
#: accepted with a caution (:func:`fixed_scene_problem`): independent beam searches over
#: torque sequences at dt = 0.05 s found cylinders the rule accepts with a start they could
#: not bring down at up to 2.55 times the least torque the rule accepts (a measured factor,
#: not a bound; ``docs/MAINTAINERS.md``).
NEAR = 3.0
#: On a drum no factor held: the same searches found drums with damping accepted with such a
#: start at up to DRUM_SEEN times that torque (starts moving outward), so every drum a
#: descending task accepts gets the caution.
DRUM_SEEN = 4.65
#: The scenes :func:`range_problem` draws from a box besides its corners and middle: at least
#: DRAWS, and DRAWS_PER_FIELD per field (uniformly, with a fixed seed, as the resets draw
#: them).
DRAWS = 32
DRAWS_PER_FIELD = 8
#: x = φ'² [rad²/s²] taken as unbounded.
_X_CAP = 1e30


def _rows(phi: Any, m: Any, r: Any, kappa: Any, e: Any, k: Any, g: Any,
          mu: Any) -> tuple[np.ndarray, ...]:
    """(A, B, C), each (3, n): the rolling conditions N > 0, μN − F >= 0 and μN + F >= 0 at
    each φ [rad] as A + B·x + C·u >= 0 in x = φ'² and u = τ − cφ' [N·m], over m g (the
    scene's numbers floats or arrays like ``phi``)."""
    def forces(x: float, u: float) -> tuple[np.ndarray, np.ndarray]:
        a = equations.accel(phi, math.sqrt(x), u, m, r, kappa, e, k, g, 0.0)
        normal, friction = equations.contact_forces(phi, math.sqrt(x), a, m, r, kappa, e, g)
        return normal / (m * g), friction / (m * g)

    (n0, f0), (n1, f1), (n2, f2) = forces(0.0, 0.0), forces(1.0, 0.0), forces(0.0, 1.0)

    def rows(n: np.ndarray, f: np.ndarray) -> np.ndarray:
        return np.array([n, mu * n - f, mu * n + f])

    base = rows(n0, f0)
    return base, rows(n1, f1) - base, rows(n2, f2) - base


def fastest_rolling(A: np.ndarray, B: np.ndarray, C: np.ndarray, low: float,
                    high: Any) -> np.ndarray:
    """The largest x >= 0 with some u in [``low``, ``high``] where every row of A + B·x + C·u
    >= 0 holds (arrays (rows, n)), elementwise: the polygon's vertex of largest x, found
    among every pair of its edges' lines (1e30 where it is unbounded; −inf where empty)."""
    n = A.shape[1]
    high = np.broadcast_to(high, (n,))
    lines = [(np.ones(n), np.zeros(n), np.zeros(n)),            # x >= 0
             (-np.ones(n), np.zeros(n), np.full(n, _X_CAP)),    # x <= cap
             (np.zeros(n), np.ones(n), np.full(n, -low)),       # u >= low
             (np.zeros(n), -np.ones(n), high)]                  # u <= high
    lines += [(B[j], C[j], A[j]) for j in range(len(A))]        # b x + c u + a >= 0
    best = np.full(n, -np.inf)
    with np.errstate(all="ignore"):
        for i, (b1, c1, a1) in enumerate(lines):
            for b2, c2, a2 in lines[i + 1:]:
                det = b1 * c2 - b2 * c1
                x = (c1 * a2 - c2 * a1) / det
                u = (b2 * a1 - b1 * a2) / det
                ok = np.isfinite(x) & np.isfinite(u)
                for b, c, a in lines:  # within every edge, with a relative slack
                    ok &= b * x + c * u + a >= -1e-9 * (abs(b * x) + abs(c * u) + abs(a))
                best = np.where(ok & (x > best), x, best)
    return best


def _cell_inertia(phi: np.ndarray, m: float, r: float, kappa: float, e: float, k: float,
                  inertia: np.ndarray) -> np.ndarray:
    """A lower bound of J_I [kg·m²] on each cell between neighbouring points of ``phi``:
    the smaller end, or its least, J_I(0), where θ = φ/s passes a whole turn."""
    turns = np.floor(phi / (2.0 * math.pi * (1.0 - r * kappa)))
    return np.where(turns[1:] != turns[:-1], equations.inertia(0.0, m, r, kappa, e, k),
                    np.minimum(inertia[:-1], inertia[1:]))


class Doom(NamedTuple):
    """A doomed start: at |φ| = ``start`` [rad] moving at ``speed`` [rad/s] toward ``where``
    (|φ| [rad]), where it passes at ``least`` [rad/s] or faster and no torque rolls."""

    start: float
    speed: float
    where: float
    least: float


class _Grid(NamedTuple):
    """What :func:`doomed` reads of a task in a scene: on a grid of |φ|
    [rad], V [J], dV/d|φ| [N·m], J_I [kg·m²], J_I's least on each cell, the cells' widths,
    V's least on each cell, the largest φ'² [rad²/s²] at which some torque rolls moving in
    and out; the starts (:func:`roller_gym.start_set.covering`, past the success band) and
    their fastest speeds in and out [rad/s]."""

    phi: np.ndarray
    V: np.ndarray
    slope: np.ndarray
    inertia: np.ndarray
    cell_j: np.ndarray
    width: np.ndarray
    cell_v: np.ndarray
    most_in: np.ndarray
    most_out: np.ndarray
    starts: np.ndarray
    speed_in: np.ndarray
    speed_out: np.ndarray


#: :func:`_grid`'s answers by task type, torques and scene numbers (a fixed scene's refusal
#: and caution ask for the same); the last CACHED kept.
_GRIDS: dict[tuple, _Grid | None] = {}


def _grid(task: Any, scene: Scene) -> _Grid | None:
    """The :class:`_Grid` of ``task`` in the scalar ``scene``; None where no start lies past
    the success band."""
    key = (type(task), task.max_torque, tuple(task.start_torques), task.success_band,
           *map(float, (*scene.params, scene.mu)))
    if key in _GRIDS:
        return _GRIDS[key]
    if len(_GRIDS) >= start_set.CACHED:
        _GRIDS.clear()
    cover = start_set.covering(task, scene)
    keep = cover.phi > task.success_band
    starts = cover.phi[keep]
    if not starts.size:
        _GRIDS[key] = None
        return None
    torque = task.max_torque
    m, r, kappa, e, k, g, c = scene.params
    far = float(starts[-1])
    phi = np.unique(np.concatenate([np.linspace(0.0, far, GRID_POINTS), starts, np.linspace(
        far, float(max(reach(scene, math.pi), far)), GRID_POINTS)]))
    V = equations.potential(phi, m, r, kappa, e, g)
    slope = equations.dpotential(phi, m, r, kappa, e, g)
    inertia = equations.inertia(phi, m, r, kappa, e, k)
    width = np.diff(phi)
    # V on a cell is at least its smaller end less what its slope takes over half of it.
    cell_v = np.minimum(V[:-1], V[1:]) - 0.5 * width * np.maximum(abs(slope[:-1]),
                                                                  abs(slope[1:]))
    rows = _rows(phi, m, r, kappa, e, k, g, scene.mu)
    # u = τ − cφ' lies in [−T, T + c|φ'|] moving in and [−T − c|φ'|, T] moving out, with
    # |φ'| at most the fastest at which anything rolls with u unbounded that way.
    widest = [np.sqrt(np.maximum(fastest_rolling(*rows, *ends), 0.0))
              for ends in ((-torque, _X_CAP), (-_X_CAP, torque))]
    _GRIDS[key] = _Grid(phi, V, slope, inertia,
                        _cell_inertia(phi, m, r, kappa, e, k, inertia), width, cell_v,
                        fastest_rolling(*rows, -torque, torque + c * widest[0]),
                        fastest_rolling(*rows, -torque - c * widest[1], torque),
                        starts, cover.speed_in[keep], cover.speed_out[keep])
    return _GRIDS[key]


def _one_scene(task: Any, scene: Any) -> None:
    """Raise TypeError unless ``task`` is a task (an instance of a
    :class:`~roller_gym.task.Task` class) and ``scene`` a Scene, ValueError where it is a
    batch: the checks here take one scene."""
    if isinstance(task, type) or not hasattr(task, "max_torque"):
        raise TypeError(f"task={shown(task)} is not a task: pass an instance of a task class, "
                        "e.g. roller_gym.TASKS['RollerHold'](max_torque=1.0)")
    require_scene(scene)
    if scene.batch_size is not None:
        raise ValueError(f"scene={shown(scene)} is a batch of {scene.batch_size} rollers: "
                         "the descent checks take one scene; pass scene.item(i)")


def doomed(task: Any, scene: Scene) -> Doom | None:
    """The nearest start the draw may accept in the scalar ``scene`` (the far end of a cell
    of :func:`roller_gym.start_set.covering`, at rest or at its fastest speed in or out) from
    which the roller must slip or lift off whatever the torque (a :class:`Doom`), or None.

    Two ways: on its way in to the success band, through each stretch where dV/d|φ| >
    max_torque (it cannot stop there) from the stretch's top (at rest, or the start's speed
    where the stretch begins at the start); and, where gravity
    pushes the start away harder than the torque holds (dV/d|φ| < −max_torque), on its way
    out, as long as its least kinetic energy stays positive (it cannot stop, so cannot turn
    back). Checked on a grid of :data:`GRID_POINTS` |φ| out to the starts and as many on
    to ψ = π."""
    _one_scene(task, scene)
    grid = _grid(task, scene)
    if grid is None:
        return None
    (phi, V, slope, inertia, cell_j, width, cell_v, most_in, most_out, starts, speed_in,
     speed_out) = grid
    torque, band = task.max_torque, task.success_band
    c = scene.damping
    forced = slope > torque
    stops = np.where(~forced, np.arange(phi.size), phi.size)
    stop_above = np.minimum.accumulate(stops[::-1])[::-1]  # the next point that may stop

    def spent(anchor: np.ndarray, cells: np.ndarray, kinetic: np.ndarray) -> np.ndarray:
        """The damping's most work [J] on each cell of a run from ``anchor`` with the
        kinetic energy ``kinetic`` [J] there: c·|φ'|max·Δφ, |φ'|max from the most energy the
        run can have on the cell."""
        reach_ = np.maximum(abs(phi[cells] - phi[anchor]), abs(phi[cells + 1] - phi[anchor]))
        most = V[anchor] + kinetic - cell_v[cells] + torque * reach_
        return c * np.sqrt(np.maximum(2.0 * most / cell_j[cells], 0.0)) * width[cells]

    for s, w_in, w_out in zip(np.searchsorted(phi, starts), speed_in, speed_out, strict=True):
        i = np.arange(s + 1)
        a = np.minimum(stop_above[i], s)  # where the way in through i began (at rest, or at s)
        # At s itself the start may move in at up to w_in: its kinetic energy there.
        kinetic = np.where(a == s, 0.5 * inertia[s] * w_in**2, 0.0)
        work = spent(a[:-1], i[:-1], kinetic[:-1])
        below = np.concatenate([np.cumsum(work[::-1])[::-1], [0.0]])  # Σ over cells >= i
        least = 2.0 * (V[a] + kinetic - V[i] - torque * (phi[a] - phi[i])
                       - (below - below[a])) / inertia[i]
        dead = forced[i] & (phi[i] > band) & (least > most_in[i])
        if dead.any():
            j = int(np.flatnonzero(dead)[-1])  # the first met on the way in
            return Doom(float(phi[s]), float(w_in), float(phi[j]),
                        math.sqrt(max(least[j], 0.0)))
        if slope[s] < -torque:  # pushed out
            j = np.arange(s + 1, phi.size)
            kinetic = 0.5 * inertia[s] * w_out**2  # moving out at up to w_out
            energy = (V[s] + kinetic - V[j] - torque * (phi[j] - phi[s])
                      - np.cumsum(spent(np.full(j.size, s), j - 1, np.full(j.size, kinetic))))
            least = 2.0 * energy / inertia[j]
            dead = np.cumprod(energy > 0.0).astype(bool) & (least > most_out[j])
            if dead.any():
                q = int(np.flatnonzero(dead)[0])
                return Doom(float(phi[s]), float(w_out), float(phi[j[q]]),
                            math.sqrt(max(least[q], 0.0)))
    return None


class Verdict(NamedTuple):
    """A fixed scene's verdict (:func:`fixed_scene_problem`): why the task cannot be posed
    there (``refused``, for a ValueError), or why it may still hold starts no policy brings
    down (``caution``, for a warning); None each where there is none."""

    refused: str | None
    caution: str | None


def _way(found: Doom) -> str:
    """Where the doomed start of ``found`` goes."""
    start, _, where, speed = found
    return (f"from a start the draw may take at |phi| up to {start:.4g} rad the roller "
            f"passes |phi| = {where:.4g} rad at {speed:.3g} rad/s or more, where no torque "
            "rolls")


def _refusal(task: Any, scene: Scene, found: Doom) -> str:
    return (f"{task.name} cannot be solved from every start of {shown(scene)} with "
            f"max_torque={task.max_torque:g} N·m: {_way(found)} (gravity outweighs "
            "max_torque on the way, so no torque can stop it before), and slips or lifts "
            "off; use a larger max_torque or mu, or a smaller e")


#: What every caution says of the check.
_NECESSARY = ("The check is a necessary condition, in continuous time, so near it some starts "
              "may still end in a slip or a lift-off whatever the policy")


def _caution(task: Any, scene: Scene, found: Doom) -> str:
    weaker = task.max_torque / NEAR
    return (f"{task.name} in {shown(scene)} with max_torque={task.max_torque:g} N·m is "
            f"accepted, but within {NEAR:g} times the least torque the descent check "
            f"proves necessary: at max_torque={weaker:.3g} N·m, {_way(found)}. {_NECESSARY}; "
            "a larger max_torque or mu, or a smaller e or dt, gives a margin")


def _drum_caution(task: Any, where: str) -> str:
    return (f"{task.name} {where} with max_torque={task.max_torque:g} N·m is accepted, but on "
            "a drum the descent check gives no margin: drums it accepts at up to "
            f"{DRUM_SEEN:g} times the least torque it proves necessary were found with starts "
            f"(moving outward) that no policy brought down at dt = 0.05 s. {_NECESSARY}; try "
            "the hardest starts (reset(options={'state': ...})) before training")


def fixed_scene_problem(task: Any, scene: Scene, dt: float) -> Verdict:
    """:meth:`Task.infeasible` in a scene no ``randomize`` range draws (the construction's
    scenes, ``reset(options={"scene": ...})``), and there, for a task that
    :attr:`~roller_gym.task.Task.descends`, a start :func:`doomed` (refused), or doomed at
    max_torque / :data:`NEAR`, or on any drum (a caution: the rule is a necessary condition
    in continuous time, blind to dt and to friction leaving only part of the torque at
    speed)."""
    _one_scene(task, scene)
    validation.real("dt", dt, positive=True, unit="s")
    reason = task.infeasible(scene, dt)
    if reason is not None or not task.descends:
        return Verdict(reason, None)
    found = doomed(task, scene)
    if found is not None:
        return Verdict(_refusal(task, scene, found), None)
    if scene.shape == "drum":
        return Verdict(None, _drum_caution(task, f"on the drum {shown(scene)}"))
    near = doomed(type(task)(task.max_torque / NEAR), scene)
    return Verdict(None, None if near is None else _caution(task, scene, near))


def range_problem(task: Any, scene: Scene, ranges: Mapping[str, tuple[float, float]]) -> str | None:
    """Why ``task`` cannot be posed over the ``randomize`` box ``ranges`` around ``scene``
    (the other fields): a scene of the box holding a start :func:`doomed` to slip, among its
    middle, every corner (at most 2⁸, one per field's end) and draws from it (:data:`DRAWS`,
    or :data:`DRAWS_PER_FIELD` per field where more); or
    None (also for a task that does not :attr:`~roller_gym.task.Task.descends`). A refusal
    is sound: the draw takes scenes next to that one, where the start stays doomed (the
    conditions are strict). A pass proves nothing between the scenes checked."""
    _one_scene(task, scene)
    ranges = validation.ranges("ranges", ranges)
    if not task.descends or not ranges:
        return None
    return _range_problem(type(task), task.max_torque, tuple(scene.as_dict().items()),
                          tuple(sorted(ranges.items())))


@functools.lru_cache(maxsize=64)
def _range_problem(task_class: type, max_torque: float, scene_items: tuple,
                   range_items: tuple) -> str | None:
    task, scene, ranges = task_class(max_torque), Scene(**dict(scene_items)), dict(range_items)
    rng = np.random.default_rng(0)
    low, high = (np.array(ends) for ends in zip(*ranges.values(), strict=True))
    corners = np.array(list(itertools.product(*ranges.values())))
    draws = max(DRAWS, DRAWS_PER_FIELD * len(ranges))
    drawn = low + (high - low) * rng.random((draws, len(ranges)))
    for values in np.concatenate([[0.5 * (low + high)], corners, drawn]):
        point = dict(zip(ranges, map(float, values), strict=True))
        drawn_scene = scene.replace(**point)
        found = doomed(task, drawn_scene)
        if found is not None:
            where = ", ".join(f"{name}={value:.6g}" for name, value in point.items())
            return (f"randomize={shown(ranges)} draws scenes next to {where}, where "
                    f"{_refusal(task, drawn_scene, found)}, or narrow the ranges away from "
                    "that scene")
    return None


def range_caution(task: Any, scene: Scene, ranges: Mapping[str, tuple[float, float]]) -> str | None:
    """A caution for a ``randomize`` box around ``scene`` that :func:`range_problem` passes:
    where it may draw a drum (``R`` below 0) for a task that
    :attr:`~roller_gym.task.Task.descends` (as :func:`fixed_scene_problem` gives any drum);
    else None. A box whose ends or middle are no scene raises Scene's ValueError, as
    :func:`range_problem` does."""
    _one_scene(task, scene)
    ranges = validation.ranges("ranges", ranges)
    for name, (low, high) in ranges.items():  # a box range_problem refuses as not scenes
        for value in (low, 0.5 * (low + high), high):
            scene.replace(**{name: value})  # (ValueError where not a scene)
    lowest = scene.replace(R=ranges["R"][0]) if "R" in ranges else scene  # (R's low end)
    if not task.descends or lowest.shape != "drum":
        return None
    return _drum_caution(task, f"with randomize={shown(ranges)}, which draws drums,")
