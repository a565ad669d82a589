"""Loading policies and playing episodes: the one evaluation path every policy shares.

A *policy* is anything with stable-baselines3's ``predict(observation, deterministic=True)
-> (action, state)``: a trained model (:class:`TrainedPolicy`, which applies the saved
observation normalization), or a controller of :mod:`roller_gym.agents.classical`.

A training run (``scripts/train.py``) writes a directory::

    runs/<algo>-<env_id>/
        model.zip          the final model
        best_model.zip     the best model of the periodic evaluations
        config.json        what produced it: algo, env, env_kwargs, seed, steps, wall time, ...
        evaluations.npz    the periodic evaluations (the learning curve)
        vecnormalize.pkl   the normalization statistics (if the run normalized)
        checkpoints/, tb/, monitor/
"""

from __future__ import annotations

import json
import pickle
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from roller_gym.agents.classical import Controller, RandomPolicy, ZeroTorque, controller_for
from roller_gym.agents.hyperparams import CLASSICAL

__all__ = [
    "BASELINES",
    "Episode",
    "Policy",
    "TrainedPolicy",
    "algorithm_class",
    "baseline",
    "load_policy",
    "read_config",
    "rollout",
]

#: The baselines of the results table, by name.
BASELINES = ("classical", "zero", "random")

Policy = Any  # anything with predict(observation, deterministic=True) -> (action, state)


def algorithm_class(algo: str) -> type:
    """The stable-baselines3 class of ``"sac"``, ``"td3"`` or ``"ppo"``."""
    from stable_baselines3 import PPO, SAC, TD3

    classes = {"sac": SAC, "td3": TD3, "ppo": PPO}
    if algo.lower() not in classes:
        raise ValueError(f"algo={algo!r} is not one of {', '.join(classes)}")
    return classes[algo.lower()]


def read_config(run_dir: str | Path) -> dict[str, Any]:
    """The ``config.json`` a training run saved in ``run_dir``."""
    path = Path(run_dir) / "config.json"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found: is {run_dir} a run directory of train.py?")
    return json.loads(path.read_text())


class TrainedPolicy:
    """A saved stable-baselines3 model with the observation normalization it was trained with.

    Args:
        model: the loaded model (``SAC.load(...)`` etc.).
        normalizer: the saved ``VecNormalize`` (its statistics only), or None.
        config: the run's configuration (``config.json``), for reference.
    """

    def __init__(self, model: Any, normalizer: Any = None,
                 config: dict[str, Any] | None = None) -> None:
        self.model, self.normalizer, self.config = model, normalizer, dict(config or {})

    def predict(
        self,
        observation: np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """As ``model.predict``, on observations normalized as in training."""
        if self.normalizer is not None:
            observation = self.normalizer.normalize_obs(np.asarray(observation))
        return self.model.predict(observation, state, episode_start, deterministic)


def load_policy(run_dir: str | Path, best: bool = False, device: str = "cpu") -> TrainedPolicy:
    """Load the model a training run saved (and its normalization statistics).

    Args:
        run_dir: the run directory written by ``scripts/train.py``.
        best: load ``best_model.zip`` (the best periodic evaluation) instead of the final
            ``model.zip``.
        device: the torch device.
    """
    run_dir = Path(run_dir)
    config = read_config(run_dir)
    path = run_dir / ("best_model.zip" if best else "model.zip")
    model = algorithm_class(config["algo"]).load(path, device=device)
    normalizer = None
    stats = run_dir / "vecnormalize.pkl"
    if stats.is_file():
        with stats.open("rb") as f:
            normalizer = pickle.load(f)  # VecNormalize without its venv: statistics only
        normalizer.training = False
    return TrainedPolicy(model, normalizer, config)


def baseline(name: str, env: gym.Env, seed: int = 0) -> Controller:
    """A baseline policy for ``env``.

    Args:
        name: ``"classical"`` (LQR on Stabilize and Hold, the energy swing-up on Balance,
            with the settings of :data:`roller_gym.agents.hyperparams.CLASSICAL`), ``"zero"`` (no
            torque) or ``"random"`` (uniform actions).
        env: the environment the policy will act in (its scene, torque limit and dt).
        seed: the seed of the random policy.
    """
    if name == "classical":
        spec_id = env.spec.id if env.spec is not None else None
        return controller_for(env, **CLASSICAL.get(spec_id, {}))
    if name == "zero":
        return ZeroTorque()
    if name == "random":
        return RandomPolicy(seed)
    raise ValueError(f"baseline {name!r} is not one of {', '.join(BASELINES)}")


@dataclass(frozen=True)
class Episode:
    """One episode, step by step (arrays over the steps, t = dt, 2 dt, ...).

    Attributes:
        time: time [s] at the end of each step.
        phi, phi_dot: the state [rad, rad/s] after each step.
        error: the task's position error [rad] after each step.
        torque: the torque applied during each step [N·m].
        reward: the reward of each step.
        total_return: the sum of the rewards.
        success: ``info["is_success"]`` at the last step.
        terminated: whether the episode ended early (slip, lift-off, non-finite).
        target_phi: the episode's target rest position φ* [rad] (Balance: φ_b; −φ_b
            counts as well).
        frames: rendered frames (only with ``render=True``).
    """

    time: np.ndarray
    phi: np.ndarray
    phi_dot: np.ndarray
    error: np.ndarray
    torque: np.ndarray
    reward: np.ndarray
    total_return: float
    success: bool
    terminated: bool
    target_phi: float
    frames: list[np.ndarray] | None = None


def rollout(env: gym.Env, policy: Policy, seed: int, render: bool = False) -> Episode:
    """Play one episode of ``policy`` in ``env`` from ``env.reset(seed=seed)``.

    Args:
        env: a roller environment (``gymnasium.make(ID, ...)``; ``render_mode="rgb_array"``
            to collect frames).
        policy: anything with ``predict(observation, deterministic=True)``.
        seed: the reset seed (the same seed gives the same start state and target).
        render: collect ``env.render()`` frames (the first before the first step).
    """
    obs, info = env.reset(seed=seed)
    frames = [env.render()] if render else None
    rows: list[tuple[float, ...]] = []
    dt = float(env.unwrapped.config.dt)
    done = terminated = False
    while not done:
        action, _ = policy.predict(obs, deterministic=True)
        obs, reward, terminated, truncated, info = env.step(action)
        done = terminated or truncated
        rows.append((info["phi"], info["phi_dot"], info["position_error"], info["torque"],
                     float(reward)))
        if render:
            frames.append(env.render())
    data = np.array(rows, dtype=float).T
    return Episode(
        time=dt * np.arange(1, data.shape[1] + 1),
        phi=data[0], phi_dot=data[1], error=data[2], torque=data[3], reward=data[4],
        total_return=float(data[4].sum()), success=bool(info["is_success"]),
        terminated=bool(terminated), target_phi=float(info["target_phi"]), frames=frames,
    )
