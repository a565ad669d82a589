"""The native vector environment: N rollers advanced together by the batched physics.

``gymnasium.make_vec(ID, num_envs=N)`` builds it (registered as the tasks'
``vector_entry_point``). It runs the same task code as the single environment, on arrays,
and the same compiled integrator kernel per roller, so with the seeds ``seed + i`` it
reproduces N single environments seeded ``seed + i``. Autoreset is next-step, as in
Gymnasium's own vector environments: the step after an episode ends returns the first
observation of the next, with reward 0 and both flags False.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar

import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from roller_gym.config import DEFAULT_DT, DEFAULT_TOLERANCE, EnvConfig, resolve_scene
from roller_gym.physics import Scene
from roller_gym.physics import equations as eq
from roller_gym.physics import integrators as integ
from roller_gym.roller_env import episode_start
from roller_gym.task import Task, psi_rate, wrap_rate

__all__ = ["RollerVectorEnv"]


class RollerVectorEnv(VectorEnv):
    """N rollers, each with its own scene, target and random generator.

    Args:
        num_envs: the number of sub-environments.
        scene: one Scene or preset name for all, or a sequence of them (one per
            sub-environment), or a batch Scene of ``num_envs`` rollers.
        max_episode_steps: truncation; default the task's.
        dt, max_torque, tolerance, integrator, substeps, randomize, render_mode: as in
            :class:`roller_gym.roller_env.RollerEnv`, for every sub-environment.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": 20,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }
    task_class: ClassVar[type[Task]]

    def __init__(
        self,
        num_envs: int = 1,
        scene: Scene | str | Sequence[Scene | str] | None = None,
        dt: float = DEFAULT_DT,
        max_torque: float | None = None,
        tolerance: float = DEFAULT_TOLERANCE,
        integrator: str = "rk8",
        substeps: int | None = None,
        randomize: Mapping[str, tuple[float, float]] | None = None,
        render_mode: str | None = None,
        max_episode_steps: int | None = None,
    ) -> None:
        if not (isinstance(num_envs, int) and num_envs >= 1):
            raise ValueError(f"num_envs={num_envs!r} must be an integer >= 1")
        per_env = self._per_env_scenes(scene, num_envs)
        self.config = EnvConfig.build(
            self.task_class, scene=None if per_env else scene, dt=dt, max_torque=max_torque,
            tolerance=tolerance, integrator=integrator, substeps=substeps,
            randomize=randomize, render_mode=render_mode,
            render_modes=self.metadata["render_modes"],
        )
        if integrator == "dop853":
            raise ValueError("integrator='dop853' is a reference for the single environment; "
                             "the vector environment takes 'rk8', 'rk4', 'euler' or 'midpoint'")
        scenes = [resolve_scene(s, self.config.task.default_scene) for s in per_env] or [
            self.config.scene
        ] * num_envs
        for s in {id(s): s for s in scenes}.values():
            self.config.task.check_scene(s)
        # One configuration per sub-environment: the same settings, its own base scene.
        self._configs = [
            c if c.scene is s else dataclasses.replace(c, scene=s)
            for c, s in zip([self.config] * num_envs, scenes, strict=True)
        ]
        self.task = self.config.task
        self.num_envs = num_envs
        self.render_mode = render_mode
        self.max_episode_steps = (
            self.task.max_episode_steps if max_episode_steps is None else int(max_episode_steps)
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        self.action_space = batch_space(self.single_action_space, num_envs)
        size = self.task.observation_size
        self.single_observation_space = spaces.Box(-1.0, 1.0, (size,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, num_envs)

        self.scenes = list(scenes)
        self._rows = np.array([self.config.scene_row(s) for s in scenes])
        self._q = np.array([wrap_rate(s) for s in scenes], dtype=float)
        self._psi_rate = np.array([psi_rate(s) for s in scenes], dtype=float)
        self.phi = np.zeros(num_envs)
        self.phi_dot = np.zeros(num_envs)
        self.target = np.array([self.task.default_target(s) for s in scenes], dtype=float)
        self.torque = np.zeros(num_envs)
        self.steps = np.zeros(num_envs, dtype=np.int64)
        self._done = np.zeros(num_envs, dtype=bool)
        self._rngs: list[np.random.Generator] = []
        self._raw = np.empty((10, num_envs))
        cfg = self.config
        self._stepper = integ.BatchStepper(num_envs, method=cfg.integrator, dt=cfg.dt,
                                           tol=cfg.tolerance, substeps=cfg.substeps or None)
        self._stepper.scene_table()[:] = self._rows.T
        self._renderers: list[Any] | None = None

    @staticmethod
    def _per_env_scenes(scene: Any, n: int) -> list[Any]:
        """The per-sub-environment scenes given, or [] when one scene serves all."""
        if isinstance(scene, Scene) and scene.batch_size is not None:
            if scene.batch_size != n:
                raise ValueError(
                    f"scene is a batch of {scene.batch_size} rollers; num_envs={n} needs {n}"
                )
            return [scene.item(i) for i in range(n)]
        if isinstance(scene, list | tuple):
            if len(scene) != n:
                raise ValueError(f"scene has {len(scene)} entries; num_envs={n} needs {n}")
            return list(scene)
        return []

    def _start(self, i: int, options: Mapping[str, Any] | None) -> None:
        """Start a new episode in sub-environment i (the same draws as RollerEnv.reset)."""
        config = self._configs[i]
        scene, target, phi, phi_dot = episode_start(config, self._rngs[i], options)
        if scene is not self.scenes[i]:  # randomized or set by options: its numbers anew
            self.scenes[i] = scene
            self._rows[i] = config.scene_row(scene)
            self._stepper.scene_table()[:, i] = self._rows[i]
            self._q[i] = wrap_rate(scene)
            self._psi_rate[i] = psi_rate(scene)
        self.target[i], self.phi[i], self.phi_dot[i] = target, phi, phi_dot
        self.torque[i] = 0.0
        self.steps[i] = 0

    def reset(
        self,
        *,
        seed: int | Sequence[int | None] | None = None,
        options: dict[str, Any] | None = None,
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset sub-environments (all, or those in ``options["reset_mask"]``).

        ``seed``: an int gives sub-environment i the seed ``seed + i``; a list gives each its
        own. ``options`` as in :meth:`roller_gym.roller_env.RollerEnv.reset`, for every reset
        sub-environment.
        """
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        mask = np.ones(self.num_envs, bool) if mask is None else np.asarray(mask, bool)
        if seed is None:
            seeds: Sequence[int | None] = [None] * self.num_envs
        elif isinstance(seed, int | np.integer):
            seeds = [int(seed) + i for i in range(self.num_envs)]
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"seed has {len(seeds)} entries for num_envs={self.num_envs}")
        if not self._rngs:
            self._rngs = [seeding.np_random(s)[0] for s in seeds]
        else:
            for i, s in enumerate(seeds):
                if s is not None:
                    self._rngs[i] = seeding.np_random(s)[0]
        if seed is not None:
            self._np_random, self._np_random_seed = seeding.np_random(
                seeds[0] if isinstance(seeds[0], int) else None
            )
        for i in np.flatnonzero(mask):
            self._start(int(i), options)
        self._done[mask] = False
        return self._observation(), self._reset_info()

    def step(
        self, actions: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        a = self.config.action_values(actions, (self.num_envs, 1))[:, 0]
        if not self._rngs:
            raise RuntimeError("call reset() before step()")
        tau = a * self.task.max_torque
        res = self._stepper.advance(self.phi, self.phi_dot, tau)
        raw = self._raw
        for j, name in enumerate(integ.STEP_FIELDS[:10]):
            raw[j] = getattr(res, name)
        self.phi, self.phi_dot, self.torque = raw[0].copy(), raw[1].copy(), tau
        finite = raw[4] != 0
        lifting, slipping = raw[8] <= 0.0, raw[9] < 0.0
        terminated = lifting | slipping | ~finite
        self.steps += 1
        truncated = self.steps >= self.max_episode_steps
        error = np.asarray(self.task.error(self.phi, self.target, self._q), dtype=float)
        reward = np.asarray(self.task.reward_from_error(error, self.phi_dot, a), dtype=np.float64)
        info = self._info(raw, lifting, slipping, ~finite, error)

        # Next-step autoreset: the sub-environments that ended last step start over now.
        restarted = np.flatnonzero(self._done)
        for i in restarted:
            self._start(int(i), None)
        if restarted.size:
            reward[restarted] = 0.0
            terminated[restarted] = False
            truncated[restarted] = False
            self._fill_reset_info(info, restarted)
        self._done = terminated | truncated
        return self._observation(), reward, terminated, truncated, info

    # -- observation and info --------------------------------------------------------
    def _observation(self) -> np.ndarray:
        terms = self.task.observation_terms(self.phi, self.phi_dot, self.target, self._psi_rate)
        return np.stack(terms, axis=1).astype(np.float32)

    def _info(self, raw: np.ndarray, lifting, slipping, nonfinite, error) -> dict[str, Any]:
        info = {
            "phi": self.phi.copy(),
            "phi_dot": self.phi_dot.copy(),
            "psi": self._psi_rate * self.phi,
            "torque": self.torque.copy(),
            "normal_force": raw[5].copy(),
            "friction_force": raw[6].copy(),
            "energy": raw[7].copy(),
            "substeps": raw[3].astype(np.int64),
            "lifting": lifting,
            "slipping": slipping,
            "nonfinite": nonfinite,
            "liftoff_margin": raw[8].copy(),
            "slip_margin": raw[9].copy(),
            "target_phi": self.target.copy(),
            "target_psi": self._psi_rate * self.target,
            "position_error": error,
            "is_success": np.asarray(self.task.success_from_error(error, self.phi_dot),
                                     dtype=bool),
        }
        mask = np.ones(self.num_envs, dtype=bool)
        info.update({f"_{k}": mask for k in list(info)})
        return info

    def _reset_info(self) -> dict[str, Any]:
        n = self.num_envs
        info = self._info(np.zeros((10, n)), np.zeros(n, bool), np.zeros(n, bool),
                          np.zeros(n, bool), np.zeros(n))
        self._fill_reset_info(info, np.arange(self.num_envs))
        return info

    def _fill_reset_info(self, info: dict[str, Any], idx: np.ndarray) -> None:
        """The info entries of sub-environments that just started: their start state."""
        m, r, kappa, e, k, g, c, mu = self._rows[idx].T
        phi, phi_dot, target, q = self.phi[idx], self.phi_dot[idx], self.target[idx], self._q[idx]
        a = eq.accel(phi, phi_dot, 0.0, m, r, kappa, e, k, g, c)
        normal, friction = eq.contact_forces(phi, phi_dot, a, m, r, kappa, e, g)
        lift, slip = normal / (m * g), (mu * normal - np.abs(friction)) / (m * g)
        for key, value in (
            ("phi", phi), ("phi_dot", phi_dot), ("psi", self._psi_rate[idx] * phi),
            ("torque", 0.0), ("normal_force", normal), ("friction_force", friction),
            ("energy", eq.energy(phi, phi_dot, m, r, kappa, e, k, g)), ("substeps", 0),
            ("lifting", lift <= 0), ("slipping", slip < 0), ("nonfinite", False),
            ("liftoff_margin", lift), ("slip_margin", slip), ("target_phi", target),
            ("target_psi", self._psi_rate[idx] * target),
            ("position_error", self.task.error(phi, target, q)),
            ("is_success", self.task.success(phi, phi_dot, target, q)),
        ):
            info[key][idx] = value

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One RGB frame per sub-environment (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            return None
        from roller_gym.rendering import Renderer

        if self._renderers is None:
            self._renderers = [Renderer("rgb_array", self.metadata["render_fps"])
                               for _ in range(self.num_envs)]
        return tuple(
            r.draw(self.scenes[i], self.phi[i], self.target[i], self.torque[i],
                   self.task.max_torque, self.task.observes_target)
            for i, r in enumerate(self._renderers)
        )

    def close_extras(self, **kwargs: Any) -> None:
        for r in getattr(self, "_renderers", None) or []:  # also after a failed __init__
            r.close()
        self._renderers = None
