"""Every start the draw may accept in a scene: what the checks on starts (the least times,
the damping's unaided time, the forced descent) must count.

The draw (:mod:`roller_gym.episode.starts`) takes uniform candidates (φ, φ') over the task's
start range (:meth:`~roller_gym.task.Task.start_candidates`) and accepts one that rolls under
every torque of :attr:`~roller_gym.task.Task.start_torques`. That set need not be an
interval of |φ|, nor lie within the starts at rest: with a speed the roller may roll where at
rest it slips. :func:`roll_status` encloses the contact forces over a box of states (and of
scenes: the proofs over ``randomize`` ranges, :mod:`roller_gym.feasibility`) on intervals
(:mod:`roller_gym.intervals`): a box where no torque is proven to make the roller slip or
lift off may hold an accepted start. :func:`covering` halves such boxes in a scalar scene
until each is decided or small, so the starts it counts hold every accepted one and little
more.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from roller_gym.intervals import Interval
from roller_gym.physics import Scene

__all__ = ["CACHED", "DEPTH", "SPEED_PIECES", "Starts", "cover", "covering", "roll_status",
           "speed_pieces"]

#: The pieces the start speeds ±start_speed are cut into (an even number: φ' = 0 an edge).
SPEED_PIECES = 4
#: The most halvings of a box :func:`covering` makes where it is undecided.
DEPTH = 6


class Starts(NamedTuple):
    """Starts the draw accepts, at ``phi`` [rad] (|φ|, ascending), and the largest |φ'|
    [rad/s] at which it accepts each moving toward the bottom (``speed_in``) and away from
    it (``speed_out``); 0 where none moving that way is accepted."""

    phi: np.ndarray
    speed_in: np.ndarray
    speed_out: np.ndarray


def speed_pieces(task: Any, scene: Scene) -> Interval:
    """The draw's start speeds φ' [rad/s] cut into :data:`SPEED_PIECES` intervals, shape
    (n, pieces) for a batch ``scene`` of n (1 for a scalar one), each enclosing its piece
    over the scenes (as the task's candidates are monotone in each field)."""
    w = np.linspace(0.0, 1.0, SPEED_PIECES + 1)[None, :]
    w = w.repeat(scene.batch_size or 1, axis=0)
    _, speeds = task.start_candidates(np.full_like(w, 0.5), w, scene)
    return Interval(np.minimum(speeds[:, :-1], speeds[:, 1:]),
                    np.maximum(speeds[:, :-1], speeds[:, 1:]))


def roll_status(task: Any, phi: Any, phi_dot: Any, m: Any, r: Any, kappa: Any, e: Any,
                k: Any, g: Any, c: Any, mu: Any) -> tuple[np.ndarray, np.ndarray]:
    """Whether a start in the box φ [rad] × φ' [rad/s] (intervals; the scene's numbers floats
    or intervals, broadcast) may roll, and whether it surely rolls, under every torque of
    :attr:`~roller_gym.task.Task.start_torques` (N > 0, |F| <= μN): (may, sure). ``may``
    is False where one torque is proven to make it lift off or slip throughout; ``sure``
    True where every torque is proven to roll throughout. NaN ends prove nothing."""
    may, sure = True, True
    with np.errstate(all="ignore"):
        for normal, friction in task.start_contacts(phi, phi_dot, m, r, kappa, e, k, g, c):
            most, least = mu * normal, abs(friction)
            may = may & ~((normal.hi <= 0.0) | (least.lo > most.hi))
            sure = sure & (normal.lo > 0.0) & (least.hi <= most.lo)
    return np.asarray(may), np.asarray(sure)


#: :func:`covering`'s answers by (task type, start torques, scene numbers): each fixed scene's
#: checks (its least times, its descent) ask for the same; the first CACHED kept.
_KEPT: dict[tuple, Starts] = {}
CACHED = 256


def covering(task: Any, scene: Scene) -> Starts:
    """:func:`cover`, kept for the next check of the same task and scene."""
    key = (type(task), tuple(task.start_torques), *map(float, (*scene.params, scene.mu)))
    if key not in _KEPT:
        if len(_KEPT) >= CACHED:
            _KEPT.clear()
        _KEPT[key] = cover(task, scene)
    return _KEPT[key]


def cover(task: Any, scene: Scene) -> Starts:
    """The starts the draw may accept in the scalar ``scene`` (φ >= 0: the range is
    symmetric in (φ, φ') → (−φ, −φ')), by the cells between the task's
    :attr:`~roller_gym.task.Task.start_points` candidates: boxes of a cell and a piece of
    speed (:func:`speed_pieces`) are halved in φ and φ' where :func:`roll_status` leaves
    them undecided, down to :data:`DEPTH` halvings. Of each cell that keeps a box, the far
    end of its farthest box, and the fastest speed in and out of its boxes: every accepted
    start lies in a cell whose ``phi`` is at or past it, and within its speeds."""
    u = np.linspace(0.5, 1.0, task.start_points)[None, :]
    edges = task.start_candidates(u, np.full_like(u, 0.5), scene)[0][0]
    pieces = speed_pieces(task, scene)
    cells, piece = (x.ravel() for x in np.meshgrid(np.arange(edges.size - 1),
                                                   np.arange(pieces.lo.shape[1]),
                                                   indexing="ij"))
    boxes = [edges[cells], edges[cells + 1], pieces.lo[0, piece], pieces.hi[0, piece], cells]
    n = edges.size - 1
    far, fastest = np.full(n, -np.inf), np.zeros((2, n))  # of the boxes kept, by cell

    def ways(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, ...]]:
        """The boxes' fastest |φ'| and whether they move in, or out (φ >= 0: in is φ' <= 0;
        a piece never straddles 0), each way a row of ``fastest``."""
        return np.maximum(abs(lo), abs(hi)), (hi <= 0.0, lo >= 0.0)

    for depth in range(DEPTH + 1):
        may, sure = roll_status(task, Interval(*boxes[:2]), Interval(*boxes[2:4]),
                                *scene.params, scene.mu)
        done = sure | (may & (depth == DEPTH))
        _, b, lo, hi, cell = (x[done] for x in boxes)
        speed, moving = ways(lo, hi)
        np.maximum.at(far, cell, b)
        for row, way in enumerate(moving):
            np.maximum.at(fastest[row], cell[way], speed[way])
        a, b, lo, hi, cell = (x[may & ~done] for x in boxes)
        speed, moving = ways(lo, hi)
        gains = b > far[cell]  # the boxes that could move their cell's far end or a speed
        for row, way in enumerate(moving):
            gains |= way & (speed > fastest[row, cell])
        a, b, lo, hi, cell = (x[gains] for x in (a, b, lo, hi, cell))
        mid, half = 0.5 * (a + b), 0.5 * (lo + hi)  # four halves of each undecided box
        boxes = [np.concatenate(x) for x in ((a, mid, a, mid), (mid, b, mid, b),
                                             (lo, lo, half, half), (half, half, hi, hi),
                                             (cell,) * 4)]
    held = np.isfinite(far)
    return Starts(far[held], fastest[0, held], fastest[1, held])
