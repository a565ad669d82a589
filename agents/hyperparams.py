"""Every hyperparameter of the sample agents, per (algorithm, task), in one place.

``HYPERPARAMS[(algo, env_id)]`` is a plain dict, as rl-baselines3-zoo's YAML files:

* ``total_steps``: environment steps of the default training run (all environments
  together);
* ``n_envs``: parallel environments (stable-baselines3's ``DummyVecEnv``);
* ``normalize``: False, or the keyword arguments of ``VecNormalize`` (its statistics are
  saved next to the model). Off everywhere: the observations are already in [−1, 1] and
  the rewards in [0, 1];
* ``action_noise_std``: the standard deviation of TD3's Gaussian exploration noise, in
  action units (actions lie in [−1, 1]);
* everything else goes to the algorithm's constructor as it stands (``policy_kwargs``
  included).

The steps were chosen to fit the whole results run (9 trainings) in about an hour on a
2-core x86-64 CPU under load from other processes; see ``docs/RESULTS.md`` for what they achieve.

``CLASSICAL[env_id]`` holds the classical controllers' settings (see
:mod:`roller_gym.agents.classical`): Bryson's-rule scales of the LQR, the swing-up's energy gain and
its handover band.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

__all__ = ["ALGOS", "CLASSICAL", "HYPERPARAMS", "TASKS", "Linear", "hyperparams"]

ALGOS = ("sac", "td3", "ppo")
TASKS = ("roller_gym/RollerStabilize-v0", "roller_gym/RollerHold-v0", "roller_gym/RollerBalance-v0")

@dataclass(frozen=True)
class Linear:
    """A schedule (e.g. of the learning rate) from ``start`` down to 0 at the end of training.

    stable-baselines3 calls it with the remaining progress, 1 at the start and 0 at the end;
    it goes below 0 when a run overshoots its steps (PPO finishes its last rollout), where
    the schedule stays at 0: a negative learning rate would undo the training.
    """

    start: float

    def __call__(self, progress_remaining: float) -> float:
        return self.start * max(progress_remaining, 0.0)


# Small networks: the state is two numbers (three with a target), and on a CPU the
# gradient step, not the physics, is what a training run spends its time on.
_SMALL = {"net_arch": [64, 64]}

# SAC and TD3 share the off-policy settings; TD3 adds its exploration noise.
_SAC = {
    "n_envs": 1,
    "normalize": False,
    "learning_rate": 1e-3,
    "buffer_size": 100_000,
    "learning_starts": 1_000,
    "batch_size": 256,
    "gamma": 0.99,
    "train_freq": 1,
    "gradient_steps": 1,
    "policy_kwargs": _SMALL,
}

_TD3 = {**_SAC, "action_noise_std": 0.1}

_PPO = {
    "n_envs": 8,
    "normalize": False,
    "n_steps": 256,  # 8 x 256 = 2048 steps per update
    "batch_size": 64,
    "n_epochs": 10,
    # Decayed to 0: with a constant 1e-3, PPO's return on Balance collapsed for a while
    # late in training (370 -> 20 -> 370 between 150k and 170k steps).
    "learning_rate": Linear(1e-3),
    "gamma": 0.99,
    "gae_lambda": 0.95,
    "clip_range": 0.2,
    "ent_coef": 0.0,
    "policy_kwargs": _SMALL,
}

HYPERPARAMS: dict[tuple[str, str], dict[str, Any]] = {
    # -- roller_gym/RollerStabilize-v0: 200 steps, rest at the bottom
    # SAC and TD3 reach LQR's return after about 3,000 steps, PPO after about 10,000.
    ("sac", "roller_gym/RollerStabilize-v0"): {**_SAC, "total_steps": 10_000},
    ("td3", "roller_gym/RollerStabilize-v0"): {**_TD3, "total_steps": 10_000},
    ("ppo", "roller_gym/RollerStabilize-v0"): {**_PPO, "total_steps": 50_000},
    # -- roller_gym/RollerHold-v0: 200 steps, a target drawn per episode
    # All three reach LQR's return after 4,000 to 10,000 steps (SAC, TD3), 20,000 (PPO).
    ("sac", "roller_gym/RollerHold-v0"): {**_SAC, "total_steps": 15_000},
    ("td3", "roller_gym/RollerHold-v0"): {**_TD3, "total_steps": 15_000},
    ("ppo", "roller_gym/RollerHold-v0"): {**_PPO, "total_steps": 100_000},
    # -- roller_gym/RollerBalance-v0: 400 steps, swing-up and balance
    # SAC balances after about 6,000 steps, TD3 after 12,000-15,000, PPO after 60,000.
    ("sac", "roller_gym/RollerBalance-v0"): {**_SAC, "total_steps": 25_000},
    ("td3", "roller_gym/RollerBalance-v0"): {**_TD3, "total_steps": 25_000},
    ("ppo", "roller_gym/RollerBalance-v0"): {**_PPO, "total_steps": 150_000},
}

CLASSICAL: dict[str, dict[str, float]] = {
    # LQR weights (Bryson's rule): acceptable error 0.1 rad, speed 1 rad/s, torque 0.5 N·m.
    # The return is flat around them (±0.3% over a 4 x 4 x 3 grid of scales).
    "roller_gym/RollerStabilize-v0": {
        "position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5,
    },
    "roller_gym/RollerHold-v0": {"position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5},
    # Swing-up: energy gain [N·m·s/(J·rad)]; LQR handover within 0.5 rad and 1.5 rad/s.
    "roller_gym/RollerBalance-v0": {
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
        env_id: a task ID, e.g. ``"roller_gym/RollerStabilize-v0"``.

    Raises:
        ValueError: no entry for the pair; the message lists the known ones.
    """
    key = (algo.lower(), env_id)
    if key not in HYPERPARAMS:
        known = ", ".join(f"{a}/{e}" for a, e in HYPERPARAMS)
        raise ValueError(f"no hyperparameters for algo={algo!r}, env={env_id!r}; known: {known}")
    return copy.deepcopy(HYPERPARAMS[key])
