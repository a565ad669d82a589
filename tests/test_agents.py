"""The sample agents: observation decoding, the classical controllers, short training runs
(rl-zoo3, through ``roller-gym train``), saving and loading. The commands end to end are in
test_cli.py; the hyperparameter files in test_zoo.py."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import torch
from roller_gym.agents import LQR, EnergySwingUp, baseline, decode_observation, load_policy, rollout
from roller_gym.agents.hyperparams import ALGOS, CLASSICAL, hyperparams
from roller_gym.agents.policies import read_config
from roller_gym.physics import Scene, holding_torque
from zoo import HAVE_RL_ZOO3, import_rl_zoo3

torch.set_num_threads(1)


def _wrapped_difference(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + np.pi) % (2 * np.pi) - np.pi)


# -- observation decoding --------------------------------------------------------------
@pytest.mark.parametrize(("env_id", "scene"), [
    ("roller_gym/RollerStabilize-v2", None),
    ("roller_gym/RollerHold-v2", None),
    ("roller_gym/RollerBalance-v2", None),
    ("roller_gym/RollerSwing-v1", "drum"),
    ("roller_gym/RollerHold-v2", "solid_disc"),
])
def test_decode_recovers_the_state_the_env_reports(env_id, scene):
    kwargs = {} if scene is None else {"scene": scene}
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(0)
    checked = 0
    for seed in range(5):
        obs, info = env.reset(seed=seed)
        for _ in range(60):
            s = decode_observation(obs, env.unwrapped.scene, env.unwrapped.task)
            assert s.phi[0] == pytest.approx(info["phi"], abs=1e-5)
            assert s.phi_dot[0] == pytest.approx(info["phi_dot"], rel=1e-5, abs=1e-5)
            if env.unwrapped.task.observes_target:
                assert s.target_phi[0] == pytest.approx(info["target_phi"], abs=1e-5)
            else:
                assert s.target_phi is None
            checked += 1
            obs, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 1))
            if terminated or truncated:
                break
    assert checked > 100


def test_decode_picks_the_turn_beyond_one_revolution_of_phi():
    """With R = 10 r, ψ = φ/9: φ = 4 rad and φ = 4 − 2π share cos φ and sin φ, and only
    (cos ψ, sin ψ) tells them apart; φ = 7.5 and −8 rad lie beyond one turn of φ."""
    env = gym.make("roller_gym/RollerStabilize-v2", scene=Scene(R=1.0))
    for phi in (4.0, 4.0 - 2 * np.pi, -3.9, 7.5, -8.0):
        obs, _ = env.reset(options={"state": (phi, -2.0)})
        s = decode_observation(obs, env.unwrapped.scene, env.unwrapped.task)
        assert s.phi[0] == pytest.approx(phi, abs=1e-5)
        assert s.phi_dot[0] == pytest.approx(-2.0, rel=1e-5)


def test_decode_on_the_floor_gives_phi_modulo_one_turn():
    env = gym.make("roller_gym/RollerStabilize-v2", scene="floor")
    obs, _ = env.reset(options={"state": (5.0, 0.5)})
    s = decode_observation(obs, env.unwrapped.scene, env.unwrapped.task)
    assert _wrapped_difference(s.phi[0], 5.0) < 1e-5
    assert -np.pi <= s.phi[0] < np.pi


def test_decode_takes_batches_and_rejects_wrong_shapes():
    env = gym.make("roller_gym/RollerHold-v2")
    observations = np.stack([env.reset(seed=s)[0] for s in range(4)])
    batch = decode_observation(observations, env.unwrapped.scene, env.unwrapped.task)
    single = [decode_observation(o, env.unwrapped.scene, env.unwrapped.task) for o in observations]
    np.testing.assert_allclose(batch.phi, [s.phi[0] for s in single])
    np.testing.assert_allclose(batch.target_phi, [s.target_phi[0] for s in single])
    with pytest.raises(ValueError, match="shape"):
        decode_observation(np.zeros(7), env.unwrapped.scene, env.unwrapped.task)


# -- the classical controllers -------------------------------------------------------------
@pytest.mark.parametrize("env_id", ["roller_gym/RollerStabilize-v2", "roller_gym/RollerHold-v2"])
def test_lqr_succeeds_in_all_100_seeded_episodes(env_id):
    env = gym.make(env_id)
    policy = LQR.from_env(env, **CLASSICAL[env_id])
    failures = []
    for seed in range(100):
        episode = rollout(env, policy, seed)
        if not episode.success or episode.terminated:
            failures.append(seed)
    assert failures == []


def test_lqr_predict_is_shaped_like_a_stable_baselines3_model():
    env = gym.make("roller_gym/RollerHold-v2")
    policy = LQR.from_env(env)
    observations = np.stack([env.reset(seed=s)[0] for s in range(6)])
    actions, state = policy.predict(observations, deterministic=True)
    assert state is None
    assert actions.shape == (6, 1) and actions.dtype == np.float32
    assert np.all(np.abs(actions) <= 1.0)
    for obs, action in zip(observations, actions, strict=True):
        single, _ = policy.predict(obs)
        assert single.shape == (1,)
        np.testing.assert_allclose(single, action, rtol=1e-6)


def test_lqr_holds_the_target_with_the_holding_torque_and_pushes_back_when_off_it():
    env = gym.make("roller_gym/RollerHold-v2")
    policy = LQR.from_env(env)
    max_torque = env.unwrapped.task.max_torque
    obs, info = env.reset(seed=3)
    target = info["target_phi"]
    tau_star = float(holding_torque(env.unwrapped.scene, target))
    assert abs(tau_star) > 0.1 * max_torque  # a target up the wall, not at the bottom
    obs, _ = env.reset(seed=3, options={"state": (target, 0.0)})
    action, _ = policy.predict(obs)
    assert action[0] * max_torque == pytest.approx(tau_star, abs=1e-4)
    obs, _ = env.reset(seed=3, options={"state": (target + 0.05, 0.0)})
    assert policy.predict(obs)[0][0] * max_torque < tau_star - 1e-3  # restoring
    # The gains are computed once per target.
    assert list(policy._cache) == [pytest.approx(target, abs=policy.gain_resolution)]


@pytest.mark.parametrize("scene", [Scene(m=1e80, R=0.5, e=0.04),
                                   Scene(r=1e40, R=float("inf"), e=4e39, k=1e40)])
def test_lqr_says_which_scene_it_has_no_gains_for(scene):
    """Scenes where the torque has next to no effect (B ~ 1e-79 per N·m) ended in scipy's
    LinAlgError from the Riccati solver; the LQR now names the scene and its linearization."""
    from roller_gym.stabilize import StabilizeTask

    lqr = LQR(StabilizeTask(), scene, max_torque=1.0, dt=0.05)
    with pytest.raises(ValueError, match=r"LQR: no gains for Scene\(.*about phi\*=0 rad with "
                                         r"dt=0\.05 s \(scipy: .*B = "):
        lqr.gains(0.0)
    assert LQR(StabilizeTask(), Scene(), max_torque=1.0, dt=0.05).gains(0.0)[1].shape == (1, 2)


def test_energy_swing_up_balances_in_every_episode():
    env = gym.make("roller_gym/RollerBalance-v2")
    policy = EnergySwingUp.from_env(env, **CLASSICAL["roller_gym/RollerBalance-v2"])
    episodes = [rollout(env, policy, seed) for seed in range(20)]
    assert all(e.success and not e.terminated for e in episodes)
    # It does swing: the torque limit is below the largest holding torque on the way up.
    assert max(np.abs(e.phi).max() for e in episodes) > 3.5


def test_baselines_by_name():
    env = gym.make("roller_gym/RollerBalance-v2")
    assert isinstance(baseline("classical", env), EnergySwingUp)
    obs, _ = env.reset(seed=0)
    assert np.all(baseline("zero", env).predict(obs)[0] == 0)
    a1 = baseline("random", env, seed=1).predict(np.stack([obs] * 50))[0]
    a2 = baseline("random", env, seed=1).predict(np.stack([obs] * 50))[0]
    np.testing.assert_array_equal(a1, a2)
    assert a1.std() > 0.3
    with pytest.raises(ValueError, match="not one of"):
        baseline("pid", env)


# -- training (rl-zoo3 through roller-gym train), saving, loading ---------------------------
_RUNS: dict[str, tuple] = {}


def _train(argv: list[str]) -> Path:
    if not HAVE_RL_ZOO3:
        pytest.skip("training runs rl-zoo3, not installed (the zoo extra; CI installs it)")
    import_rl_zoo3("rl_zoo3.train")  # before roller-gym train imports it: see tests/zoo.py
    from roller_gym.scripts import train

    return train.main([*argv, "--verbose", "0"])


def _short_run(algo: str, tmp_path_factory) -> tuple:
    """(algo, experiment folder, log folder) of a short training run (2,000 steps), made once."""
    if algo not in _RUNS:
        log_folder = tmp_path_factory.mktemp(algo) / "runs"
        run_dir = _train([
            "--algo", algo, "--env", "roller_gym/RollerStabilize-v2", "--steps", "2000",
            "--log-folder", str(log_folder), "--eval-freq", "1000", "--eval-episodes", "2",
            "--checkpoints", "1",
        ])
        _RUNS[algo] = (algo, run_dir, log_folder)
    return _RUNS[algo]


@pytest.fixture(params=ALGOS)
def short_run(request, tmp_path_factory):
    return _short_run(request.param, tmp_path_factory)


def test_short_training_run_completes_and_saves_with_our_hyperparameters(short_run):
    algo, run_dir, log_folder = short_run
    env_id = "roller_gym/RollerStabilize-v2"
    # rl-zoo3's layout: <log folder>/<algo>/<env name>_1, no colon, no nested folder per task
    assert run_dir.parent == log_folder / algo and run_dir.name == "roller_gym-RollerStabilize-v2_1"
    config = read_config(run_dir)
    assert config["algo"] == algo and config["env"] == env_id and config["seed"] == 0
    assert config["trained_steps"] >= 2000 and config["wall_time_s"] > 0
    # The configuration rl-zoo3 saved is the hyperparameter file's entry, as written.
    assert dict(config["hyperparams"]) == hyperparams(algo, env_id)
    for name in ("best_model.zip", "evaluations.npz", Path(config["model"]).name):
        assert (run_dir / name).is_file(), name
    assert list(run_dir.glob("rl_model_*_steps.zip"))
    assert list((log_folder / "tensorboard").rglob("events.out.tfevents.*"))
    assert len(np.load(run_dir / "evaluations.npz")["timesteps"]) >= 2


def test_saved_model_loads_as_rl_zoo3_loads_it(short_run):
    """load_policy against rl-zoo3's own way (its enjoy script's): the latest experiment's
    final model, found by get_model_path and loaded by the algorithm's class."""
    from huggingface_sb3 import EnvironmentName

    algo, run_dir, log_folder = short_run
    zoo_utils = import_rl_zoo3("rl_zoo3.utils")
    ZOO_ALGOS, get_model_path = zoo_utils.ALGOS, zoo_utils.get_model_path
    env_id = "roller_gym/RollerStabilize-v2"
    _, model_path, log_path = get_model_path(0, str(log_folder), algo, EnvironmentName(env_id))
    assert Path(log_path) == run_dir
    reference = ZOO_ALGOS[algo].load(model_path, device="cpu")
    loaded = load_policy(run_dir)
    assert loaded.model.num_timesteps == reference.num_timesteps >= 2000
    env = gym.make(env_id)
    observations = np.stack([env.reset(seed=s)[0] for s in range(50)])
    expected, _ = reference.predict(observations, deterministic=True)
    np.testing.assert_array_equal(loaded.predict(observations, deterministic=True)[0], expected)
    assert rollout(env, loaded, 7).total_return == rollout(env, reference, 7).total_return
    # best=True takes the best periodic evaluation's model instead.
    best = ZOO_ALGOS[algo].load(run_dir / "best_model.zip", device="cpu")
    np.testing.assert_array_equal(load_policy(run_dir, best=True).predict(observations)[0],
                                  best.predict(observations, deterministic=True)[0])


def test_loading_a_run_leaves_gymnasium_unpatched(short_run):
    """Importing rl_zoo3 replaces Gymnasium's TimeLimit (see tests/zoo.py); reading a run
    must not do that to the caller's process."""
    _, run_dir, _ = short_run
    code = ("import sys, gymnasium as gym\n"
            "from roller_gym.agents import load_policy, rollout\n"
            f"policy = load_policy({str(run_dir)!r}, best=True)\n"
            "env = gym.make('roller_gym/RollerStabilize-v2')\n"
            "rollout(env, policy, 0)\n"
            "print('rl_zoo3' in sys.modules, type(env).__module__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=300).stdout.split()
    assert out == ["False", "gymnasium.wrappers.common"]


def test_normalized_ppo_run_saves_its_statistics_and_reloads_them(tmp_path):
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    run_dir = _train([
        "--algo", "ppo", "--steps", "1000", "--log-folder", str(tmp_path),
        "--eval-episodes", "1", "--checkpoints", "0",
        "--hyperparams", "n_envs:2", "n_steps:512", "normalize:dict(norm_obs=True)",
    ])
    config = read_config(run_dir)
    stats = Path(config["params_dir"]) / "vecnormalize.pkl"
    assert stats.is_file()
    # PPO trains whole rollouts (2 x 512): 1,000 steps become 1,024, and the linear learning
    # rate schedule ends at exactly 0, not below.
    import_rl_zoo3("rl_zoo3.utils")  # unpickling rl-zoo3's schedule imports it: tests/zoo.py
    model = PPO.load(config["model"], device="cpu")
    assert model.num_timesteps == 1024
    assert model._current_progress_remaining == 0.0 and model.lr_schedule(0.0) == 0.0
    env = gym.make("roller_gym/RollerStabilize-v2")
    normalizer = VecNormalize.load(str(stats), DummyVecEnv([lambda: env]))
    observations = np.stack([env.reset(seed=s)[0] for s in range(20)])
    normalized = normalizer.normalize_obs(observations)
    assert not np.allclose(normalized, observations)
    expected, _ = model.predict(normalized, deterministic=True)
    np.testing.assert_array_equal(load_policy(run_dir).predict(observations)[0], expected)
