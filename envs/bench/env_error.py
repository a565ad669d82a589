"""Part 3 of the work-precision study (:mod:`roller_gym.bench.workprecision`): the
environments' own state error at default settings on the reference episode, through
``gymnasium.make`` and ``gymnasium.make_vec``."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["env_episode_error", "global_error", "measure_environments", "vector_episode_error"]


def global_error(states: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """The largest error along the episode (|Δφ| [rad], |Δφ'| [rad/s]); inf if it diverged."""
    if not np.isfinite(states).all():
        return math.inf, math.inf
    worst = np.abs(states - ref).max(axis=0)
    return float(worst[0]), float(worst[1])


def env_episode_error(ref: np.ndarray, torques: np.ndarray, seed: int) -> tuple[float, float]:
    """The state error (φ [rad], φ' [rad/s]) of
    ``gymnasium.make("roller_gym/RollerStabilize-v2")`` at default settings over the reference
    episode: the same start (rest at φ = 0) and the same torques, through the env."""
    import gymnasium as gym

    env = gym.make("roller_gym/RollerStabilize-v2")
    base = env.unwrapped
    base.reset(seed=seed, options={"state": (0.0, 0.0)})
    states = [(0.0, 0.0)]
    for tau in torques:  # the episode goes on past a termination: the physics is measured
        base.step(np.array([tau / base.task.max_torque], dtype=np.float32))
        states.append((base.phi, base.phi_dot))
    env.close()
    return global_error(np.array(states), ref)


def vector_episode_error(ref: np.ndarray, torques: np.ndarray, n: int,
                         seed: int) -> tuple[float, float]:
    """The same for ``gymnasium.make_vec`` with ``n`` sub-environments, all on the reference
    episode, up to the first step at which one terminates (autoreset would restart it)."""
    import gymnasium as gym

    env = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=n)
    env.reset(seed=seed, options={"state": (0.0, 0.0)})
    base = env.unwrapped
    worst = np.zeros(2)
    for i, tau in enumerate(torques):
        a = np.full((n, 1), tau / base.task.max_torque, dtype=np.float32)
        _, _, terminated, truncated, info = env.step(a)
        if terminated.any() or truncated.any():
            break
        got = np.stack([info["phi"], info["phi_dot"]], axis=1)
        worst = np.maximum(worst, np.abs(got - ref[i + 1]).max(axis=0))
    env.close()
    return float(worst[0]), float(worst[1])


def measure_environments(ref: np.ndarray, torques: np.ndarray, n: int,
                         seed: int) -> dict[str, Any]:
    """The state errors (φ [rad], φ' [rad/s]) of the environments at default settings on
    the default scene's reference episode (``ref``: its states, one row per control step;
    ``torques`` [N·m]): one through ``gymnasium.make``, and ``n`` sub-environments of
    ``gymnasium.make_vec``; ``seed`` their resets'."""
    import roller_gym  # noqa: F401 - registers the environments

    return {"env_error": list(env_episode_error(ref, torques, seed)),
            "vector_error": list(vector_episode_error(ref, torques, n, seed)),
            "vector_error_envs": n}
