"""The single roller environment: a Gymnasium ``Env`` on the physics of :mod:`roller_gym.physics`.

The tasks (``stabilize.py``, ``hold.py``, ``balance.py``) subclass :class:`RollerEnv`
with their :class:`~roller_gym.task.Task`; this file holds what they share: construction,
reset, step, info and rendering.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from roller_gym.config import DEFAULT_DT, DEFAULT_TOLERANCE, EnvConfig
from roller_gym.physics import Scene, contact, energy
from roller_gym.physics import integrators as integ
from roller_gym.task import Task, psi_rate, wrap_rate

__all__ = ["RollerEnv", "episode_start"]


def episode_start(
    config: EnvConfig, rng: np.random.Generator, options: Mapping[str, Any] | None
) -> tuple[Scene, float, float, float]:
    """(scene, φ* [rad], φ [rad], φ' [rad/s]) of a new episode, from ``rng`` and ``options``.

    The draws are made in one order (scene, target, state) whatever the options, so that a
    seed gives the same episode in the single and the vector environment; only the state's
    draw is skipped when ``options["state"]`` gives it (the draw may be impossible there, e.g.
    in a scene with too little friction for a random start).
    """
    options = dict(options or {})
    unknown = set(options) - {"state", "target", "scene"}
    if unknown:
        raise ValueError(
            f"reset options {sorted(unknown)} are not known; allowed: 'state', 'target', 'scene'"
        )
    scene = config.draw_scene(rng)
    if options.get("scene") is not None:
        scene = config.resolve_option_scene(options["scene"])
        config.task.check_scene(scene)
    target = config.task.sample_target(rng, scene)
    if options.get("target") is not None:
        target = config.task.target_from_option(options["target"], scene)
    if options.get("state") is None:
        phi, phi_dot = config.task.sample_state(rng, scene, target)
    else:
        try:
            phi, phi_dot = (float(x) for x in options["state"])
        except (TypeError, ValueError):
            raise ValueError(
                f"options['state']={options['state']!r} must be a pair (phi [rad], "
                "phi_dot [rad/s]) of numbers"
            ) from None
        if not (math.isfinite(phi) and math.isfinite(phi_dot)):
            raise ValueError(f"options['state']={options['state']!r} must be finite")
    return scene, float(target), phi, phi_dot


class RollerEnv(gym.Env[np.ndarray, np.ndarray]):
    """A roller driven by a torque, rolling without slipping on a fixed surface.

    Args:
        scene: an :class:`roller_gym.Scene` or a preset's name (``roller_gym.PRESETS``);
            default: the task's preset.
        dt: the control step [s]; the torque is constant over it.
        max_torque: the torque [N·m] an action of ±1 applies; default: the task's.
        tolerance: the integrator's target state error per control step (φ [rad],
            φ' [rad/s]); it sets the number of substeps.
        integrator: ``"rk8"`` (8th order at automatic substeps; the default and the
            fastest at tight tolerances), ``"rk4"``, ``"euler"`` (semi-implicit, Pendulum's
            scheme), ``"midpoint"`` (implicit, energy-stable) or ``"dop853"`` (scipy's
            adaptive, slow: a reference).
        substeps: a fixed number of substeps per control step instead of the automatic rule.
        randomize: ``{field: (low, high)}``: Scene fields drawn uniformly at each reset
            (domain randomization), e.g. ``{"m": (0.8, 1.2), "e": (0.03, 0.05)}``.
        render_mode: ``"human"``, ``"rgb_array"`` or None.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": ["human", "rgb_array"], "render_fps": 20}
    task_class: ClassVar[type[Task]]

    def __init__(
        self,
        scene: Scene | str | None = None,
        dt: float = DEFAULT_DT,
        max_torque: float | None = None,
        tolerance: float = DEFAULT_TOLERANCE,
        integrator: str = "rk8",
        substeps: int | None = None,
        randomize: Mapping[str, tuple[float, float]] | None = None,
        render_mode: str | None = None,
    ) -> None:
        self.config = EnvConfig.build(
            self.task_class, scene=scene, dt=dt, max_torque=max_torque, tolerance=tolerance,
            integrator=integrator, substeps=substeps, randomize=randomize,
            render_mode=render_mode, render_modes=self.metadata["render_modes"],
        )
        self.task = self.config.task
        self.render_mode = render_mode
        self.action_space = spaces.Box(-1.0, 1.0, (1,), np.float32)
        size = self.task.observation_size
        self.observation_space = spaces.Box(-1.0, 1.0, (size,), np.float32)
        self._set_scene(self.config.scene)
        self.target = self.task.default_target(self.scene)
        self.phi, self.phi_dot, self.torque = self.target, 0.0, 0.0
        self._renderer = None

    def _set_scene(self, scene: Scene) -> None:
        self.scene = scene
        cfg = self.config
        self._stepper = integ.Stepper(scene, method=cfg.integrator, dt=cfg.dt,
                                      tol=cfg.tolerance, substeps=cfg.substeps or None)
        self._q = wrap_rate(scene)
        self._psi_rate = psi_rate(scene)

    # -- Gymnasium API -----------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode. ``options``: ``"state"``: (φ [rad], φ' [rad/s]); ``"target"``:
        the task's target (see the task); ``"scene"``: a Scene or preset for this episode."""
        super().reset(seed=seed)
        scene, self.target, self.phi, self.phi_dot = episode_start(
            self.config, self.np_random, options
        )
        self._set_scene(scene)
        self.torque = 0.0
        c = contact(scene, self.phi, self.phi_dot, 0.0)
        info = self._info(0.0, float(c.normal), float(c.friction),
                          float(energy(scene, self.phi, self.phi_dot)), 0, bool(c.lifting),
                          bool(c.slipping), False, float(c.liftoff_margin), float(c.slip_margin),
                          self.task.error(self.phi, self.target, self._q))
        if self.render_mode == "human":
            self.render()
        return self._observation(), info

    def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if type(action) is np.ndarray and action.shape == (1,) and math.isfinite(action[0]):
            a = min(1.0, max(-1.0, float(action[0])))  # the common case, without the checks' cost
        else:
            a = float(self.config.action_values(action, (1,))[0])
        tau = a * self.task.max_torque
        phi, phi_dot, _, substeps, finite, normal, friction, energy, lift, slip, _, _ = (
            self._stepper.advance(self.phi, self.phi_dot, tau)
        )
        self.phi, self.phi_dot, self.torque = phi, phi_dot, tau
        lifting, slipping, nonfinite = lift <= 0.0, slip < 0.0, not finite
        error = self.task.error(phi, self.target, self._q)
        reward = float(self.task.reward_from_error(error, phi_dot, a))
        info = self._info(tau, normal, friction, energy, substeps, lifting, slipping,
                          nonfinite, lift, slip, error)
        if self.render_mode == "human":
            self.render()
        return self._observation(), reward, lifting or slipping or nonfinite, False, info

    def _observation(self) -> np.ndarray:
        return np.array(
            self.task.observation_terms(self.phi, self.phi_dot, self.target, self._psi_rate),
            dtype=np.float32,
        )

    def _info(self, tau, normal, friction, energy, substeps, lifting, slipping, nonfinite,
              lift, slip, error) -> dict[str, Any]:
        return {
            "phi": self.phi,
            "phi_dot": self.phi_dot,
            "psi": self._psi_rate * self.phi,
            "torque": tau,
            "normal_force": normal,
            "friction_force": friction,
            "energy": energy,
            "substeps": int(substeps),
            "lifting": bool(lifting),
            "slipping": bool(slipping),
            "nonfinite": bool(nonfinite),
            "liftoff_margin": lift,
            "slip_margin": slip,
            "target_phi": self.target,
            "target_psi": self._psi_rate * self.target,
            "position_error": float(error),
            "is_success": bool(self.task.success_from_error(error, self.phi_dot)),
        }

    # -- rendering ---------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        if self.render_mode is None:
            gym.logger.warn(
                "render() was called without a render_mode; pass render_mode='rgb_array' or "
                f"'human' to gymnasium.make({self.spec.id if self.spec else ''!r}, ...)"
            )
            return None
        if self._renderer is None:
            from roller_gym.rendering import Renderer  # pygame is imported only when rendering

            self._renderer = Renderer(self.render_mode, self.metadata["render_fps"])
        return self._renderer.draw(self.scene, self.phi, self.target, self.torque,
                                   self.task.max_torque, self.task.observes_target)

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
