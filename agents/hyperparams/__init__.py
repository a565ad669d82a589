"""The hyperparameters of the sample agents and the classical controllers' settings.

The trained agents' hyperparameters live in rl-baselines3-zoo's YAML format, one file per
algorithm next to this module (``sac.yml``, ``td3.yml``, ``ppo.yml``), keyed by task ID. They
are the only copy: ``roller-gym train`` passes the file to rl-zoo3, and so can you::

    python -m rl_zoo3.train --algo sac --env roller_gym/RollerStabilize-v2 \\
        --gym-packages roller_gym -conf PATH

where PATH is ``str(config_file("sac"))``; ``roller-gym train --show-command`` prints the
whole command with it.

An entry holds, as rl-zoo3 reads it: ``n_timesteps`` (environment steps of the default run,
all environments together), ``policy``, ``n_envs`` (parallel environments), ``normalize``
(``VecNormalize``, off), ``policy_kwargs`` (a Python expression, as a string), schedules as
``"lin_<start>"``, TD3's ``noise_type``/``noise_std``; everything else goes to the algorithm's
constructor. :func:`hyperparams` returns an entry as written there.

:data:`CLASSICAL` holds the classical controllers' settings (see
:mod:`roller_gym.agents.classical`), which rl-zoo3 does not know: Bryson's-rule scales of the
LQR, the swing-up's energy gain and its handover band.
"""

from __future__ import annotations

import copy
import functools
from importlib import resources
from importlib.resources.abc import Traversable
from typing import Any

from roller_gym import ENV_IDS
from roller_gym.physics.scene import shown

__all__ = ["ALGOS", "CLASSICAL", "TASKS", "config_file", "hyperparams", "load_config"]

#: The algorithms with a hyperparameter file (stable-baselines3's names, lower case).
ALGOS = ("sac", "td3", "ppo")
#: The tasks every file has an entry for: every task of the registry.
TASKS = ENV_IDS


def config_file(algo: str) -> Traversable:
    """The rl-zoo3 hyperparameter file of ``algo`` (``sac.yml`` etc.), a package resource.

    On an installed package it is a file on disk (``str(config_file("sac"))`` is its path);
    ``importlib.resources.as_file(config_file(algo))`` gives a path in every case.

    Raises:
        ValueError: ``algo`` is not one of :data:`ALGOS`.
    """
    if algo.lower() not in ALGOS:
        raise ValueError(f"algo={shown(algo)} has no hyperparameter file; allowed: "
                         f"{', '.join(ALGOS)}")
    return resources.files(__name__) / f"{algo.lower()}.yml"


@functools.cache
def _read(algo: str) -> dict[str, Any]:
    try:
        import yaml
    except ImportError:
        from roller_gym.extras import missing

        raise missing("yaml", "zoo", "reading the hyperparameter files") from None
    return yaml.safe_load(config_file(algo).read_text())


def load_config(algo: str) -> dict[str, dict[str, Any]]:
    """The whole hyperparameter file of ``algo``, parsed as rl-zoo3 parses it
    (``yaml.safe_load``): task ID -> entry. A fresh copy, safe to modify."""
    return copy.deepcopy(_read(algo.lower()))


CLASSICAL: dict[str, dict[str, float]] = {
    # LQR weights (Bryson's rule): acceptable error 0.1 rad, speed 1 rad/s, torque 0.5 N·m.
    # The return is flat around them (±0.3% over a 4 x 4 x 3 grid of scales).
    "roller_gym/RollerStabilize-v2": {
        "position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5,
    },
    "roller_gym/RollerHold-v2": {"position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5},
    "roller_gym/RollerTrack-v1": {
        "position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.5,
    },
    # The scene varies unobserved: gentler on the torque (0.1 N·m), so that the LQR informed of
    # each episode's scene seldom slips on its way (v1: 97 % success against 93 % at 0.5 N·m).
    "roller_gym/RollerHoldRandomized-v2": {
        "position_scale": 0.1, "speed_scale": 1.0, "torque_scale": 0.1,
    },
    # Swing-up: energy gain [N·m·s/(J·rad)]; LQR handover within 0.5 rad and 1.5 rad/s.
    "roller_gym/RollerBalance-v2": {
        "energy_gain": 20.0,
        "capture_angle": 0.5,
        "capture_speed": 1.5,
        "position_scale": 0.1,
        "speed_scale": 1.0,
        "torque_scale": 0.5,
    },
}
# The weak-torque Balance: the same swing-up (its return is flat in torque_scale 0.05-0.5).
CLASSICAL["roller_gym/RollerBalanceWeak-v0"] = CLASSICAL["roller_gym/RollerBalance-v2"]


def hyperparams(algo: str, env_id: str) -> dict[str, Any]:
    """The rl-zoo3 entry of ``env_id`` in ``algo``'s file, as written there (a fresh copy).

    Args:
        algo: ``"sac"``, ``"td3"`` or ``"ppo"``.
        env_id: a task ID, e.g. ``"roller_gym/RollerStabilize-v2"``.

    Raises:
        ValueError: no entry for the pair; the message lists the known tasks.
    """
    config = load_config(algo)
    if env_id not in config:
        raise ValueError(f"no hyperparameters for env={shown(env_id)} in {algo.lower()}.yml; "
                         f"known: {', '.join(k for k in config if k in TASKS)}")
    return config[env_id]
