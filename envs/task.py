"""What a task asks of the roller: start state, target, observation, reward, success.

A task knows the physics (:mod:`roller_gym.physics`) but neither Gymnasium nor pygame. Its
per-episode methods (targets, start states) take arrays of rollers. Its per-step formulas
(position error, reward, success, observation) are this module's compiled functions, the
same for every task and parametrized by the task's class variables (:data:`TASK_CONSTANTS`);
the single and the vector environment run them in one compiled kernel
(:func:`roller_gym.episode.outcome`). Each task is one class in its own module (``stabilize.py``,
``hold.py``, ``balance.py``, ``track.py``), added to the registry :data:`TASKS` by the decorator
:func:`register`, as dm_control's suite does; registration with Gymnasium, the agents,
the scripts and the tests iterate over the registry. A new task is one class in a module of
its own, listed in ``roller_gym.TASK_MODULES``, with its hyperparameters (README, "Adding a
task").

**The position error.** The target is a rest position φ* [rad]. The error is measured
along the configuration, one turn of ψ either way: with the wrap rate q = rκ/(1 − rκ)
(ψ = qφ; q = 1 on the floor, where ψ stays 0 and φ itself is wrapped),

    error = wrap(q (φ − φ*)) / q   [rad of φ],

so the contact point is r·|error| metres of rolling away from its target.

**The observation** (float32, every entry in [−1, 1]) is a tuple of named fields, each
declared once in :data:`OBSERVATION_FIELDS`; a task lists the ones it observes, in order,
in ``Task.observation``, and agents read them by name (:meth:`Task.index`).

**The reward** (:func:`step_reward`) is a product of bounded terms (:mod:`roller_gym.rewards`),
in [0, 1] per step, the same formula for every task with each task's weights; a new term is
a function there, a weighted factor in :func:`step_reward` and its weight's name in
:data:`TASK_CONSTANTS` (README, "Adding a task"):

    reward = position(ε)
             · (1 − w_v + w_v · near(φ' − φ*', speed_margin))
             · (1 − w_u + w_u · near((τ − τ*) / max_torque, 1))
    position(ε) = (1 − w_p) · tolerance(ε, band, position_margin)
                  + w_p · tolerance(ε, band, 3 · band)

with ε the position error, φ*' the target's rate (0 for a rest position), τ* the torque
that holds the roller at rest at the target (``info["target_torque"]``), ``band`` the
success band, w_v = 0.5 (moving with the target), w_u = 0.2 (no torque beyond holding) and
w_p = 0.6 (precision). ``tolerance`` is 1 inside the band; outside it decays as ``near``
of the distance to the band. So at rest the reward is largest inside the success band, and
resting one band-width outside it costs about 14 % of the step's reward (the narrow term),
while the wide term still guides from far away.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numba
import numpy as np
from numba.extending import register_jitable
from roller_gym import rewards
from roller_gym.physics import Scene, equations, equilibria, trig
from roller_gym.physics.integrators import SCENE_FIELDS, contact_state, scene_arrays

__all__ = ["NAMESPACE", "OBSERVATION_FIELDS", "SPEED_SCALE", "TASKS", "TASK_CONSTANTS", "Task",
           "get_task", "hold_range", "hold_ranges", "observation_values", "per_scene",
           "position_error", "psi_rate", "register", "state_observation", "step_reward",
           "step_success", "target_observation", "unstable_rest_positions", "wrap_rate"]

#: The Gymnasium namespace of every task: ``roller_gym/<Task>-v<version>``.
NAMESPACE = "roller_gym"
#: The speed [rad/s] at which the observed tanh(φ'/SPEED_SCALE) reaches 0.76.
SPEED_SCALE = 10.0

#: Every observation field a task may list: name -> (its formula, its unit).
OBSERVATION_FIELDS: dict[str, tuple[str, str]] = {
    "cos_psi": ("cos ψ: where the roller is on the surface", "1"),
    "sin_psi": ("sin ψ", "1"),
    "cos_phi": ("cos φ: how the roller is turned", "1"),
    "sin_phi": ("sin φ", "1"),
    "speed": ("tanh(φ' / 10 rad/s): the angular speed, squashed", "1"),
    "cos_psi_target": ("cos ψ*: where the target is on the surface", "1"),
    "sin_psi_target": ("sin ψ*", "1"),
    "cos_phi_target": ("cos φ*: the roller's rotation at the target", "1"),
    "sin_phi_target": ("sin φ*", "1"),
    "target_speed": ("tanh(φ*' / 10 rad/s): how fast the target moves, squashed", "1"),
}

_TARGET_FIELDS = ("cos_psi_target", "sin_psi_target", "cos_phi_target", "sin_phi_target",
                  "target_speed")

#: The registry: task name -> task class (see :func:`register`).
TASKS: dict[str, type[Task]] = {}


def register(cls: type[Task]) -> type[Task]:
    """Class decorator: add a task to :data:`TASKS` (``import roller_gym`` then registers
    ``roller_gym/<name>-v<version>`` with Gymnasium)."""
    if cls.name in TASKS:
        raise ValueError(f"a task named {cls.name!r} is registered already")
    unknown = set(cls.observation) - set(OBSERVATION_FIELDS)
    if unknown:
        raise ValueError(f"{cls.name}.observation names unknown fields {sorted(unknown)}; "
                         f"known: {', '.join(OBSERVATION_FIELDS)}")
    compiled = [name for name in _COMPILED if getattr(cls, name) is not getattr(Task, name)]
    if compiled:
        raise ValueError(
            f"{cls.name} overrides {', '.join(compiled)}: the environments compute these in "
            "one compiled kernel from the task's class variables (TASK_CONSTANTS); set those, "
            "or change the formula itself (step_reward, step_success, position_error)")
    TASKS[cls.name] = cls
    return cls


#: The per-step methods the environments do not call (their compiled kernel runs the same
#: formulas), so a task may not override them.
_COMPILED = ("error", "observation_dict", "observation_terms", "reward", "success")


def get_task(task: str | type[Task]) -> type[Task]:
    """The task class from its name (``"RollerHold"``), its ID or the class itself."""
    if isinstance(task, type) and issubclass(task, Task):
        return task
    name = task.split("/")[-1].split("-v")[0] if isinstance(task, str) else None
    if name not in TASKS:
        raise ValueError(f"task={task!r} is not a registered task; allowed: "
                         f"{', '.join(TASKS)}")
    return TASKS[name]


def psi_rate(scene: Scene) -> float | np.ndarray:
    """dψ/dφ = rκ/(1 − rκ) [-]: ψ = psi_rate · φ (0 on the floor, where ψ stays 0); a float
    for a scalar scene, an array for a batch."""
    kappa = np.asarray(scene.kappa, dtype=float)
    rate = scene.r * kappa / (1.0 - scene.r * kappa)
    return float(rate) if np.ndim(rate) == 0 else rate


def wrap_rate(scene: Scene) -> float | np.ndarray:
    """The rate q by which errors are wrapped (see the module docs): :func:`psi_rate`, except
    on the floor, where ψ stays 0 and φ itself is wrapped (q = 1)."""
    rate = psi_rate(scene)
    if np.ndim(rate) == 0:
        return rate if rate != 0.0 else 1.0
    return np.where(rate == 0.0, 1.0, rate)


#: The most turns of φ a start state lies from the bottom (see :meth:`Task.start_candidates`).
START_TURNS = 64


class Task:
    """The base of the tasks. Subclasses set the class variables and, where the task has a
    target to draw, ``sample_targets`` (a rest position) or ``sample_target_params`` and
    ``target_at`` (a moving target)."""

    name: ClassVar[str]
    #: The version in the task's ID; a change to its dynamics, reward or spaces bumps it.
    version: ClassVar[int] = 0
    #: The observation's fields, in order (names of :data:`OBSERVATION_FIELDS`).
    observation: ClassVar[tuple[str, ...]] = ("cos_psi", "sin_psi", "cos_phi", "sin_phi",
                                              "speed")
    #: The classical controller that solves the task: ``"lqr"`` or ``"swing_up"``
    #: (:func:`roller_gym.agents.controller_for`), and its label in tables.
    classical: ClassVar[str] = "lqr"
    #: Whether the target's mirror image −φ* counts as well (the error is to the nearer).
    symmetric_target: ClassVar[bool] = False
    #: Whether the target moves during an episode (then :meth:`target_at` gives it).
    moving_target: ClassVar[bool] = False
    #: How many numbers per episode define the target (1 for a rest position φ*).
    target_size: ClassVar[int] = 1
    #: The preset the task's scene defaults to.
    default_scene: ClassVar[str] = "paper"
    #: The torque [N·m] an action of ±1 asks for, by default.
    default_max_torque: ClassVar[float] = 0.5
    max_episode_steps: ClassVar[int] = 200
    reward_threshold: ClassVar[float]
    position_margin: ClassVar[float] = 2.0  # rad of φ
    precision_weight: ClassVar[float] = 0.6
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

    @classmethod
    def env_id(cls) -> str:
        """The task's Gymnasium ID, ``roller_gym/<name>-v<version>``."""
        return f"{NAMESPACE}/{cls.name}-v{cls.version}"

    @property
    def observation_size(self) -> int:
        return len(self.observation)

    @property
    def observes_target(self) -> bool:
        """Whether the observation carries the target."""
        return any(field in _TARGET_FIELDS for field in self.observation)

    @classmethod
    def index(cls, field: str) -> int:
        """The position of an observation field (a name of :data:`OBSERVATION_FIELDS`)."""
        try:
            return cls.observation.index(field)
        except ValueError:
            raise ValueError(f"{cls.name} does not observe {field!r}; it observes "
                             f"{', '.join(cls.observation)}") from None

    # -- per episode (arrays of rollers; the uniforms come from the episode core) ------
    #: The start-state rule, as the error message states it when no start state is found.
    start_rule: ClassVar[str] = "ψ within ±60° (|φ| <= 64 turns) and |φ'| <= 1 rad/s"

    def check_scene(self, scene: Scene) -> None:
        """Raise ValueError if the task cannot be posed in ``scene`` (default: any scene)."""

    def scene_proven(self, params: Any, estimates: Sequence[Scene]) -> bool:
        """Whether :meth:`check_scene` is proven to pass in every scene of a box of them
        (``params``: :class:`roller_gym.feasibility.Params`, intervals; ``estimates``: scenes
        of the box to start estimates from, e.g. its midpoint). A task without a condition:
        True; one with a condition and no proof of it: False (a randomized range is then
        refused)."""
        return type(self).check_scene is Task.check_scene

    def infeasible(self, scene: Scene) -> str | None:
        """Why the task cannot be posed in the scalar ``scene``, or None if it can: the
        task's own condition (:meth:`check_scene`), and a start state: one of the
        :meth:`fallback_starts` must roll under every torque within the limit (the draw
        falls back to it, so a start-state draw never fails where this holds)."""
        try:
            self.check_scene(scene)
        except ValueError as error:
            return str(error)
        if self.fallback_start(scene) is None:
            return (f"no start state of {scene!r} rolls under torques up to "
                    f"{self.max_torque} N·m (the roller slips or lifts off at every state of "
                    f"{self.start_rule}); lower max_torque or raise mu")
        return None

    def fallback_start(self, scene: Scene) -> tuple[float, float] | None:
        """The start state (φ [rad], φ' [rad/s]) the draw falls back to when none of its
        random candidates rolls: the accepted one nearest the bottom of a fixed grid of
        states at rest over the start range (41 points, φ = 0 among them), or None."""
        phi, phi_dot = self.fallback_candidates(scene)
        ok = self.start_accepted(phi, phi_dot, scene)[0]
        if not ok.any():
            return None
        order = np.argsort(np.abs(phi[0]), kind="stable")
        best = order[np.argmax(ok[order])]
        return float(phi[0, best]), float(phi_dot[0, best])

    def fallback_candidates(self, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
        """The fixed grid of :meth:`fallback_start`, shape (n, 42) for a batch ``scene`` of n
        (n = 1 for a scalar one): the middle of the start range (the bottom) first, then 41
        points across it, at rest (φ [rad], φ' [rad/s]). :mod:`roller_gym.feasibility`
        encloses each candidate over a box of scenes by its values at the box's corners, so
        a task's candidates must be monotone in each Scene field (as these are)."""
        grid = np.linspace(0.0, 1.0, 41)
        u = np.concatenate([[0.5], grid])[None, :].repeat(scene.batch_size or 1, axis=0)
        return self.start_candidates(u, np.full_like(u, 0.5), scene)

    def sample_targets(self, u: np.ndarray, scene: Scene) -> np.ndarray:
        """The rest positions φ* [rad] the episodes ask for, from uniforms ``u`` in [0, 1)
        (one per roller of the batch ``scene``)."""
        raise NotImplementedError

    def sample_target_params(self, u: np.ndarray, scene: Scene) -> np.ndarray:
        """The numbers (n, ``target_size``) that define each episode's target, from uniforms
        of that shape; a rest position φ* [rad] by default (:meth:`sample_targets`)."""
        return self.sample_targets(u[:, 0], scene)[:, None]

    def target_at(self, params: np.ndarray, t: Any) -> tuple[Any, Any]:
        """(φ* [rad], φ*' [rad/s]) at time t [s] of the episode from its ``params``
        (floats for one episode's params of shape (target_size,), else arrays)."""
        return params[..., 0], 0.0 * params[..., 0]

    def start_candidates(
        self, u_phi: np.ndarray, u_dot: np.ndarray, scene: Scene
    ) -> tuple[np.ndarray, np.ndarray]:
        """Candidate start states (φ [rad], φ' [rad/s]) of shape (n, K) from uniforms of that
        shape (``scene`` a batch of n): around the bottom, up to ψ = ±60°, and a speed up
        to ±1 rad/s; φ within ±START_TURNS turns (on a nearly flat surface, R of thousands
        of r, ψ = ±60° lies further: float64's rounding of such a φ passes the tolerance)."""
        q = np.abs(wrap_rate(scene))  # q < 0 on a drum; q = 1 on the floor
        limit = np.minimum(math.radians(60.0) / np.asarray(q, float),
                           2.0 * math.pi * START_TURNS).reshape(-1, 1)
        return limit * (2.0 * u_phi - 1.0), 2.0 * u_dot - 1.0

    @property
    def start_torques(self) -> tuple[float, float, float]:
        """The torques [N·m] a start state must roll under: −max_torque, 0, +max_torque."""
        return (-self.max_torque, 0.0, self.max_torque)

    def start_accepted(self, phi: np.ndarray, phi_dot: np.ndarray, scene: Scene) -> np.ndarray:
        """Whether the roller rolls at each candidate of shape (n, K) (N > 0, |F| <= μN, as
        margins N/(m g) > 0 and (μN − |F|)/(m g) >= 0) under every torque of
        :attr:`start_torques`: one compiled call over all candidates and torques."""
        shape = np.broadcast_shapes(np.shape(phi), np.shape(phi_dot),
                                    (scene.batch_size or 1, 1))
        torques = self.start_torques
        lanes = (len(torques), *shape)  # one lane per (torque, roller, candidate)
        state = np.empty((3, *lanes))  # broadcast as they are written
        state[0], state[1] = phi, phi_dot
        state[2] = np.reshape(torques, (-1, 1, 1))
        numbers = scene_arrays(scene, shape[0])
        par = np.empty((len(numbers), *lanes))
        par[...] = numbers[:, None, :, None]
        margins = contact_state(par.reshape(len(numbers), -1), *state.reshape(3, -1))[4:]
        rolls = (margins[0] > 0.0) & (margins[1] >= 0.0)
        return rolls.reshape(lanes).all(axis=0)

    def start_contacts(self, phi: Any, phi_dot: Any, m: Any, r: Any, kappa: Any, e: Any,
                       k: Any, g: Any, c: Any) -> list[tuple[Any, Any]]:
        """The contact forces (N, F) [N] at the state under each torque of
        :attr:`start_torques`: plain arithmetic on the equations, so floats, arrays and
        intervals (:mod:`roller_gym.intervals`) alike (the feasibility proofs)."""
        out = []
        for tau in self.start_torques:
            a = equations.accel(phi, phi_dot, tau, m, r, kappa, e, k, g, c)
            out.append(equations.contact_forces(phi, phi_dot, a, m, r, kappa, e, g))
        return out

    def target_from_option(self, value: Any, scene: Scene) -> float:
        """φ* [rad] from ``reset(options={"target": value})``; tasks with a target override."""
        raise ValueError(f"{self.name} has no target to set; options['target'] is not allowed")

    def default_target(self, scene: Scene) -> float:
        """The target used when none is drawn (for rendering before reset)."""
        return 0.0

    # -- per step (the formulas are the module's compiled functions, see below) -------
    @functools.cached_property
    def constants(self) -> np.ndarray:
        """The task's numbers the per-step formulas take, in :data:`TASK_CONSTANTS` order."""
        return np.array([float(getattr(self, name)) for name in TASK_CONSTANTS])

    def error(self, phi, target, q):
        """The task's position error [rad of φ] (:func:`position_error`)."""
        return position_error(phi, target, q, float(self.symmetric_target))

    @staticmethod
    def error_to(phi, target, q):
        """The error [rad of φ] to one rest position (see the module docs): wrap(q (φ − φ*))/q,
        q from :func:`wrap_rate`."""
        return rewards.wrap_angle(q * (phi - target)) / q

    def observation_terms(self, phi, phi_dot, target, rate, target_rate=0.0):
        """The observation's entries, in the order of ``observation`` (floats or arrays);
        ``rate`` = dψ/dφ = rκ/(1 − rκ) (0 on the floor), ``target_rate`` φ*' [rad/s]."""
        terms = self.observation_dict(phi, phi_dot, target, rate, target_rate)
        return tuple(terms[name] for name in self.observation)

    def observation_dict(self, phi, phi_dot, target, rate, target_rate=0.0) -> dict[str, Any]:
        """Every observation field by name (:func:`observation_values`)."""
        return dict(zip(OBSERVATION_FIELDS,
                        observation_values(phi, phi_dot, target, rate, target_rate),
                        strict=True))

    def reward(self, step: Mapping[str, Any]):
        """The reward in [0, 1] (:func:`step_reward`) from the step's named physics: the
        info's keys (``position_error``, ``phi_dot``, ``target_phi_dot``, ``torque``,
        ``target_torque``)."""
        return step_reward(step["position_error"], step["phi_dot"] - step["target_phi_dot"],
                           (step["torque"] - step["target_torque"]) / self.max_torque,
                           self.success_band, self.position_margin, self.precision_weight,
                           self.speed_margin, self.speed_weight, self.control_weight)

    def success(self, step: Mapping[str, Any]):
        """Inside the success band, moving with the target (:func:`step_success`)."""
        return step_success(step["position_error"], step["phi_dot"] - step["target_phi_dot"],
                            self.success_band, self.success_speed)


# -- the per-step formulas, written once -------------------------------------------------------
# Plain arithmetic on NumPy's ufuncs and :mod:`roller_gym.physics.trig`: the same source serves
# floats and arrays from Python and, compiled, the environments' per-step kernel
# (:func:`roller_gym.episode.outcome`), which takes a task's numbers as :data:`TASK_CONSTANTS`.

#: The task's class variables the per-step formulas take: the order of :meth:`Task.constants`,
#: the numbers the compiled kernel takes. The kernel finds each by its name's place here
#: (``TASK_CONSTANTS.index``), so a new name may go anywhere.
TASK_CONSTANTS = ("success_band", "position_margin", "precision_weight", "speed_margin",
                  "speed_weight", "control_weight", "success_speed", "max_torque",
                  "symmetric_target", "observes_target")


@register_jitable(inline="always")
def position_error(phi, target, q, symmetric):
    """The position error [rad of φ], wrap(q (φ − φ*))/q (see the module docs); with
    ``symmetric`` (1.0) the error to the nearer of ±φ*."""
    error = rewards.wrap_angle(q * (phi - target)) / q
    if symmetric != 0.0:
        mirror = rewards.wrap_angle(q * (phi + target)) / q
        error = trig.select(np.abs(mirror) < np.abs(error), mirror, error)
    return error


@register_jitable(inline="always")
def step_reward(error, speed_error, control_error, band, position_margin, precision_weight,
                speed_margin, speed_weight, control_weight):
    """The reward in [0, 1] (formula in the module docs) from the position error ε [rad of φ],
    the speed error φ' − φ*' [rad/s] and the control error (τ − τ*)/max_torque [-]."""
    position = ((1.0 - precision_weight) * rewards.tolerance(error, band, position_margin)
                + precision_weight * rewards.tolerance(error, band, 3.0 * band))
    return (position * rewards.blend(rewards.near(speed_error, speed_margin), speed_weight)
            * rewards.blend(rewards.near(control_error, 1.0), control_weight))


@register_jitable(inline="always")
def step_success(error, speed_error, band, success_speed):
    """|ε| <= band [rad of φ] and |φ' − φ*'| <= success_speed [rad/s]."""
    return (np.abs(error) <= band) & (np.abs(speed_error) <= success_speed)


@register_jitable(inline="always")
def state_observation(phi, phi_dot, rate):
    """The roller's own fields of :data:`OBSERVATION_FIELDS` (the first five, in order);
    ``rate`` = dψ/dφ."""
    sin_psi, cos_psi = trig.sincos(rate * phi)
    sin_phi, cos_phi = trig.sincos(phi)
    return cos_psi, sin_psi, cos_phi, sin_phi, trig.tanh(phi_dot / SPEED_SCALE)


@register_jitable(inline="always")
def target_observation(target, rate, target_rate):
    """The target's fields of :data:`OBSERVATION_FIELDS` (the last five, in order);
    ``target_rate`` φ*' [rad/s]."""
    sin_psi_target, cos_psi_target = trig.sincos(rate * target)
    sin_phi_target, cos_phi_target = trig.sincos(target)
    return (cos_psi_target, sin_psi_target, cos_phi_target, sin_phi_target,
            trig.tanh(target_rate / SPEED_SCALE))


@register_jitable(inline="always")
def observation_values(phi, phi_dot, target, rate, target_rate):
    """Every field of :data:`OBSERVATION_FIELDS`, in its order (the formulas listed there);
    ``rate`` = dψ/dφ, ``target_rate`` φ*' [rad/s]."""
    return (*state_observation(phi, phi_dot, rate),
            *target_observation(target, rate, target_rate))


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


def _cached_per_scene(function):
    """Memoize ``function(scene, *args)`` on the scene's values (resets call it per episode)."""

    @functools.lru_cache(maxsize=1024)
    def cached(values: tuple[tuple[str, float], ...], *args):
        return function(Scene(**dict(values)), *args)

    @functools.wraps(function)
    def wrapper(scene: Scene, *args):
        return cached(tuple(scene.as_dict().items()), *args)

    return wrapper


def hold_ranges(scene: Scene, max_torque: float, torque_share: float = 0.8,
                friction_share: float = 0.9, points: int = 2001) -> tuple[np.ndarray, np.ndarray]:
    """The intervals [low, high] of rest positions φ [rad] around 0 that can be held at rest,
    one per roller of the batch ``scene`` (arrays of the batch's size; of 1 for a scalar
    scene), in one compiled call whatever the batch's size.

    Contiguous around φ = 0, within ψ = ±π (|φ| <= π/|q|, q from :func:`wrap_rate`), where
    the holding torque is at most ``torque_share``·max_torque [N·m] and the contact holds
    with margin: N > 0 and |F| <= ``friction_share``·μN (at rest N = m g cos ψ,
    F = m g sin ψ). Each side is a grid of ``points`` values of φ from 0 to ±π/|q| (those of
    ``np.linspace``, bit for bit), walked outward from φ = 0: the bound is the last grid
    point before the first one that fails (φ = 0 if that one fails, ±π/|q| if none does), so
    the cost is proportional to the range's width, not to ``points``.
    """
    if points < 1:
        raise ValueError(f"points={points!r} must be >= 1")
    if not all(isinstance(getattr(scene, f.name), float | np.ndarray)
               for f in dataclasses.fields(Scene)):  # e.g. an int or float32 number
        scene = Scene(**{f.name: np.asarray(getattr(scene, f.name), float)[()]
                         for f in dataclasses.fields(Scene)})  # float64, as hold_range's floats
    rows = dict(zip(SCENE_FIELDS, scene_arrays(scene), strict=True))  # each of n rollers
    numbers = [rows[name] for name in ("m", "r", "kappa", "e", "k", "g", "damping", "mu")]
    half = np.empty_like(numbers[0])
    half[...] = np.reshape(math.pi / np.abs(wrap_rate(scene)), -1)  # q < 0 on a drum
    low, high = np.empty_like(half), np.empty_like(half)
    _hold_bounds(*numbers, half, float(torque_share * max_torque), float(friction_share),
                 int(points), low, high)
    return low, high


@_cached_per_scene
def hold_range(scene: Scene, max_torque: float, torque_share: float = 0.8,
               friction_share: float = 0.9, points: int = 2001) -> tuple[float, float]:
    """The interval (low, high) of rest positions φ [rad] around 0 that can be held at rest
    in the scalar ``scene``: :func:`hold_ranges` of it (the same compiled walk), memoized."""
    low, high = hold_ranges(scene, max_torque, torque_share, friction_share, points)
    return float(low[0]), float(high[0])


@register_jitable(inline="always")
def _holds(phi, m, r, kappa, e, k, g, c, mu, torque_limit, friction_share):
    """Whether the roller can be held at rest at φ [rad] (:func:`hold_ranges`' condition): its
    holding torque τ = dV/dφ [N·m] within ``torque_limit``, and under τ at rest N > 0 and
    |F| <= ``friction_share``·μN."""
    tau = equations.dpotential(phi, m, r, kappa, e, g)
    phi_ddot = equations.accel(phi, 0.0, tau, m, r, kappa, e, k, g, c)
    normal, friction = equations.contact_forces(phi, 0.0, phi_ddot, m, r, kappa, e, g)
    return ((abs(tau) <= torque_limit) & (normal > 0)
            & (abs(friction) <= friction_share * mu * normal))


@register_jitable(inline="always")
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
                 low, high):
    """low[j], high[j] of :func:`hold_ranges` for roller j (scene numbers as rows, ``half``
    π/|q| [rad]): each side's grid walked outward from φ = 0, a block of
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
                                   torque_limit, friction_share)
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
