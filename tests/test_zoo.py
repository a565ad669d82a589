"""The hyperparameter files in rl-baselines3-zoo's format: complete, read by rl-zoo3's own
ExperimentManager into models with exactly those settings, and used by ``python -m
rl_zoo3.train`` as shipped."""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
from importlib.resources import as_file
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym.agents import rollout
from roller_gym.agents.hyperparams import ALGOS, TASKS, config_file, hyperparams, load_config
from zoo import NEEDS_RL_ZOO3, import_rl_zoo3

yaml = pytest.importorskip("yaml", reason="PyYAML is not installed (it comes with the zoo extra)")

PAIRS = [(algo, env_id) for algo in ALGOS for env_id in TASKS]
#: Entries rl-zoo3 consumes itself, or that are checked on their own below.
ZOO_KEYS = {"n_timesteps", "policy", "n_envs", "normalize", "policy_kwargs", "noise_type",
            "noise_std", "learning_rate", "clip_range", "frame_stack"}


def _raw(algo: str) -> dict:
    """The file as YAML reads it, without roller_gym's reader."""
    with as_file(config_file(algo)) as path:
        return yaml.safe_load(Path(path).read_text())


def test_every_algorithm_has_a_file_with_an_entry_for_every_task_and_nothing_else():
    assert set(TASKS) == set(roller_gym.ENV_IDS)
    for algo in ALGOS:
        # No "default" entry either: rl-zoo3 would silently use it for a misspelt task ID.
        assert set(_raw(algo)) == set(TASKS), algo
        assert load_config(algo) == _raw(algo)


def test_the_module_of_the_files_is_not_hidden_by_a_name_of_its_package():
    """``import roller_gym.agents.hyperparams as h`` resolves through the package's attributes:
    a function of the same name there would stand in for the module."""
    import roller_gym.agents.hyperparams as module

    assert module.config_file("sac").name == "sac.yml"


def test_hyperparams_rejects_an_unknown_algorithm_or_task():
    with pytest.raises(ValueError, match=r"algo='a2c'.*allowed: sac, td3, ppo"):
        hyperparams("a2c", TASKS[0])
    with pytest.raises(ValueError, match=r"env='CartPole-v1'.*known: roller_gym/"):
        hyperparams("sac", "CartPole-v1")


def test_td3_has_sacs_settings_plus_its_own_exploration():
    sac, td3 = _raw("sac"), _raw("td3")
    for env_id in TASKS:
        noise = {k: td3[env_id].pop(k) for k in ("noise_type", "noise_std")}
        # Random steps before learning may differ, but stay within the training budget.
        starts = td3[env_id].pop("learning_starts")
        assert 0 < starts < td3[env_id]["n_timesteps"]
        sac[env_id].pop("learning_starts")
        assert td3[env_id] == sac[env_id]
        # rl-zoo3's two kinds of action noise, at most the half-width of the action box.
        assert noise["noise_type"] in ("normal", "ornstein-uhlenbeck")
        assert 0.0 < noise["noise_std"] <= 1.0


@NEEDS_RL_ZOO3
def test_rl_zoo3_knows_every_algorithm():
    assert set(ALGOS) <= set(import_rl_zoo3("rl_zoo3.utils").ALGOS)


@NEEDS_RL_ZOO3
@pytest.mark.parametrize("env_id", TASKS)
def test_ppo_trains_whole_rollouts_so_its_linear_schedule_ends_at_zero(env_id):
    ExperimentManager = import_rl_zoo3("rl_zoo3.exp_manager").ExperimentManager
    entry = _raw("ppo")[env_id]
    steps, rollout_steps = entry["n_timesteps"], entry["n_envs"] * entry["n_steps"]
    assert steps % rollout_steps == 0
    # stable-baselines3's progress after PPO's last rollout, through rl-zoo3's schedule.
    schedule = ExperimentManager._preprocess_schedules(dict(entry))["learning_rate"]
    done = rollout_steps * math.ceil(steps / rollout_steps)
    assert schedule(1.0 - done / steps) == 0.0
    assert schedule(1.0) == float(entry["learning_rate"].split("_")[1])


@NEEDS_RL_ZOO3
@pytest.mark.parametrize(("algo", "env_id"), PAIRS)
def test_rl_zoo3_builds_the_model_with_exactly_the_files_settings(algo, env_id, tmp_path):
    ExperimentManager = import_rl_zoo3("rl_zoo3.exp_manager").ExperimentManager
    raw = _raw(algo)[env_id]
    with as_file(config_file(algo)) as conf:
        manager = ExperimentManager(argparse.Namespace(), algo, env_id, str(tmp_path),
                                    config=str(conf), seed=0, eval_freq=-1, device="cpu",
                                    verbose=0)
        model, saved = manager.setup_experiment()
    try:
        assert dict(saved) == raw
        assert manager.n_timesteps == raw["n_timesteps"] and not manager.normalize
        assert model.n_envs == raw["n_envs"]
        assert model.get_env().get_attr("spec")[0].id == env_id
        if "frame_stack" in raw:  # rl-zoo3 stacks the observations: the policy sees them all
            from stable_baselines3.common.vec_env import VecFrameStack

            assert isinstance(model.get_env(), VecFrameStack)
            single = gym.spec(env_id).make().observation_space.shape[0]
            assert model.observation_space.shape == (raw["frame_stack"] * single,)
        assert model.policy_class is model.policy_aliases[raw["policy"]]
        assert model.policy.net_arch == eval(raw["policy_kwargs"])["net_arch"]
        for key in set(raw) - ZOO_KEYS:  # the rest goes to the algorithm as it stands
            value = getattr(model, key)
            assert (value.frequency if key == "train_freq" else value) == raw[key], key
        lr = raw["learning_rate"]
        if isinstance(lr, str):  # "lin_<start>": linear from start down to 0
            start = float(lr.split("_")[1])
            assert model.lr_schedule(1.0) == start and model.lr_schedule(0.25) == 0.25 * start
        else:
            assert model.lr_schedule(1.0) == model.lr_schedule(0.25) == lr
        if "clip_range" in raw:
            assert model.clip_range(0.5) == raw["clip_range"]
        if "noise_type" in raw:
            kinds = {"normal": "NormalActionNoise",
                     "ornstein-uhlenbeck": "OrnsteinUhlenbeckActionNoise"}
            assert type(model.action_noise).__name__ == kinds[raw["noise_type"]]
            np.testing.assert_array_equal(model.action_noise._sigma, [raw["noise_std"]])
        else:
            assert getattr(model, "action_noise", None) is None
    finally:
        model.get_env().close()


@NEEDS_RL_ZOO3
def test_python_m_rl_zoo3_train_uses_the_shipped_file(tmp_path):
    """The documented command, in a subprocess: rl-zoo3 reads the file from the package,
    saves it as the run's config.yml, and saves a TD3 model with its settings that acts; and
    rl-zoo3's enjoy replays the run with the episode roller_gym's rollout gives."""
    from stable_baselines3 import TD3

    algo, env_id, env_name = "td3", "roller_gym/RollerHold-v2", "roller_gym-RollerHold-v2"
    with as_file(config_file(algo)) as conf:
        subprocess.run(
            [sys.executable, "-m", "rl_zoo3.train", "--algo", algo, "--env", env_id,
             "--gym-packages", "roller_gym", "-conf", str(conf), "-n", "300", "--seed", "0",
             "--eval-freq", "-1", "--device", "cpu", "--num-threads", "1", "--verbose", "0",
             "--log-folder", str(tmp_path)],
            check=True, capture_output=True, cwd=tmp_path, timeout=600,
        )
    run_dir = tmp_path / algo / f"{env_name}_1"
    with (run_dir / env_name / "config.yml").open() as f:
        saved = yaml.load(f, Loader=yaml.UnsafeLoader)  # rl-zoo3 saves an OrderedDict
    assert dict(saved) == _raw(algo)[env_id]

    model = TD3.load(run_dir / f"{env_name}.zip", device="cpu")
    assert model.num_timesteps == 300
    assert (model.batch_size, model.learning_starts, model.gamma) == (256, 1000, 0.99)
    assert model.policy.net_arch == [64, 64]
    np.testing.assert_array_equal(model.action_noise._sigma, [0.1])
    env = gym.make(env_id)
    action, _ = model.predict(env.reset(seed=0)[0], deterministic=True)
    assert action.shape == (1,) and np.all(np.abs(action) <= 1.0)
    episode = rollout(env, model, seed=0)
    assert len(episode.torque) > 0 and np.all(np.isfinite(episode.torque))
    # rl-zoo3's own replay of the run (its enjoy script, seed 0): the same episode
    enjoyed = subprocess.run(
        [sys.executable, "-m", "rl_zoo3.enjoy", "--algo", algo, "--env", env_id,
         "--gym-packages", "roller_gym", "-f", str(tmp_path), "--exp-id", "1", "--no-render",
         "--deterministic", "--device", "cpu", "-n", str(len(episode.torque))],
        check=True, capture_output=True, text=True, cwd=tmp_path, timeout=600,
    ).stdout
    assert f"Episode Reward: {episode.total_return:.2f}" in enjoyed, enjoyed
    assert f"Episode Length {len(episode.torque)}" in enjoyed, enjoyed
