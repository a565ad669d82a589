"""Proof that a task can be posed in every scene of a box of ``randomize`` ranges.

:func:`check_ranges` runs a branch and bound over the box of ranges. A box is *proven* when
every condition of :func:`problem` holds for every scene in it, shown by evaluating the same
equations (:mod:`roller_gym.physics.equations`, :func:`roller_gym.validation.
integration_magnitudes` and ``integration_rates``) on intervals
(:mod:`roller_gym.intervals`, outward rounding). Otherwise the float check
(:func:`problem`) runs at the box's midpoint: a failure there is a counterexample, and the
range is refused with the field, the point, the reason and a feasible part of the field's
range; else the box is split in two along its widest field (relative to that field's
range) and both halves are examined. A range is accepted only when the whole box is covered
by proven boxes; if that takes more than :data:`MAX_BOXES` boxes the range is refused as
not proven, naming what was proven.

What is proven on a box B (the conditions of :func:`problem`, in exact arithmetic):

1. :func:`roller_gym.validation.check_integrable`: m g r and J_min within [1e-100, 1e100]
   and (ω_max + spin + c/J_min)·dt <= LARGEST_PHASE_PER_STEP, on intervals.
2. A start state (:meth:`Task.fallback_start`): one of the fixed candidates rolls (N > 0,
   |F| <= μN) under −max_torque, 0 and +max_torque for every scene of B. Each candidate's
   φ and φ' are enclosed by their hull over B's corners: for the tasks here they are
   monotone in each field (Balance: constants; the others: (π/3)(2u − 1)/|q| with
   |q| = |rκ/(1 − rκ)| monotone in r and in R on either side of R = 0, which a range cannot
   cross).
3. The target within reach (:func:`roller_gym.bounds.reach_proven`): the least times of
   :func:`roller_gym.bounds.least_times` from every start (|φ| up to the far end of the
   farthest cell between candidates of 2. where a start at rest or moving may roll) within
   the task's share of the episode, and the unaided time from the farthest start (from the
   farthest candidate proven to roll) past it.
4. The task's own condition (:meth:`Task.scene_proven`): none for Stabilize and Hold; for
   Balance, :func:`unstable_rest_enclosure`.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence
from typing import Any

import numpy as np
from roller_gym import start_set, validation
from roller_gym.bounds import Params, box_params, reach_proven
from roller_gym.intervals import Interval
from roller_gym.physics import Scene, equations
from roller_gym.physics.analysis import MAX_TURNS, nearest_unstable_rests
from roller_gym.physics.scene import shown
from roller_gym.task import Task, unstable_rest_positions

__all__ = ["MAX_BOXES", "Params", "box_params", "check_ranges", "problem",
           "rolls_proven", "unstable_rest_enclosure"]

#: The most boxes the branch and bound examines before it refuses a range as not proven.
MAX_BOXES = 4000
#: Boxes narrower than this share of their field's range (every field) are not split again.
SMALLEST_SHARE = 1e-5
#: The most such boxes (neither proven nor refuted) before the proof gives up.
MAX_STALLED = 4
#: The proof also gives up when more than MAX_FINE boxes narrower than FINE_SHARE of their
#: fields' ranges are unproven at one depth: a region the enclosures cannot close at any
#: resolution (there the unproven boxes double with every depth), not the edge of one.
FINE_SHARE = 1e-3
MAX_FINE = 16
#: Points of the scan along a field that names the feasible part of its range.
SCAN_POINTS = 33

Box = dict[str, tuple[float, float]]


def problem(task: Task, scene: Scene, dt: float) -> str | None:
    """Why ``task`` cannot be posed in the scalar ``scene`` with steps of ``dt`` [s], or None:
    :func:`validation.check_integrable`, then :meth:`Task.infeasible` (floats, one scene)."""
    try:
        validation.check_integrable(scene, dt, task.max_torque, task.start_speed)
    except ValueError as error:
        return str(error)
    return task.infeasible(scene, dt)


def _posable(task: Task, scene: Scene, dt: float,
             points: Sequence[Mapping[str, float]]) -> Iterator[bool]:
    """For each point of the box of ranges, whether :func:`problem` finds nothing there: for
    a task without a condition of its own, :func:`problem`'s checks on all points at once
    (floats; the same equations), True where they pass; else False (ask :func:`problem`)."""
    if not points or type(task).check_scene is not Task.check_scene:
        return iter([False] * len(points))
    names = list(points[0])
    batch = scene.replace(**{n: np.array([p[n] for p in points], float) for n in names})
    m, r, kappa, e, k, g, c = (np.broadcast_to(np.asarray(x, float), (len(points),))
                               for x in batch.params)
    with np.errstate(all="ignore"):
        weight_arm, j_min = validation.integration_magnitudes(m, r, e, k, g)
        rates = validation.integration_rates(m, r, kappa, e, g, c, j_min, task.max_torque,
                                             task.start_speed)
        ok = validation.step_phase(rates, dt) <= validation.LARGEST_PHASE_PER_STEP
        for x in (weight_arm, j_min):
            ok &= (np.abs(x) >= validation.SMALLEST) & (np.abs(x) <= validation.LARGEST)
    ok &= (task.max_torque >= validation.SMALLEST) & (task.max_torque <= validation.LARGEST)
    phi, phi_dot = task.fallback_candidates(batch)
    ok &= task.start_accepted(phi, phi_dot, batch).any(axis=1)
    return iter(ok.tolist())


# -- the conditions on boxes, many at once (arrays of intervals, one element a box) ---------
def _boxes_params(scene: Scene, boxes: Sequence[Box]) -> Params:
    """:func:`box_params` of many boxes of the same fields: intervals of shape (len(boxes),)."""
    n = len(boxes)

    def field(name: str) -> Interval:
        if name in boxes[0]:
            ends = np.array([b[name] for b in boxes], float).reshape(n, 2)
            return Interval(ends[:, 0], ends[:, 1])
        return Interval(np.full(n, float(getattr(scene, name))))

    kappa = 1.0 / field("R") if "R" in boxes[0] else Interval(np.full(n, float(scene.kappa)))
    return Params(field("m"), field("r"), kappa, field("e"), field("k"), field("g"),
                  field("damping"), field("mu"))


def _integrable_proven(p: Params, dt: float, max_torque: float,
                       start_speed: float) -> np.ndarray:
    weight_arm, j_min = validation.integration_magnitudes(p.m, p.r, p.e, p.k, p.g)
    ok = np.ones(np.shape(p.m.lo), bool)
    for x in (weight_arm, j_min):
        size = abs(x)
        ok &= (size.lo >= validation.SMALLEST) & (size.hi <= validation.LARGEST)
    # The rates with m scaled out (J_min ∝ m; ω_max does not depend on m, spin² and decay
    # are ∝ 1/m: largest at the least m), so that m's range is not counted twice.
    least = Interval(p.m.lo)
    _, j_unit = validation.integration_magnitudes(1.0, p.r, p.e, p.k, p.g)
    rates = validation.integration_rates(1.0, p.r, p.kappa, p.e, p.g, p.c / least, j_unit,
                                         max_torque / least, start_speed)
    return ok & (validation.step_phase(rates, dt).hi <= validation.LARGEST_PHASE_PER_STEP)


def _corners(scene: Scene, boxes: Sequence[Box]) -> Scene:
    """The corners of every box as one batch scene (box by box, 2^fields corners each)."""
    names = list(boxes[0])
    values = np.array([list(itertools.product(*(b[n] for n in names))) for b in boxes],
                      float).reshape(-1, len(names))
    return scene.replace(**{n: values[:, i] for i, n in enumerate(names)})


def _starts_proven(task: Task, scene: Scene, boxes: Sequence[Box],
                   p: Params) -> tuple[np.ndarray, Interval]:
    """Whether, for each box, one start candidate rolls in all its scenes; and an interval
    holding each box's farthest start the draw may take: from the farthest candidate proven
    to roll to the far end of the farthest cell between neighbouring candidates where a start
    at rest or moving may roll (:func:`roller_gym.start_set.roll_status`) in some scene."""
    n = len(boxes)
    corners = _corners(scene, boxes) if boxes[0] else scene
    phi, phi_dot = task.fallback_candidates(corners)
    phi, phi_dot = (Interval.hull(x.reshape(n, -1, x.shape[-1]), axis=1)
                    for x in (phi, phi_dot))  # (boxes, candidates)
    pieces = start_set.speed_pieces(task, corners)  # (corners of every box, pieces)
    speeds = Interval(pieces.lo.reshape(n, -1, pieces.lo.shape[-1]).min(axis=1)[:, None, :],
                      pieces.hi.reshape(n, -1, pieces.hi.shape[-1]).max(axis=1)[:, None, :])
    p = Params(*(Interval(x.lo[:, None], x.hi[:, None]) for x in p))
    weights = [(p.m, p.g)]
    if not (phi_dot.lo.any() or phi_dot.hi.any()):
        # At rest (φ' = 0) φ'' = (τ − dV/dφ)/J_I, and N/(m g), F/(m g) are affine in
        # τ/(m g) (m and g enter only so); N > 0 and μN − |F| >= 0 (concave in it) hold for
        # every m g of the box where they hold at its least and at its largest m g.
        weights = [(Interval(p.m.lo), Interval(p.g.lo)), (Interval(p.m.hi), Interval(p.g.hi))]
    ok = np.ones(np.shape(phi.lo), bool)
    for m, g in weights:
        for normal, friction in task.start_contacts(phi, phi_dot, m, p.r, p.kappa, p.e, p.k,
                                                    g, p.c):
            ok &= (normal.lo > 0) & (abs(friction).hi <= (p.mu * normal).lo)
    # The cells between the grid's neighbouring candidates (after the first, the middle).
    cells = Interval(np.minimum(phi.lo[:, 1:-1], phi.lo[:, 2:]),
                     np.maximum(phi.hi[:, 1:-1], phi.hi[:, 2:]))
    q = Params(*(Interval(x.lo[:, :, None], x.hi[:, :, None]) for x in p))
    may = start_set.roll_status(task, Interval(cells.lo[:, :, None], cells.hi[:, :, None]),
                                speeds, q.m, q.r, q.kappa, q.e, q.k, q.g, q.c,
                                q.mu)[0].any(axis=2)
    return ok.any(axis=1), Interval(np.max(np.where(ok, abs(phi).lo, 0.0), axis=1),
                                    np.max(np.where(may, abs(cells).hi, 0.0), axis=1))


def _boxes_proven(task: Task, scene: Scene, dt: float, boxes: Sequence[Box],
                  ranges: Box) -> np.ndarray:
    """Whether each box is proven: the conditions common to the tasks on all boxes at once,
    then the task's own (:meth:`Task.scene_proven`) box by box where it has one."""
    with np.errstate(all="ignore"):  # infinities and NaN prove nothing (see intervals)
        p = _boxes_params(scene, boxes)
        starts, farthest = _starts_proven(task, scene, boxes, p)
        ok = (_integrable_proven(p, dt, task.max_torque, task.start_speed) & starts
              & reach_proven(task, p, dt, farthest))
        if type(task).scene_proven is not Task.scene_proven:
            for i in np.flatnonzero(ok):
                estimates = (scene.replace(**_middle(boxes[i])),  # the nearer first
                             scene.replace(**_middle(ranges)))
                ok[i] = task.scene_proven(box_params(scene, boxes[i]), estimates, dt)
    return ok


# -- Balance: the unstable rest position ------------------------------------------------------
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


# -- the branch and bound ---------------------------------------------------------------------
def _middle(box: Box) -> dict[str, float]:
    return {n: 0.5 * lo + 0.5 * hi for n, (lo, hi) in box.items()}


def _middle_key(box: Box) -> tuple[float, ...]:
    return tuple(_middle(box).values())


#: A range whose ends (of one sign) are more than this ratio apart is split geometrically.
GEOMETRIC_RATIO = 100.0


def _geometric(low: float, high: float) -> bool:
    return (low > 0 and high > GEOMETRIC_RATIO * low) or (high < 0 and low < GEOMETRIC_RATIO * high)


def _share(part: tuple[float, float], whole: tuple[float, float]) -> float:
    """How much of a field's range ``whole`` a box's ``part`` covers: on a log scale where the
    range spans orders of magnitude (:data:`GEOMETRIC_RATIO`), else linearly."""
    if _geometric(*whole):  # (logs of each end: a ratio of ends near float64's top overflows)
        return ((math.log(abs(part[1])) - math.log(abs(part[0])))
                / (math.log(abs(whole[1])) - math.log(abs(whole[0]))))
    return (part[1] - part[0]) / (whole[1] - whole[0])


def _split(low: float, high: float, whole: tuple[float, float]) -> float:
    """Where a box's side [low, high] is split: its geometric middle where the field's range
    spans orders of magnitude, so that each decade is examined alike; else its middle."""
    if _geometric(*whole):
        return math.copysign(math.sqrt(abs(low)) * math.sqrt(abs(high)), low)  # (no overflow)
    return 0.5 * low + 0.5 * high


def check_ranges(task: Task, scene: Scene, dt: float,
                 ranges: Mapping[str, tuple[float, float]]) -> None:
    """Raise ValueError unless ``task`` is proven to be posable in every scene of the box
    of ``ranges`` (each field's own rule already checked); see the module docs."""
    key = (type(task), task.max_torque, tuple(scene.as_dict().items()), dt,
           tuple(sorted(ranges.items())))
    message = _check_ranges_cached(*key)
    if message is not None:
        raise ValueError(message)


@functools.lru_cache(maxsize=256)
def _check_ranges_cached(task_class: type[Task], max_torque: float,
                         scene_items: tuple[tuple[str, float], ...], dt: float,
                         range_items: tuple[tuple[str, tuple[float, float]], ...]) -> str | None:
    task, scene, ranges = task_class(max_torque), Scene(**dict(scene_items)), dict(range_items)

    def fails(values: Mapping[str, float]) -> str | None:
        return problem(task, scene.replace(**values), dt)

    if (type(task).scene_proven is Task.scene_proven
            and not task.scene_proven(None, (), dt)):  # (a condition with no proof of it)
        return (f"randomize={shown(ranges)} cannot be used with {task.name}: the task has its own "
                "condition on the scene (check_scene, pump_time) and no proof of it over a "
                "range of scenes (scene_proven), so that every scene of the range can pose it "
                "cannot be shown; use a fixed scene")
    names = list(ranges)
    for ends in itertools.product(*(ranges[n] for n in names)):  # a quick look first
        corner = dict(zip(names, ends, strict=True))
        reason = fails(corner)
        if reason is not None:
            return _counterexample(ranges, corner, reason, fails)
    width = {n: hi - lo for n, (lo, hi) in ranges.items()}
    frontier: list[Box] = [dict(ranges)]  # the boxes of one depth, examined together
    proven: list[Box] = []
    stalled: list[Box] = []  # boxes split as finely as allowed, neither proven nor refuted
    examined = 0
    while frontier:
        batch, left = frontier[:MAX_BOXES - examined], frontier[MAX_BOXES - examined:]
        examined += len(batch)
        deeper: list[Box] = []
        ok = _boxes_proven(task, scene, dt, batch, ranges)
        posable = _posable(task, scene, dt, [_middle(b) for b, good in zip(batch, ok,
                                                                           strict=True)
                                             if not good])
        fine: list[Box] = []
        for box, good in zip(batch, ok, strict=True):
            if good:
                proven.append(box)
                continue
            middle = _middle(box)
            reason = None if next(posable) else fails(middle)
            if reason is not None:
                return _counterexample(ranges, middle, reason, fails)
            shares = {n: _share(box[n], ranges[n]) for n in names if width[n] > 0}
            widest = max(shares, key=shares.get, default=None)
            if widest is not None and shares[widest] < FINE_SHARE:
                fine.append(box)
                if len(fine) > MAX_FINE:
                    return _not_proven(ranges, proven, sorted(fine, key=_middle_key),
                                       "however finely the box is split")
            if widest is None or shares[widest] < SMALLEST_SHARE:
                stalled.append(box)  # the rest of the box of ranges is examined all the same
                if len(stalled) >= MAX_STALLED:  # (its coarser boxes were, at lower depths)
                    return _not_proven(ranges, proven, stalled,
                                       "however finely the box is split")
                continue
            lo, hi = box[widest]
            split = _split(lo, hi, ranges[widest])
            deeper += [{**box, widest: (lo, split)}, {**box, widest: (split, hi)}]
        if left:
            return _not_proven(ranges, proven, [*stalled, left[0]], f"within {MAX_BOXES} boxes")
        frontier = deeper
    if stalled:
        return _not_proven(ranges, proven, stalled, "however finely the box is split")
    return None


def _counterexample(ranges: Mapping[str, tuple[float, float]], point: Mapping[str, float],
                    reason: str, fails: Callable[[Mapping[str, float]], str | None]) -> str:
    """The refusal at a point where the task cannot be posed: names the field (of several,
    the one with the longest feasible part of its range through the point) and that part."""
    best = None
    for name, (low, high) in ranges.items():
        def ok(v: float, n: str = name) -> bool:
            return fails({**point, n: v}) is None

        part = _feasible_part(ok, low, high, point[name])
        share = 0.0 if part is None else (part[1] - part[0]) / (high - low or 1.0)
        if best is None or share > best[0]:
            best = (share, name, part)
    _, name, part = best
    others = {n: v for n, v in point.items() if n != name}
    where = f"{name} = {point[name]:.6g}" + (f" (other fields at {others})" if others else "")
    feasible = "none" if part is None else _inward(*part)
    return (f"randomize[{shown(name)}]={shown(ranges[name])} cannot be used: at {where} {reason}; "
            f"feasible part of the range: {feasible}")


def _inward(low: float, high: float, digits: int = 6) -> str:
    """[low, high] with its ends rounded inward to ``digits`` significant digits (more where
    that would empty it)."""
    for n in range(digits, 18):
        a, b = (_round_to(x, n, up) for x, up in ((low, True), (high, False)))
        if a <= b:
            return f"[{a:.{n}g}, {b:.{n}g}]"
    return f"[{shown(low)}, {shown(high)}]"


def _round_to(x: float, digits: int, up: bool) -> float:
    if x == 0 or not math.isfinite(x):
        return x
    scale = 10.0 ** (digits - 1 - math.floor(math.log10(abs(x))))
    y = (math.ceil if up else math.floor)(x * scale) / scale
    return y if (y >= x if up else y <= x) else x  # keep the direction despite rounding


def _not_proven(ranges: Mapping[str, tuple[float, float]], proven: list[Box],
                stalled: list[Box], how: str) -> str:
    """The refusal when the proof does not close (no counterexample found either): says
    that the range may be feasible, where the proof stalled, and what was proven (for one
    field, every proven run of it, on both sides of the stalls)."""
    def show(b: Mapping[str, tuple[float, float]]) -> str:
        return ", ".join(f"{n} in {_inward(lo, hi)}" for n, (lo, hi) in b.items())

    def runs(boxes: list[Box]) -> list[Box]:  # one field: touching boxes merged
        (name,) = ranges
        merged: list[list[float]] = []
        for lo, hi in sorted(b[name] for b in boxes):
            if merged and lo <= merged[-1][1]:
                merged[-1][1] = max(merged[-1][1], hi)
            else:
                merged.append([lo, hi])
        return [{name: (lo, hi)} for lo, hi in merged]

    if len(ranges) == 1:
        stalled = runs(stalled)
    if len(ranges) == 1 and proven:  # the runs of proven intervals
        done = " and ".join(show(b) for b in runs(proven))
    elif proven:
        def share(b: Box) -> float:
            return math.prod((hi - lo) / (ranges[n][1] - ranges[n][0]) for n, (lo, hi)
                             in b.items() if ranges[n][1] > ranges[n][0])

        done = f"the largest proven box is {show(max(proven, key=share))}"
    else:
        done = "nothing"
    where = "; ".join(show(b) for b in stalled[:MAX_STALLED])
    if len(stalled) > MAX_STALLED:
        where += f"; and {len(stalled) - MAX_STALLED} more boxes"
    return (f"randomize={shown(dict(ranges))} cannot be used: it may be feasible (no scene of it "
            "was found where the task cannot be posed), but that the task can be posed in "
            f"every scene of it could not be proven {how} (the proof does not close on "
            f"{where}); proven: {done}. Narrow the ranges to a proven part")


def _feasible_part(ok: Callable[[float], bool], low: float, high: float,
                   bad: float | None = None) -> tuple[float, float] | None:
    """The longest feasible run of a scan of [low, high] (``bad``, a known infeasible value,
    among the points), its ends refined by bisection to 1e-6 of the range's width (both on
    a log scale where the range spans orders of magnitude: :func:`_split`)."""
    geometric = _geometric(low, high)
    points = (np.copysign(np.geomspace(abs(low), abs(high), SCAN_POINTS), low) if geometric
              else np.linspace(low, high, SCAN_POINTS))
    grid = np.union1d(points, [] if bad is None else [bad])
    flags = [v != bad and ok(float(v)) for v in grid]
    best, start = None, None
    for i, flag in enumerate([*flags, False]):
        if flag and start is None:
            start = i
        if not flag and start is not None:
            if best is None or i - start > best[1] - best[0]:
                best = (start, i - 1)
            start = None
    if best is None:
        return None
    ends = []
    for inside, step in ((best[0], -1), (best[1], 1)):
        a = float(grid[inside])
        outside = inside + step
        if not 0 <= outside < grid.size:
            ends.append(a)
            continue
        b = float(grid[outside])
        for _ in range(60):
            if _share((min(a, b), max(a, b)), (low, high)) <= 1e-6:
                break
            mid = _split(min(a, b), max(a, b), (low, high))
            a, b = (mid, b) if ok(mid) else (a, mid)
        ends.append(a)
    return min(ends), max(ends)

