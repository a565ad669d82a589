"""Ray RLlib runs the tasks unchanged: one short PPO iteration of ``scripts/train_rllib.py``.

On a local Ray (2 CPUs), two env runners (remote processes) make roller_gym/RollerStabilize-v2 with
``gymnasium.make`` through Ray's registry; one PPO iteration must report a finite episode
return, and the saved checkpoint must restore to the trained policy: the restored module
gives the trained module's deterministic actions, which differ from the untrained ones.

Needs the ``rllib`` extra (its own environment: RLlib pins its Gymnasium release); skipped
without it. About a minute here.
"""

from __future__ import annotations

import importlib.util
import math
import sys
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

pytest.importorskip(
    "ray.rllib", reason="the rllib extra is not installed: pip install -e '.[rllib]'"
)

import ray
import torch
from ray.rllib.algorithms.algorithm import Algorithm
from ray.rllib.core.rl_module.rl_module import RLModule
from ray.rllib.utils.metrics import (
    ENV_RUNNER_RESULTS,
    EPISODE_RETURN_MEAN,
    NUM_ENV_STEPS_SAMPLED_LIFETIME,
)

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "train_rllib.py"
ENV_ID = "roller_gym/RollerStabilize-v2"
TRAIN_BATCH = 800  # env steps of the iteration: 400 per runner, two or more episodes each
MAX_TORQUE = 0.3  # not the default (0.5): it must reach the remote runners' environments


def load_script() -> ModuleType:
    spec = importlib.util.spec_from_file_location("train_rllib", SCRIPT)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def local_ray() -> Iterator[None]:
    ray.init(address="local", num_cpus=2, include_dashboard=False,
             object_store_memory=200 * 1024**2, log_to_driver=False)
    try:
        yield
    finally:
        ray.shutdown()


def deterministic_actions(module: RLModule, obs: np.ndarray) -> np.ndarray:
    """The policy's inference actions (the mean, no exploration noise) for a batch of obs."""
    with torch.no_grad():
        out = module.forward_inference({"obs": torch.as_tensor(obs)})
        dist = module.get_inference_action_dist_cls().from_logits(out["action_dist_inputs"])
        return dist.to_deterministic().sample().numpy()


def test_ppo_iteration_on_two_env_runners_and_checkpoint_restores(
    local_ray: None, tmp_path: Path
) -> None:
    script = load_script()
    script.register_tasks()
    args = script.parse_args([
        "--algo", "PPO", "--env", ENV_ID, "--num-env-runners", "2", "--envs-per-runner", "1",
        "--train-batch-size", str(TRAIN_BATCH), "--minibatch-size", "100", "--num-epochs", "4",
        "--seed", "0",
    ])
    torch.set_num_threads(1)
    algo = script.build_config(args, {"max_torque": MAX_TORQUE}).build_algo()
    try:
        # The env runners are remote processes that made the task with our kwargs.
        torques = algo.env_runner_group.foreach_env_runner(
            lambda runner: [e.unwrapped.task.max_torque for e in runner.env.unwrapped.envs],
            local_env_runner=False,
        )
        assert torques == [[MAX_TORQUE], [MAX_TORQUE]]

        obs = np.random.default_rng(0).uniform(-1, 1, (16, 5)).astype(np.float32)
        untrained = deterministic_actions(algo.get_module(), obs)

        result = algo.train()
        line, steps = script.progress(result, 0)
        print(line)
        runners = result[ENV_RUNNER_RESULTS]
        assert math.isfinite(runners[EPISODE_RETURN_MEAN])
        assert 0.0 < runners[EPISODE_RETURN_MEAN] <= 200.0  # reward in [0, 1], 200 steps
        assert steps == runners[NUM_ENV_STEPS_SAMPLED_LIFETIME] >= TRAIN_BATCH

        trained = deterministic_actions(algo.get_module(), obs)
        assert np.all(np.isfinite(trained)) and trained.shape == (16, 1)
        assert not np.allclose(trained, untrained)  # the iteration did update the policy
        checkpoint = algo.save_to_path(str(tmp_path / "checkpoint"))
    finally:
        algo.stop()

    restored = Algorithm.from_checkpoint(checkpoint)
    try:
        assert restored.iteration == 1
        np.testing.assert_array_equal(deterministic_actions(restored.get_module(), obs), trained)
    finally:
        restored.stop()
