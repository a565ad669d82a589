"""The forced descent from a start: where no torque holds the roller, it rolls on toward the
bottom at a speed the torque cannot take away, and there it may have to slip or lift off.

From a start at rest at |φ| = φs to a target near the bottom, wherever dV/d|φ| > max_torque
the roller cannot stop; by the power balance (``docs/PHYSICS.md``) its kinetic energy at φ is
then at least V(φa) − V(φ) − max_torque·(φa − φ) − the damping's work, φa the last point
where it could have stopped. N and F are affine in (φ'², τ − cφ'), so whether some speed
above that and some torque roll at φ is a linear program in two variables
(:func:`fastest_rolling`). A start where one has none is doomed: every episode from it ends
in a slip or a lift-off, whatever the policy. :func:`doomed` finds the nearest such start of
a task's accepted ones in a scalar scene, and :func:`fixed_scene_problem` refuses a fixed
scene with one. Over ``randomize`` ranges it is not yet proven (``docs/MAINTAINERS.md``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from roller_gym.physics import Scene, equations
from roller_gym.physics.scene import shown

__all__ = ["doomed", "fastest_rolling", "fixed_scene_problem", "slips_on_descent"]

#: Points of the scalar check's grid of |φ| from the bottom to the farthest accepted start.
GRID_POINTS = 2001
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


def doomed(task: Any, scene: Scene) -> tuple[float, float, float] | None:
    """The nearest of ``task``'s accepted starts (at rest, :meth:`Task.accepted_starts`) in
    the scalar ``scene`` from which the roller must slip or lift off on its way down to the
    success band, whatever the torque:
    (its |φ| [rad], the |φ| [rad] where, the least speed [rad/s] there), or None. Checked on
    a grid of :data:`GRID_POINTS` |φ| (and the starts)."""
    starts = np.unique(task.accepted_starts(scene))
    starts = starts[starts > task.success_band]
    if not starts.size:
        return None
    torque = task.max_torque
    m, r, kappa, e, k, g, c = scene.params
    phi = np.unique(np.concatenate([np.linspace(0.0, starts[-1], GRID_POINTS), starts]))
    V = equations.potential(phi, m, r, kappa, e, g)
    forced = equations.dpotential(phi, m, r, kappa, e, g) > torque
    j_least = m * (k * k + (r - e) ** 2)  # J_I >= m (k² + (r − e)²)
    fastest = math.sqrt(max(2.0 * (V.max() - V.min() + torque * phi[-1]) / j_least, 0.0))
    most = fastest_rolling(*_rows(phi, m, r, kappa, e, k, g, scene.mu), -torque,
                           torque + c * fastest)
    # The next point at or above each where the roller could stop (an index past the end).
    stops = np.where(~forced, np.arange(phi.size), phi.size)
    stop_above = np.minimum.accumulate(stops[::-1])[::-1]
    inertia = equations.inertia(phi, m, r, kappa, e, k)
    for s in np.searchsorted(phi, starts):
        i = np.arange(s + 1)
        a = np.minimum(stop_above[i], s)  # where the descent through i began at rest
        gained = V[a] - V[i]
        worked = torque * (phi[a] - phi[i])
        # The damping's work from a down to i, at most c·Σ φ'_max Δφ with φ'_max from the
        # energy at each cell's lower end (V rises with |φ| where the roller is forced).
        fast = np.sqrt(np.maximum(2.0 * (gained + worked) / j_least, 0.0))
        cell = c * fast[:-1] * np.diff(phi[: s + 1])
        below = np.concatenate([np.cumsum(cell[::-1])[::-1], [0.0]])  # Σ over cells >= i
        spent = below - below[a]
        least = 2.0 * (gained - worked - spent) / inertia[: s + 1]
        dead = forced[: s + 1] & (phi[: s + 1] > task.success_band) & (least > most[: s + 1])
        if dead.any():
            j = int(np.flatnonzero(dead)[-1])  # the first met on the way down
            return float(phi[s]), float(phi[j]), math.sqrt(max(least[j], 0.0))
    return None


def slips_on_descent(task: Any, scene: Scene) -> str | None:
    """Why ``task`` cannot be posed in the scalar ``scene`` for a doomed start
    (:func:`doomed`), or None."""
    found = doomed(task, scene)
    if found is None:
        return None
    start, where, speed = found
    return (f"{task.name} cannot be solved from every start of {shown(scene)} with "
            f"max_torque={task.max_torque:g} N·m: from the start at rest at |phi| = "
            f"{start:.4g} rad no torque can stop the roller before |phi| = {where:.4g} rad "
            f"(dV/dphi > max_torque there), where it passes at {speed:.3g} rad/s or more and "
            "slips or lifts off under every torque; use a larger max_torque or mu, or a "
            "smaller e")


def fixed_scene_problem(task: Any, scene: Scene, dt: float) -> str | None:
    """:meth:`Task.infeasible` in a scene no ``randomize`` range draws (the construction's
    scenes, ``reset(options={"scene": ...})``), and there, for a task that
    :attr:`~roller_gym.task.Task.descends`, :func:`slips_on_descent`."""
    reason = task.infeasible(scene, dt)
    if reason is None and task.descends:
        reason = slips_on_descent(task, scene)
    return reason
