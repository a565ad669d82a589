"""What a task asks of the roller: start state, target, observation, reward, success.

A task knows the physics (:mod:`roller_gym.physics`) but neither Gymnasium nor pygame. Its
per-episode methods (targets, start states) take arrays of rollers. Its per-step
objective (``reward``, ``success``, see below) is its own; the position error and the
observation are this module's compiled functions, the same for every task; the single and
the vector environment run them in one compiled kernel per task
(:mod:`roller_gym.episode.kernel`). Each task is one class in its own module
(``stabilize.py``, ``hold.py``, ``balance.py``, ``track.py``, ``swing.py``), added to the
registry :data:`TASKS` by the decorator :func:`register`, as dm_control's suite does;
registration with Gymnasium, the agents, the scripts and the tests iterate over the
registry. A new task is one class in a module of
its own, listed in ``roller_gym.TASK_MODULES``, with its hyperparameters (README, "Adding a
task").

**The position error.** The target is a rest position φ* [rad]. The error is measured
along the configuration, within half a period of the roller's pose either way: with the
wrap rate q (:func:`wrap_rate`: 2π/|q| is the least turn of φ after which the contact
point and the eccentric mass are both where they were; q = rκ/(1 − rκ) = dψ/dφ where
1/|q| is a whole number, as in every default scene; 1 on the floor),

    error = wrap(q (φ − φ*)) / q   [rad of φ],   or φ − φ* where q = 0 (no such period),

so the contact point is r·|error| metres of rolling away from its target.

**The observation** (float32, every entry in [−1, 1]) is a tuple of named fields, each
declared once in :data:`OBSERVATION_FIELDS`; a task lists the ones it observes, in order,
in ``Task.observation``, and agents read them by name (:meth:`Task.index`).

**The objective** is the task's own: ``reward(s, k)`` in [0, 1] per step and
``success(s, k)``, static methods of the task compiled by numba (``@objective``), functions
of the step's named quantities ``s`` (a :class:`roller_gym.episode.Step`: position error,
speeds, torque and holding torque, energy and the target's, contact forces and margins) and
of the task's numbers ``k`` (``k.<name>`` for each name of the task's :attr:`Task.parameters`,
its class variables and ``max_torque``), built from the reward vocabulary
(:mod:`roller_gym.rewards`). The environments compile their per-step kernel for each task
from these functions; :meth:`Task.step_reward` and :meth:`Task.step_success` run the same
source in Python. The default, shared by Stabilize, Hold, Balance and Track, is
:func:`step_reward`:

    reward = position(ε)
             · (1 − w_v + w_v · near(φ' − φ*', speed_margin))
             · (1 − w_u + w_u · near((τ − τ*) / max_torque, 1))
    position(ε) = (1 − w_p) · tolerance(ε, band, position_margin)
                  + w_p · near(ε, 3 · band)

with ε the position error, φ*' the target's rate (0 for a rest position), τ* the torque
that holds the roller at rest at the target (``info["target_torque"]``), ``band`` the
success band, w_v = 0.5 (moving with the target), w_u = 0.2 (no torque beyond holding) and
w_p = 0.6 (precision). ``tolerance`` is 1 inside the band; outside it decays as ``near``
of the distance to the band. The precision term ``near(ε, 3 · band)`` falls from the target
on, so resting with the holding torque pays strictly less as |ε| grows: at the
band's edge 0.4 + 0.6 · 0.1^(1/9) = 0.86 of the reward on the target, at twice the band
0.4 + 0.6 · 0.1^(4/9) = 0.62 (``tests/test_rewards.py`` checks it for every task).
Success: |ε| <= band and |φ' − φ*'| <= success_speed.
"""

from __future__ import annotations

import functools
import math
from collections import namedtuple
from collections.abc import Sequence
from typing import Any, ClassVar

import numpy as np
from roller_gym import bounds, rewards, start_set, validation
from roller_gym.physics import Scene, equations, trig
from roller_gym.physics.compiling import inlined
from roller_gym.physics.integrators import contact_state, scene_arrays
from roller_gym.physics.scene import shown
from roller_gym.rest import (  # the scene's rates and rest positions, importable from here too
    START_TURNS,
    angle_rate,
    hold_range,
    hold_ranges,
    per_scene,
    psi_rate,
    reach,
    unstable_rest_positions,
    wrap_rate,
)

__all__ = ["NAMESPACE", "OBSERVATION_FIELDS", "SPEED_SCALE", "START_TURNS", "TASKS",
           "TASK_CONSTANTS", "TIERS", "Task", "angle_rate", "get_task", "hold_range",
           "hold_ranges", "objective", "observation_values", "per_scene", "position_error",
           "psi_rate", "reach", "register", "state_observation", "step_reward", "step_success",
           "target_observation", "unstable_rest_positions", "wrap_rate", "wrapped"]

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

#: The suite's tiers (:attr:`Task.tier`), in the order the results page shows them.
TIERS = ("base", "hard")
#: The registry: task name -> task class (see :func:`register`).
TASKS: dict[str, type[Task]] = {}


def register(cls: type[Task]) -> type[Task]:
    """Class decorator: add a task to :data:`TASKS` (``import roller_gym`` then registers
    ``roller_gym/<name>-v<version>`` with Gymnasium)."""
    if cls.name in TASKS:
        raise ValueError(f"a task named {shown(cls.name)} is registered already")
    unknown = set(cls.observation) - set(OBSERVATION_FIELDS)
    if unknown:
        raise ValueError(f"{cls.name}.observation names unknown fields {sorted(unknown)}; "
                         f"known: {', '.join(OBSERVATION_FIELDS)}")
    if cls.tier not in TIERS:
        raise ValueError(f"{cls.name}.tier is {shown(cls.tier)}; it must be one of {TIERS}")
    compiled = [name for name in _COMPILED if getattr(cls, name) is not getattr(Task, name)]
    if compiled:
        raise ValueError(
            f"{cls.name} overrides {', '.join(compiled)}: the environments compute these in "
            "their compiled kernel for every task (position_error, observation_values); a "
            "task states its objective in reward(s, k) and success(s, k)")
    for name in ("reward", "success"):
        if not isinstance(cls.__dict__.get(name, Task.__dict__[name]), staticmethod):
            raise ValueError(f"{cls.name}.{name} must be a static method (@staticmethod over "
                             f"@objective) of (s, k), as Task.{name}")
    missing = [name for name in _KERNEL_PARAMETERS if name not in cls.parameters]
    if missing:
        raise ValueError(f"{cls.name}.parameters lacks {missing}: the kernel reads them")
    constants = namedtuple("Constants", cls.parameters)
    constants.__qualname__ = f"{cls.__qualname__}.Constants"  # pickled by reference: the
    constants.__module__ = cls.__module__  # on-disk cache keys a kernel on it
    cls.Constants = constants
    TASKS[cls.name] = cls
    return cls


#: The per-step methods the environments do not call (their compiled kernel runs the same
#: formulas for every task), so a task may not override them.
_COMPILED = ("error", "observation_dict", "observation_terms")
#: The task's numbers the shared part of the kernel reads (``k.<name>``).
_KERNEL_PARAMETERS = ("max_torque", "symmetric_target", "observes_target")


def objective(function: Any) -> Any:
    """Decorator of a task's ``reward(s, k)`` or ``success(s, k)``: compiled into the
    environments' per-step kernel (inlined by LLVM: ``roller_gym.physics.compiling.inlined``);
    in Python the function itself, for floats and arrays alike. Write it from NumPy's ufuncs,
    :mod:`roller_gym.rewards` and :mod:`roller_gym.physics.trig`."""
    return inlined(function)


def get_task(task: str | type[Task], current: bool = False) -> type[Task]:
    """The task class from its name (``"RollerHold"``), its ID or the class itself; with
    ``current``, an ID must be the task's current one (namespace and version)."""
    if isinstance(task, type) and issubclass(task, Task) and task is not Task:
        if not hasattr(task, "Constants"):  # register() checks a task and gives it these
            raise ValueError(f"task={shown(task)} is not registered: decorate the class with "
                             "roller_gym.task.register, which checks it and compiles its "
                             "objective")
        return task
    name = task.split("/")[-1].split("-v")[0] if isinstance(task, str) else None
    if name not in TASKS:
        raise ValueError(f"task={shown(task)} is not a registered task; allowed: "
                         f"{', '.join(TASKS)}")
    found = TASKS[name]
    if current and task != name and task != found.env_id():  # an ID: namespace and version
        raise ValueError(f"task={shown(task)} is not a registered ID; {name}'s is "
                         f"{shown(found.env_id())} (or give the name {shown(name)})")
    return found




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
    #: The suite's tier: ``"base"``, where the classical controller is the reference an agent
    #: should reach, or ``"hard"``, where it is not the ceiling and algorithms can differ
    #: (the results page aggregates each tier on its own).
    tier: ClassVar[str] = "base"
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
    #: The Scene fields drawn per episode when ``randomize`` is not given, ``{field: (low,
    #: high)}`` (a task whose scene varies and is not observed); None: the scene is fixed.
    scene_ranges: ClassVar[dict[str, tuple[float, float]] | None] = None
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
    #: The names of the numbers the objective reads (``k.<name>``): class variables, and
    #: ``max_torque``, the instance's. A task with numbers of its own extends the tuple.
    parameters: ClassVar[tuple[str, ...]] = ("success_band", "position_margin",
                                             "precision_weight", "speed_margin",
                                             "speed_weight", "control_weight",
                                             "success_speed", "max_torque",
                                             "symmetric_target", "observes_target")
    #: The named tuple of :attr:`parameters`, made by :func:`register`.
    Constants: ClassVar[type]

    def __init__(self, max_torque: float | None = None) -> None:
        self.max_torque = validation.real(
            "max_torque", self.default_max_torque if max_torque is None else max_torque,
            positive=True, unit="N·m")

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
            raise ValueError(f"{cls.name} does not observe {shown(field)}; it observes "
                             f"{', '.join(cls.observation)}") from None

    # -- per episode (arrays of rollers; the uniforms come from the episode core) ------
    #: The start-state rule, as the error message states it when no start state is found.
    #: ψ [rad] of the start range's edges: a start lies within ±start_angle of ψ.
    start_angle: ClassVar[float] = math.radians(60.0)
    start_rule: ClassVar[str] = "ψ within ±60° (|φ| <= 64 turns) and |φ'| <= 1 rad/s"
    #: The largest |φ'| [rad/s] of a drawn start state: the construction refuses a dt too
    #: long to integrate a step from it (:func:`roller_gym.validation.check_integrable`).
    start_speed: ClassVar[float] = 1.0

    def check_scene(self, scene: Scene) -> None:
        """Raise ValueError if the task cannot be posed in ``scene`` (default: any scene)."""

    def scene_proven(self, params: Any, estimates: Sequence[Scene], dt: float) -> bool:
        """Whether :meth:`check_scene` and the :meth:`pump_time` condition of
        :meth:`infeasible` (with the control step ``dt`` [s]) are proven to pass in every
        scene of a box of them (``params``: :class:`roller_gym.feasibility.Params`,
        intervals; ``estimates``: scenes of the box to start estimates from, e.g. its
        midpoint). A task without either: True; one with a condition and no proof of it:
        False (a randomized range is then refused)."""
        return (type(self).check_scene is Task.check_scene
                and type(self).pump_time is Task.pump_time)

    #: The share of an episode (max_episode_steps·dt) within which the least time of
    #: :meth:`pump_time` must bring the target's energy. The full torque in phase with φ'
    #: takes 2.3–2.8 times that least time on the tasks' scenes (``docs/MAINTAINERS.md``),
    #: so there it needs at most about 0.85 of the episode.
    PUMP_SHARE: ClassVar[float] = 0.3

    def pump_time(self, scene: Scene) -> tuple[float, float, float] | None:
        """For a task whose target needs energy pumped in (a swing, a swing-up): (the energy
        [J] to bring, the fastest speed ω [rad/s] on the way, the least time [s] the torque
        needs for it, :func:`roller_gym.bounds.energy_time`: its power max_torque·|φ'| with
        |φ'| at most that energy's speed, as the energy grows) in the scalar ``scene``; None
        (the default) for the others. A task with one proves it over a range of scenes in its
        :meth:`scene_proven`, or takes no ``randomize`` range (:mod:`roller_gym.feasibility`)."""
        return None

    def infeasible(self, scene: Scene, dt: float | None = None) -> str | None:
        """Why the task cannot be posed in the scalar ``scene``, or None if it can: the
        task's own condition (:meth:`check_scene`); with the control step ``dt`` [s], the
        target within reach of the torque in the episode (:meth:`pump_time` at most
        PUMP_SHARE of max_episode_steps·dt, and :func:`roller_gym.bounds.too_slow`); and a
        start state: one of the :meth:`fallback_starts` must roll under every torque within
        the limit (the draw falls back to it, so a start-state draw never fails where this
        holds)."""
        try:
            self.check_scene(scene)
        except ValueError as error:
            return str(error)
        pumped = self.pump_time(scene) if dt is not None else None
        episode = self.max_episode_steps * (dt or 0.0)
        if pumped is not None and not pumped[2] <= self.PUMP_SHARE * episode:
            energy, speed, seconds = pumped
            return (f"max_torque={self.max_torque:g} N·m is too weak for {shown(scene)} in "
                    f"episodes of {self.max_episode_steps} steps of dt={dt:g} s "
                    f"({episode:.3g} s): even the most power it can put in, max_torque·|φ'| "
                    f"with |φ'| growing with the energy up to the target's fastest speed "
                    f"{speed:.3g} rad/s, needs {seconds:.3g} s to bring the target's "
                    f"{energy:.3g} J, more than {self.PUMP_SHARE:g} of the episode; use a "
                    "larger max_torque or a longer dt")
        slow = bounds.too_slow(self, scene, dt) if dt is not None else None
        if slow is not None:
            return slow
        if self.fallback_start(scene) is None:
            return (f"no start state of {shown(scene)} rolls under torques up to "
                    f"{self.max_torque} N·m (the roller slips or lifts off at every state of "
                    f"{self.start_rule}); lower max_torque or raise mu")
        return None

    #: Whether every target lies near the bottom, so that the roller comes down from its
    #: start: its :meth:`least_times` bound the way, and in a fixed scene no start may be
    #: doomed to slip on it (:func:`roller_gym.descent.doomed`). False for a pump.
    descends: ClassVar[bool] = True
    #: The share of an episode within which each of :meth:`least_times` must fit.
    reach_share: ClassVar[float] = 0.5

    def least_times(self, p: Any, start: Any) -> dict[str, Any]:
        """Lower bounds [s] of the time the task's target needs, as intervals over the box
        of scenes ``p`` (:class:`roller_gym.bounds.Params`), by name
        (:data:`roller_gym.bounds.LEAST_TIMES`): by default, from a start at rest at |φ| =
        ``start`` [rad] (intervals, elementwise) to rest at the bottom, near which every
        target of the tasks with this start range lies (:func:`roller_gym.bounds.
        least_times`). Each must fit in :attr:`reach_share` of an episode. A task that does
        not :attr:`descend <descends>` (a pump) has none and bounds its own time
        (:meth:`pump_time`)."""
        if not self.descends:
            return {}
        return bounds.least_times(p, self.max_torque, start, self.success_band,
                                  self.success_speed)

    def unaided_time(self, p: Any, farthest: Any) -> Any:
        """For a task whose target is where the free motion comes to rest: a lower bound
        [s] (an interval over ``p``) of the time the damping alone needs to bring the roller
        there from the farthest start (at rest at |φ| = ``farthest`` [rad], an interval; as
        :meth:`least_times`), which must exceed the
        episode (else no torque at all may succeed); None (the default) for the others."""
        return None

    start_points: ClassVar[int] = 201  #: the candidates of :meth:`accepted_starts`

    def accepted_starts(self, scene: Scene) -> np.ndarray:
        """|φ| [rad] bounding every start the draw may accept in the scalar ``scene``, at rest
        or moving: the far ends of the cells between :attr:`start_points` candidates over the
        start range that may hold one (:func:`roller_gym.start_set.covering`)."""
        return start_set.covering(self, scene).phi

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
        to ±:attr:`start_speed`; φ within ±START_TURNS turns (on a nearly flat surface, R of
        thousands of r, ψ = ±60° lies further: float64's rounding of such a φ passes the
        tolerance)."""
        limit = np.reshape(reach(scene, self.start_angle), (-1, 1))
        return limit * (2.0 * u_phi - 1.0), self.start_speed * (2.0 * u_dot - 1.0)

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
        lhs, inertia, *trig_terms, _ = equations.accel_terms(phi, phi_dot, 0.0, m, r, kappa, e,
                                                             k, g, c)  # shared by the torques
        return [equations.forces(*trig_terms, phi_dot, (lhs + tau / m) / inertia, m, r, kappa,
                                 e, g) for tau in self.start_torques]

    def target_from_option(self, value: Any, scene: Scene) -> float:
        """φ* [rad] from ``reset(options={"target": value})``; tasks with a target override."""
        raise ValueError(f"{self.name} has no target to set; options['target'] is not allowed")

    def default_target(self, scene: Scene) -> float:
        """The target used when none is drawn (for rendering before reset)."""
        return 0.0

    # -- per step: the objective is the task's (compiled), the rest the module's ----------
    @functools.cached_property
    def constants(self) -> Any:
        """The task's numbers its objective reads, a :attr:`Constants` of :attr:`parameters`."""
        return self.Constants(*(float(getattr(self, name)) for name in self.parameters))

    @staticmethod
    @objective
    def reward(s, k):
        """The reward in [0, 1] of a step's quantities ``s`` (a Step) for the task's numbers
        ``k``: :func:`step_reward` (the formula in the module docs)."""
        return step_reward(s.position_error, s.phi_dot - s.target_phi_dot,
                           (s.torque - s.target_torque) / k.max_torque, k.success_band,
                           k.position_margin, k.precision_weight, k.speed_margin,
                           k.speed_weight, k.control_weight)

    @staticmethod
    @objective
    def success(s, k):
        """Inside the success band, moving with the target (:func:`step_success`)."""
        return step_success(s.position_error, s.phi_dot - s.target_phi_dot, k.success_band,
                            k.success_speed)

    def step_reward(self, step: Any) -> Any:
        """:meth:`reward` in Python, of a Step or of a mapping of its quantities (e.g. a
        step's info; a quantity it lacks is NaN)."""
        return self.reward(_as_step(step), self.constants)

    def step_success(self, step: Any) -> Any:
        """:meth:`success` in Python, as :meth:`step_reward`."""
        return self.success(_as_step(step), self.constants)

    def error(self, phi, target, q):
        """The task's position error [rad of φ] (:func:`position_error`)."""
        return position_error(phi, target, q, float(self.symmetric_target))

    @staticmethod
    def error_to(phi, target, q):
        """The error [rad of φ] to one rest position (see the module docs): wrap(q (φ − φ*))/q,
        q from :func:`wrap_rate` (φ − φ* where q = 0)."""
        return wrapped(phi - target, q)

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


def _as_step(step: Any) -> Any:
    from roller_gym.episode.record import Step, step_record

    return step if isinstance(step, Step) else step_record(step)


# -- the per-step formulas, written once -------------------------------------------------------
# Plain arithmetic on NumPy's ufuncs and :mod:`roller_gym.physics.trig`: the same source serves
# floats and arrays from Python and, compiled, the environments' per-step kernel
# (:mod:`roller_gym.episode.outcome`).

#: The precision term's margin, in success bands: ``near`` is 0.1 there (module docs).
PRECISION_MARGIN = 3.0

#: The numbers the default objective reads (:attr:`Task.parameters` of the base class).
TASK_CONSTANTS = Task.parameters


@inlined
def wrapped(x, q):
    """x [rad of φ] wrapped into half a period 2π/|q| either way, wrap(q x)/q; x itself where
    q = 0 (no period, see :func:`wrap_rate`)."""
    periodic = q != 0.0
    rate = trig.select(periodic, q, 1.0)
    return trig.select(periodic, rewards.wrap_angle(rate * x) / rate, x)


@inlined
def position_error(phi, target, q, symmetric):
    """The position error [rad of φ], wrap(q (φ − φ*))/q (see the module docs); with
    ``symmetric`` (1.0) the error to the nearer of ±φ*."""
    error = wrapped(phi - target, q)
    if symmetric != 0.0:
        mirror = wrapped(phi + target, q)
        error = trig.select(np.abs(mirror) < np.abs(error), mirror, error)
    return error


@inlined
def step_reward(error, speed_error, control_error, band, position_margin, precision_weight,
                speed_margin, speed_weight, control_weight):
    """The reward in [0, 1] (formula in the module docs) from the position error ε [rad of φ],
    the speed error φ' − φ*' [rad/s] and the control error (τ − τ*)/max_torque [-]."""
    position = ((1.0 - precision_weight) * rewards.tolerance(error, band, position_margin)
                + precision_weight * rewards.near(error, PRECISION_MARGIN * band))
    return (position * rewards.blend(rewards.near(speed_error, speed_margin), speed_weight)
            * rewards.blend(rewards.near(control_error, 1.0), control_weight))


@inlined
def step_success(error, speed_error, band, success_speed):
    """|ε| <= band [rad of φ] and |φ' − φ*'| <= success_speed [rad/s]."""
    return (np.abs(error) <= band) & (np.abs(speed_error) <= success_speed)


@inlined
def state_observation(phi, phi_dot, rate):
    """The roller's own fields of :data:`OBSERVATION_FIELDS` (the first five, in order);
    ``rate`` = dψ/dφ."""
    sin_psi, cos_psi = trig.sincos(rate * phi)
    sin_phi, cos_phi = trig.sincos(phi)
    return cos_psi, sin_psi, cos_phi, sin_phi, trig.tanh(phi_dot / SPEED_SCALE)


@inlined
def target_observation(target, rate, target_rate):
    """The target's fields of :data:`OBSERVATION_FIELDS` (the last five, in order);
    ``target_rate`` φ*' [rad/s]."""
    sin_psi_target, cos_psi_target = trig.sincos(rate * target)
    sin_phi_target, cos_phi_target = trig.sincos(target)
    return (cos_psi_target, sin_psi_target, cos_phi_target, sin_phi_target,
            trig.tanh(target_rate / SPEED_SCALE))


@inlined
def observation_values(phi, phi_dot, target, rate, target_rate):
    """Every field of :data:`OBSERVATION_FIELDS`, in its order (the formulas listed there);
    ``rate`` = dψ/dφ, ``target_rate`` φ*' [rad/s]."""
    return (*state_observation(phi, phi_dot, rate),
            *target_observation(target, rate, target_rate))

