"""roller-gym's sample agents: trained (stable-baselines3) and classical policies.

Every policy offers stable-baselines3's ``predict(observation, deterministic=True) ->
(action, state)``, so one evaluation path (:func:`rollout`) serves them all.

=====================  ===============================================================
module                 what it holds
=====================  ===============================================================
``hyperparams``        the rl-zoo3 hyperparameter files (``sac.yml``, ...) per
                       task, and the classical controllers' settings (its function
                       ``hyperparams`` is not re-exported here: the name would hide
                       the module)
``observation``        the state (φ, φ', target φ*) recovered from an observation
``classical``          :class:`LQR` (Stabilize, Hold), :class:`EnergySwingUp`
                       (Balance), :class:`ZeroTorque`, :class:`RandomPolicy`
``policies``           loading a trained run, the baselines by name, playing an episode
=====================  ===============================================================

The commands: ``roller-gym train`` (train and save a run with rl-zoo3), ``roller-gym
evaluate`` (the results table and plots), ``roller-gym replay`` (an episode to a GIF).

Example::

    import gymnasium as gym
    import roller_gym
    from roller_gym.agents import LQR, rollout

    env = gym.make("roller_gym/RollerHold-v2")
    episode = rollout(env, LQR.from_env(env), seed=0)
    print(episode.total_return, episode.success)
"""

from roller_gym.agents.classical import (
    LQR,
    Controller,
    EnergyPump,
    EnergySwingUp,
    Informed,
    RandomPolicy,
    ZeroTorque,
    controller_for,
)
from roller_gym.agents.hyperparams import CLASSICAL
from roller_gym.agents.observation import DecodedState, decode_observation
from roller_gym.agents.policies import TrainedPolicy, baseline, load_policy, rollout

__all__ = [
    "CLASSICAL",
    "LQR",
    "Controller",
    "DecodedState",
    "EnergyPump",
    "EnergySwingUp",
    "Informed",
    "RandomPolicy",
    "TrainedPolicy",
    "ZeroTorque",
    "baseline",
    "controller_for",
    "decode_observation",
    "load_policy",
    "rollout",
]
