"""What a task asks of the roller: start state, target, observation, reward, success.

A task knows the physics (:mod:`roller_gym.physics`) but neither Gymnasium nor pygame. Its
per-step methods take floats (one environment) or arrays (the vector environment) and are
written once for both. The tasks themselves are in ``stabilize.py``, ``hold.py`` and
``balance.py``.

**The position error.** The target is a rest position φ* [rad]. The error is measured
along the configuration, one turn of ψ either way: with the wrap rate q = rκ/(1 − rκ)
(ψ = qφ; q = 1 on the floor, where ψ stays 0 and φ itself is wrapped),

    error = wrap(q (φ − φ*)) / q   [rad of φ],

so the contact point is r·|error| metres of rolling away from its target.

**The observation** (float32, every entry in [−1, 1]):

=====  ==================================================  =====
index  entry                                               unit
=====  ==================================================  =====
0, 1   cos ψ, sin ψ: where the roller is on the surface    1
2, 3   cos φ, sin φ: how it is turned                       1
4      tanh(φ' / speed_scale), speed_scale = 10 rad/s       1
5, 6   cos ψ*, sin ψ* (tasks with a target only)            1
7, 8   cos φ*, sin φ* (tasks with a target only)            1
=====  ==================================================  =====

**The reward** is a product of bounded terms (:mod:`roller_gym.rewards`), in [0, 1] per step:

    reward = near(error, position_margin)
             · (1 − w_v + w_v · near(φ', speed_margin))
             · (1 − w_u + w_u · near(action, 1))

with w_v = 0.5 (being at rest) and w_u = 0.2 (using little torque; action in [−1, 1]).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, ClassVar

import numpy as np
from roller_gym import rewards
from roller_gym.physics import Scene, contact, equations, equilibria, holding_torque

__all__ = ["SPEED_SCALE", "Task", "hold_range", "per_scene", "psi_rate",
           "unstable_rest_positions", "wrap_rate"]

#: The speed [rad/s] at which the observed tanh(φ'/SPEED_SCALE) reaches 0.76.
SPEED_SCALE = 10.0


def wrap_rate(scene: Scene):
    """q = rκ/(1 − rκ) = dψ/dφ on a curved surface, 1 on the floor (float or array)."""
    kappa = np.asarray(scene.kappa, dtype=float)
    q = np.where(kappa == 0, 1.0, scene.r * kappa / (1.0 - scene.r * kappa))
    return float(q) if q.ndim == 0 else q


def psi_rate(scene: Scene) -> float:
    """dψ/dφ = rκ/(1 − rκ) [-] of a scalar scene (0 on the floor)."""
    return float(scene.r * scene.kappa / (1.0 - scene.r * scene.kappa))


class Task:
    """The base of the tasks. Subclasses set the class variables and ``sample_target``."""

    name: ClassVar[str]
    #: The preset the task's scene defaults to.
    default_scene: ClassVar[str] = "paper"
    #: The torque [N·m] an action of ±1 asks for, by default.
    default_max_torque: ClassVar[float] = 0.5
    max_episode_steps: ClassVar[int] = 200
    reward_threshold: ClassVar[float]
    #: Whether the observation carries the target (entries 5 to 8).
    observes_target: ClassVar[bool] = False
    position_margin: ClassVar[float] = 2.0  # rad of φ
    speed_margin: ClassVar[float] = 5.0  # rad/s
    speed_weight: ClassVar[float] = 0.5
    control_weight: ClassVar[float] = 0.2
    #: Success: |error| <= success_band [rad] and |φ'| <= success_speed [rad/s].
    success_band: ClassVar[float] = 0.05
    success_speed: ClassVar[float] = 0.1

    def __init__(self, max_torque: float | None = None) -> None:
        self.max_torque = float(self.default_max_torque if max_torque is None else max_torque)
        if not (math.isfinite(self.max_torque) and self.max_torque > 0):
            raise ValueError(f"max_torque={max_torque!r} [N·m] must be finite and > 0")

    @property
    def observation_size(self) -> int:
        return 9 if self.observes_target else 5

    # -- per episode (arrays of rollers; the uniforms come from the episode core) ------
    #: The start-state rule, as the error message states it when no start state is found.
    start_rule: ClassVar[str] = (
        "within psi = ±60°, |phi_dot| <= 1 rad/s, rolling under every torque within the "
        "limit; lower max_torque or raise mu"
    )

    def check_scene(self, scene: Scene) -> None:
        """Raise ValueError if the task cannot be posed in ``scene`` (default: any scene)."""

    def sample_targets(self, u: np.ndarray, scene: Scene) -> np.ndarray:
        """The rest positions φ* [rad] the episodes ask for, from uniforms ``u`` in [0, 1)
        (one per roller of the batch ``scene``)."""
        raise NotImplementedError

    def start_candidates(
        self, u_phi: np.ndarray, u_dot: np.ndarray, scene: Scene
    ) -> tuple[np.ndarray, np.ndarray]:
        """Candidate start states (φ [rad], φ' [rad/s]) of shape (n, K) from uniforms of that
        shape (``scene`` a batch of n): around the bottom, up to ψ = ±60°, and a speed up
        to ±1 rad/s."""
        q = np.abs(wrap_rate(scene))  # q < 0 on a drum; q = 1 on the floor
        limit = (math.radians(60.0) / np.asarray(q, float)).reshape(-1, 1)
        return limit * (2.0 * u_phi - 1.0), 2.0 * u_dot - 1.0

    def start_accepted(self, phi: np.ndarray, phi_dot: np.ndarray, scene: Scene) -> np.ndarray:
        """Whether the roller rolls at each candidate (N > 0, |F| <= μN) under any torque
        within the limit (−max_torque, 0 and +max_torque)."""
        rows = {f: np.asarray(getattr(scene, f), float).reshape(-1, 1)
                for f in ("m", "r", "e", "k", "g", "mu", "damping")}
        m, r, e, k, g, mu, c = (rows[f] for f in ("m", "r", "e", "k", "g", "mu", "damping"))
        kappa = np.asarray(scene.kappa, float).reshape(-1, 1)
        ok = np.ones(np.broadcast_shapes(phi.shape, m.shape), bool)
        for tau in (-self.max_torque, 0.0, self.max_torque):
            a = equations.accel(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
            normal, friction = equations.contact_forces(phi, phi_dot, a, m, r, kappa, e, g)
            ok &= (normal > 0) & (np.abs(friction) <= mu * normal)
        return ok

    def target_from_option(self, value: Any, scene: Scene) -> float:
        """φ* [rad] from ``reset(options={"target": value})``; tasks with a target override."""
        raise ValueError(f"{self.name} has no target to set; options['target'] is not allowed")

    def default_target(self, scene: Scene) -> float:
        """The target used when none is drawn (for rendering before reset)."""
        return 0.0

    # -- per step (floats or arrays) ---------------------------------------------------
    def error(self, phi, target, q):
        """The position error [rad of φ] (see the module docs); q from :func:`wrap_rate`."""
        return rewards.wrap_angle(q * (phi - target)) / q

    def observation_terms(self, phi, phi_dot, target, psi_rate):
        """The observation's entries as a tuple; ``psi_rate`` = rκ/(1 − rκ) (0 on the floor)."""
        psi = psi_rate * phi
        f = rewards.xp(psi)
        terms = (f.cos(psi), f.sin(psi), f.cos(phi), f.sin(phi), f.tanh(phi_dot / SPEED_SCALE))
        if self.observes_target:
            psi_t = psi_rate * target
            f = rewards.xp(psi_t)
            terms += (f.cos(psi_t), f.sin(psi_t), f.cos(target), f.sin(target))
        return terms

    def reward(self, phi, phi_dot, action, target, q):
        """The reward in [0, 1] (formula in the module docs)."""
        return self.reward_from_error(self.error(phi, target, q), phi_dot, action)

    def success(self, phi, phi_dot, target, q):
        """Inside the tolerance band at rest."""
        return self.success_from_error(self.error(phi, target, q), phi_dot)

    def reward_from_error(self, error, phi_dot, action):
        """:meth:`reward` from the position error already computed."""
        return rewards.near(error, self.position_margin) * rewards.product(
            (rewards.near(phi_dot, self.speed_margin), self.speed_weight),
            (rewards.near(action, 1.0), self.control_weight),
        )

    def success_from_error(self, error, phi_dot):
        """:meth:`success` from the position error already computed."""
        return (abs(error) <= self.success_band) & (abs(phi_dot) <= self.success_speed)


def per_scene(function, scene: Scene) -> np.ndarray:
    """``function(scalar scene)`` for each roller of a batch scene, computed once per
    distinct scene (float results, as an array of the batch's size)."""
    n = scene.batch_size or 1
    rows = np.stack([np.broadcast_to(np.asarray(getattr(scene, f.name), float), (n,))
                     for f in dataclasses.fields(Scene)], axis=1)
    unique, inverse = np.unique(rows, axis=0, return_inverse=True)
    names = [f.name for f in dataclasses.fields(Scene)]
    values = np.array([function(Scene(**dict(zip(names, row, strict=True))))
                       for row in unique], dtype=float)
    return values[np.asarray(inverse).reshape(-1)]


def _cached_per_scene(function):
    """Memoize ``function(scene, *args)`` on the scene's values (resets call it per episode)."""

    @functools.lru_cache(maxsize=1024)
    def cached(values: tuple[tuple[str, float], ...], *args):
        return function(Scene(**dict(values)), *args)

    @functools.wraps(function)
    def wrapper(scene: Scene, *args):
        return cached(tuple(scene.as_dict().items()), *args)

    return wrapper


@_cached_per_scene
def hold_range(scene: Scene, max_torque: float, torque_share: float = 0.8,
               friction_share: float = 0.9, points: int = 2001) -> tuple[float, float]:
    """The interval of rest positions φ [rad] around 0 that can be held at rest.

    Contiguous around φ = 0, within one turn of ψ either way, where the holding torque is
    at most ``torque_share``·max_torque and the contact holds with margin: N > 0 and
    |F| <= ``friction_share``·μN (at rest N = m g cos ψ, F = m g sin ψ).
    """
    q = wrap_rate(scene)
    half = math.pi / abs(q)  # q < 0 on a drum
    bounds = []
    for sign in (1.0, -1.0):
        phi = sign * np.linspace(0.0, half, points)
        c = contact(scene, phi, 0.0, holding_torque(scene, phi))
        normal, friction = np.asarray(c.normal), np.asarray(c.friction)
        ok = (np.abs(holding_torque(scene, phi)) <= torque_share * max_torque) & (normal > 0)
        ok &= np.abs(friction) <= friction_share * scene.mu * normal
        last = int(np.argmin(ok)) - 1 if not ok.all() else points - 1
        bounds.append(float(phi[max(last, 0)]))
    return bounds[1], bounds[0]


@_cached_per_scene
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
