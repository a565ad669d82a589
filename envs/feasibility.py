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
   and its phase per step (``validation.step_phase``: the rates times dt, and the turns a
   held torque's speed adds) <= LARGEST_PHASE_PER_STEP, on intervals.
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
   Balance, :func:`roller_gym.unstable_rest.unstable_rest_enclosure`.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Iterator, Mapping, Sequence

import numpy as np
from roller_gym import start_set, validation
from roller_gym.bounds import Params, box_params, reach_proven
from roller_gym.intervals import Interval
from roller_gym.physics import Scene
from roller_gym.physics.scene import shown
from roller_gym.task import Task

__all__ = ["MAX_BOXES", "Params", "box_params", "check_ranges", "problem"]

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
        ok &= start_set.roll_status(task, phi, phi_dot, m, p.r, p.kappa, p.e, p.k, g, p.c,
                                    p.mu)[1]
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

    def proves(narrower: Mapping[str, tuple[float, float]]) -> bool:
        return _check_ranges_cached(task_class, max_torque, scene_items, dt,
                                    tuple(sorted(narrower.items()))) is None

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
            return _counterexample(ranges, corner, reason, fails, proves)
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
                return _counterexample(ranges, middle, reason, fails, proves)
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
                    reason: str, fails: Callable[[Mapping[str, float]], str | None],
                    proves: Callable[[Mapping[str, tuple[float, float]]], bool]) -> str:
    """The refusal at a point where the task cannot be posed: names the field (of several,
    the one with the longest feasible part of its range through the point) and that part,
    and whether that part, with the other fields' ranges as given, is proven (``proves``):
    the scan's edge is where the task stops being posable, which the proof may not reach."""
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
    feasible = "none"
    if part is not None:
        feasible, low, high = _inward(*part)
        feasible += (
            " (proven with the other ranges as given)" if proves({**ranges, name: (low, high)})
            else " (a scan of it poses the task, but the proof, with the other ranges as "
            "given, does not close on all of it: use a narrower part)")
    return (f"randomize[{shown(name)}]={shown(ranges[name])} cannot be used: at {where} {reason}; "
            f"feasible part of the range: {feasible}")


def _inward(low: float, high: float, digits: int = 6) -> tuple[str, float, float]:
    """[low, high] with its ends rounded inward to ``digits`` significant digits (more where
    that would empty it): as written, and its two ends."""
    for n in range(digits, 18):
        a, b = (_round_to(x, n, up) for x, up in ((low, True), (high, False)))
        if a <= b:
            return f"[{a:.{n}g}, {b:.{n}g}]", a, b
    return f"[{shown(low)}, {shown(high)}]", low, high


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
        return ", ".join(f"{n} in {_inward(lo, hi)[0]}" for n, (lo, hi) in b.items())

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

