"""Every hyperparameter of the sample agents, per (algorithm, task), in one place.

``HYPERPARAMS[(algo, env_id)]`` is a plain dict, as rl-baselines3-zoo's YAML files:

* ``total_steps``: environment steps of the default training run (all environments
  together);
* ``n_envs``: parallel environments (stable-baselines3's ``DummyVecEnv``);
* ``normalize``: False, or the keyword arguments of ``VecNormalize`` (its statistics are
  saved next to the model);
* ``action_noise_std``: TD3's Gaussian exploration noise, as a share of the action range;
* everything else goes to the algorithm's constructor as it stands (``policy_kwargs``
  included).

The steps were chosen to fit the whole results run (9 trainings) in about an hour on a
shared 2-core CPU; see ``docs/RESULTS.md`` for what they achieve.

``CLASSICAL[env_id]`` holds the classical controllers' settings (see
:mod:`agents.classical`): Bryson's-rule scales of the LQR, the swing-up's energy gain and
its handover band.
"""

from __future__ import annotations

import copy
from typing import Any

__all__ = ["ALGOS", "CLASSICAL", "HYPERPARAMS", "TASKS", "hyperparams"]

ALGOS = ("sac", "td3", "ppo")
TASKS = ("RollerStabilize-v0", "RollerHold-v0", "RollerBalance-v0")

# Small networks: the state is two numbers (three with a target), and on this CPU the
# gradient step, not the physics, is what a training run spends its time on.
_SMALL = {"net_arch": [64, 64]}

_SAC = {
    "n_envs": 1,
    "normalize": False,  # observations are already in [-1, 1], rewards in [0, 1]
    "learning_rate": 1e-3,
    "buffer_size": 100_000,
    "learning_starts": 1_000,
    "batch_size": 256,
    "gamma": 0.99,
    "train_freq": 1,
    "gradient_steps": 1,
    "policy_kwargs": _SMALL,
}

_TD3 = {
    "n_envs": 1,
    "normalize": False,
    "action_noise_std": 0.1,
    "learning_rate": 1e-3,
    "buffer_size": 100_000,
    "learning_starts": 1_000,
    "batch_size": 256,
    "gamma": 0.99,
    "train_freq": 1,
    "gradient_steps": 1,
    "policy_kwargs": _SMALL,
}

_PPO = {
    "n_envs": 8,
    "normalize": False,
    "n_steps": 256,  # 8 x 256 = 2048 steps per update
    "batch_size": 64,
    "n_epochs": 10,
    "learning_rate": 1e-3,
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
    "policy_kwargs": _SMALL,
}

HYPERPARAMS: dict[tuple[str, str], dict[str, Any]] = {
    # -- RollerStabilize-v0: 200 steps, rest at the bottom --------------------------------
    ("sac", "RollerStabilize-v0"): {**_SAC, "total_steps": 20_000},
    ("td3", "RollerStabilize-v0"): {**_TD3, "total_steps": 20_000},
    ("ppo", "RollerStabilize-v0"): {**_PPO, "total_steps": 200_000},
    # -- RollerHold-v0: 200 steps, a target drawn per episode ------------------------------
    ("sac", "RollerHold-v0"): {**_SAC, "total_steps": 40_000},
    ("td3", "RollerHold-v0"): {**_TD3, "total_steps": 40_000},
    ("ppo", "RollerHold-v0"): {**_PPO, "total_steps": 300_000},
    # -- RollerBalance-v0: 400 steps, swing-up and balance ---------------------------------
    ("sac", "RollerBalance-v0"): {**_SAC, "total_steps": 60_000},
    ("td3", "RollerBalance-v0"): {**_TD3, "total_steps": 60_000},
    ("ppo", "RollerBalance-v0"): {**_PPO, "total_steps": 400_000},
}

CLASSICAL: dict[str, dict[str, float]] = {
    # LQR weights (Bryson's rule): acceptable error 0.1 rad, speed 1 rad/s, torque 0.5 N·m.
    # The return is flat around them (±0.3% over a 4 x 4 x 3 grid of scales).
    "RollerStabilize-v0": {"position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5},
    "RollerHold-v0": {"position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5},
    # Swing-up: energy gain [N·m/(J·rad/s)]; LQR handover within 0.5 rad and 1.5 rad/s.
    "RollerBalance-v0": {
        "energy_gain": 20.0,
        "capture_angle": 0.5,
        "capture_speed": 1.5,
        "position_scale": 0.1,
        "speed_scale": 1.0,
        "torque_scale": 0.5,
    },
}


def hyperparams(algo: str, env_id: str) -> dict[str, Any]:
    """A copy of ``HYPERPARAMS[(algo, env_id)]`` (safe to modify).

    Args:
        algo: ``"sac"``, ``"td3"`` or ``"ppo"``.
        env_id: a task ID, e.g. ``"RollerStabilize-v0"``.

    Raises:
        ValueError: no entry for the pair; the message lists the known ones.
    """
    key = (algo.lower(), env_id)
    if key not in HYPERPARAMS:
        known = ", ".join(f"{a}/{e}" for a, e in HYPERPARAMS)
        raise ValueError(f"no hyperparameters for algo={algo!r}, env={env_id!r}; known: {known}")
    return copy.deepcopy(HYPERPARAMS[key])
