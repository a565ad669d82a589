"""The single roller environment: a Gymnasium ``Env`` on the physics of :mod:`roller_gym.physics`.

Every task (a :class:`~roller_gym.task.Task` of ``stabilize.py``, ``hold.py``,
``balance.py`` or ``track.py``) runs in this one class: each ID is registered as
``RollerEnv`` with ``task=`` its name. This file holds construction, reset, step, info and
rendering.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from roller_gym import episode, validation
from roller_gym.config import EnvConfig, Settings, takes_settings
from roller_gym.episode import INFO_KEYS, INFO_ROW, OutcomeKernel
from roller_gym.episode.record import C
from roller_gym.physics import Scene
from roller_gym.physics.integrators import Stepper
from roller_gym.physics.scene import shown
from roller_gym.task import Task, get_task, psi_rate, wrap_rate

__all__ = ["RollerEnv"]



@takes_settings(before=("task",))
class RollerEnv(gym.Env[np.ndarray, np.ndarray]):
    """A roller driven by a torque, rolling without slipping on a fixed surface.

    Args:
        task: the task: a name of the registry (``"RollerHold"``, see
            :data:`roller_gym.task.TASKS`), its ID, or its class.
        {settings}
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, task: str | type[Task] = "RollerStabilize", **settings: Any) -> None:
        self.config = EnvConfig.build(get_task(task, current=True),
                                      Settings.of(type(self), settings),
                                      render_modes=self.metadata["render_modes"])
        self.task = self.config.task
        self._outcome = OutcomeKernel(self.task, 1)
        self.render_mode = self.config.render_mode
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        size = self.task.observation_size
        self.observation_space = spaces.Box(-1.0, 1.0, (size,), np.float32)
        cfg = self.config
        self._stepper = Stepper(cfg.scene, integrator=cfg.integrator, dt=cfg.dt,
                                tolerance=cfg.tolerance, substeps=cfg.substeps or None)
        self._link()
        self._terms_of: tuple[Scene, str] | None = None  # what the context's target terms are of
        self._set_scene(cfg.scene)
        self._set_target(self.task.default_target(cfg.nominal_scene), 0.0)  # (until a reset)
        self._steps = 0  # of this episode: its time is _steps · dt, as in the vector env
        self._target_params = np.full(self.task.target_size, self.target)
        self.phi, self.phi_dot, self.torque = self.target, 0.0, 0.0
        self._stream_seed: int | None = None  # set by the first reset
        self._episode = 0
        self._renderer = None

    def _set_scene(self, scene: Scene) -> None:
        self.scene = scene
        self._stepper.set_scene(scene)
        self._q = wrap_rate(scene)
        self._psi_rate = psi_rate(scene)
        context = self._outcome.context
        context[C.wrap_rate, 0], context[C.psi_rate, 0] = self._q, self._psi_rate

    def _set_target(self, target: float, rate: float) -> None:
        self.target, self.target_rate = target, rate
        context = self._outcome.context
        context[C.target_phi, 0], context[C.target_phi_dot, 0] = target, rate
        terms_of = (self.scene, float(target).hex())  # the scene and the target's bits
        if terms_of != self._terms_of:  # (a reset to the same target keeps its terms)
            for name, value in episode.target_terms(self.scene, target).items():
                context[getattr(C, name), 0] = value
            self._terms_of = terms_of
        self.target_torque = float(context[C.target_torque, 0])

    # -- Gymnasium API -----------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode. ``options``: ``"state"``: (φ [rad], φ' [rad/s]); ``"target"``:
        the task's target (see the task); ``"scene"``: a Scene or preset for this episode."""
        seed = episode.check_seed(seed)
        if seed is not None or self._stream_seed is None:
            stream_seed = episode.random_seed() if seed is None else seed
            number = 0
        else:
            stream_seed, number = self._stream_seed, self._episode + 1
        start = episode.start_episodes(  # before any change: refused options leave none
            self.config, self.config.scene, np.array([stream_seed], np.uint64),
            np.array([number], np.uint64), options,
        )
        super().reset(seed=seed)
        self._stream_seed, self._episode = stream_seed, number
        scene = start.scene if start.scene.batch_size is None else start.scene.item(0)
        if scene is not self.scene:  # randomized, or set by the options: its numbers anew
            self._set_scene(scene)
        self._target_params = start.target_params[0]
        self._set_target(float(start.target[0]), float(start.target_rate[0]))
        self._steps = 0  # of this episode: its time is _steps · dt, as in the vector env
        self.phi, self.phi_dot, self.torque = float(start.phi[0]), float(start.phi_dot[0]), 0.0
        self._stepper.forget()  # a new episode does not continue the last one's substeps
        self._advance.start(self.phi, self.phi_dot)  # its outcome, by the step's own kernel
        self._info.hold()  # the target's keys, the same at every step of the episode
        if self.render_mode == "human":
            self.render()
        return self._observation.copy(), self._info()

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._stream_seed is None:
            raise RuntimeError("call reset() before step()")
        common = (type(action) is np.ndarray and action.shape == (1,)
                  and action.dtype.char in "fd")  # .item() a Python float (not a longdouble)
        a = action.item() if common else math.nan
        if math.isfinite(a):  # the common case, without the checks' cost
            if not -1.0 <= a <= 1.0:  # clipped (as min and max would, at a tenth of the cost)
                a = 1.0 if a > 1.0 else -1.0
        else:
            a = float(validation.actions(action, (1,))[0])
        tau = a * self.task.max_torque
        self._steps += 1
        if self.task.moving_target:  # the target at the step's end
            target, rate = self.task.target_at(self._target_params,
                                               self._steps * self.config.dt)
            self._set_target(float(target), float(rate))
        self.phi, self.phi_dot, reward, terminated = self._advance(self.phi, self.phi_dot, tau)
        self.torque = tau
        if self.render_mode == "human":
            self.render()
        return self._observation.copy(), reward, terminated, False, self._info()

    # -- rendering ---------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "render() was called without a render_mode; pass render_mode='rgb_array' or "
                f"'human' to gymnasium.make({shown(self.spec.id if self.spec else '')}, ...)"
            )
            return None
        if self._renderer is None:
            from roller_gym.rendering import Renderer  # pygame is imported only when rendering

            self._renderer = Renderer(self.render_mode, self.metadata["render_fps"])
        return self._renderer.draw(self.scene, self.phi, self.target, self.torque,
                                   self.task.max_torque, self.task.observes_target)

    def _link(self) -> None:
        """Views of the outcome's buffers that every step reads and writes, and the step bound
        to them (made again after unpickling, which copies the buffers)."""
        outcome = self._outcome
        self._observation = outcome.observation[0]
        self._info = _scalar_info(self.config.info_keys, outcome.table[:, 0],
                                  outcome.flags[:, 0],
                                  held=() if self.task.moving_target else _TARGET_KEYS)
        self._info.hold()  # (after unpickling: the episode's; before a reset: unread)
        self._advance = outcome.bind(self._stepper)  # a step: its outcome into these views

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_renderer"] = None  # pygame surfaces do not pickle: draw again afterwards
        for view in ("_observation", "_info", "_advance"):
            del state[view]
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._link()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None


class _Whole(dict):
    """np.int64 scalars by their value, a whole float (the outcome's table holds the integer
    key, the substeps, as one): np.int64(x) costs as much as four float reads, a lookup here
    far less. It keeps the first KEPT values met."""

    KEPT = 4096

    def __missing__(self, value: float) -> np.int64:
        whole = np.int64(value)  # (NaN raises, as it always did)
        if len(self) < self.KEPT:
            self[value] = whole
        return whole


_WHOLE = _Whole()


#: The info keys that follow from the episode's target and scene alone (the context's rows,
#: passed on, and ψ* = qφ*): the same at every step of an episode whose target stands still.
_TARGET_KEYS = ("target_phi", "target_psi", "target_phi_dot", "target_torque")


def _scalar_info(keys: tuple[str, ...], table: np.ndarray, flags: np.ndarray,
                 held: tuple[str, ...] = ()) -> Callable[[], dict[str, Any]]:
    """A function of no arguments that returns one roller's info of ``keys`` (in INFO_KEYS
    order) as it stands in its column of the outcome's ``table`` and ``flags`` (views): a new
    dict each call, the values NumPy scalars (``np.float64``, ``np.int64``, ``np.bool_``), so
    that every value has a ``dtype``, as array-based clients (TorchRL) expect. The keys of
    ``held`` are read by its method ``hold()`` alone (the caller's promise: they keep their
    values until it calls ``hold()`` again), into the dict that every call copies.

    Every step makes one, so the function is written out for ``keys``, one statement per key
    (``info["phi"] = table[1]``, ...), on a copy of a dict of those keys: a copy costs a
    fraction of building a dict, and a loop, ``zip`` or ``dict.update`` over pairs costs
    about twice as much as the statements."""
    assert tuple(key for key in INFO_KEYS if key in keys) == tuple(keys), keys
    reads = {float: "table[{}]", int: "whole[table.item({})]", bool: "flags[{}]"}

    def written(chosen: list[str]) -> str:
        return "".join(f"    info[{key!r}] = {reads[INFO_KEYS[key][0]].format(INFO_ROW[key])}\n"
                       for key in chosen)

    namespace = {"__name__": __name__, "template": dict.fromkeys(keys), "table": table,
                 "flags": flags, "whole": _WHOLE}
    exec(f"def info():\n    info = template.copy()\n"
         f"{written([key for key in keys if key not in held])}    return info\n"
         f"def hold():\n    info = template\n{written([key for key in keys if key in held])}",
         namespace)
    info = namespace["info"]
    info.hold = namespace["hold"]
    return info
