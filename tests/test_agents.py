"""The sample agents: observation decoding, the classical controllers, short training runs,
saving and loading, and the scripts end to end."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
import torch
from roller_gym.agents import LQR, EnergySwingUp, baseline, decode_observation, load_policy, rollout
from roller_gym.agents.hyperparams import ALGOS, CLASSICAL, HYPERPARAMS, TASKS, Linear
from roller_gym.physics import holding_torque

ROOT = Path(__file__).resolve().parents[1]
torch.set_num_threads(1)


def _load_script(name: str):
    path = ROOT / "scripts" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_script_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _wrapped_difference(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + np.pi) % (2 * np.pi) - np.pi)


# -- observation decoding --------------------------------------------------------------
@pytest.mark.parametrize(("env_id", "scene"), [
    ("roller_gym/RollerStabilize-v0", None),
    ("roller_gym/RollerHold-v0", None),
    ("roller_gym/RollerBalance-v0", None),
    ("roller_gym/RollerStabilize-v0", "drum"),
    ("roller_gym/RollerHold-v0", "solid_disc"),
])
def test_decode_recovers_the_state_the_env_reports(env_id, scene):
    kwargs = {} if scene is None else {"scene": scene}
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(0)
    checked = 0
    for seed in range(5):
        obs, info = env.reset(seed=seed)
        for _ in range(60):
            s = decode_observation(obs, env.unwrapped.scene)
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
    """In the paper's scene ψ = φ/4: φ = 4 rad and φ = 4 − 2π share cos φ and sin φ, and only
    (cos ψ, sin ψ) tells them apart."""
    env = gym.make("roller_gym/RollerStabilize-v0")
    for phi in (4.0, 4.0 - 2 * np.pi, -3.9, 7.5):
        obs, _ = env.reset(options={"state": (phi, -2.0)})
        s = decode_observation(obs, env.unwrapped.scene)
        assert s.phi[0] == pytest.approx(phi, abs=1e-5)
        assert s.phi_dot[0] == pytest.approx(-2.0, rel=1e-5)


def test_decode_on_the_floor_gives_phi_modulo_one_turn():
    env = gym.make("roller_gym/RollerStabilize-v0", scene="floor")
    obs, _ = env.reset(options={"state": (5.0, 0.5)})
    s = decode_observation(obs, env.unwrapped.scene)
    assert _wrapped_difference(s.phi[0], 5.0) < 1e-5
    assert -np.pi <= s.phi[0] < np.pi


def test_decode_takes_batches_and_rejects_wrong_shapes():
    env = gym.make("roller_gym/RollerHold-v0")
    observations = np.stack([env.reset(seed=s)[0] for s in range(4)])
    batch = decode_observation(observations, env.unwrapped.scene)
    single = [decode_observation(o, env.unwrapped.scene) for o in observations]
    np.testing.assert_allclose(batch.phi, [s.phi[0] for s in single])
    np.testing.assert_allclose(batch.target_phi, [s.target_phi[0] for s in single])
    with pytest.raises(ValueError, match="shape"):
        decode_observation(np.zeros(7), env.unwrapped.scene)


# -- the classical controllers -------------------------------------------------------------
@pytest.mark.parametrize("env_id", ["roller_gym/RollerStabilize-v0", "roller_gym/RollerHold-v0"])
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
    env = gym.make("roller_gym/RollerHold-v0")
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
    env = gym.make("roller_gym/RollerHold-v0")
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
    assert list(policy._cache) == [pytest.approx(target, abs=1e-6)]


def test_energy_swing_up_balances_in_every_episode():
    env = gym.make("roller_gym/RollerBalance-v0")
    policy = EnergySwingUp.from_env(env, **CLASSICAL["roller_gym/RollerBalance-v0"])
    episodes = [rollout(env, policy, seed) for seed in range(20)]
    assert all(e.success and not e.terminated for e in episodes)
    # It does swing: the torque limit is below the largest holding torque on the way up.
    assert max(np.abs(e.phi).max() for e in episodes) > 3.5


def test_baselines_by_name():
    env = gym.make("roller_gym/RollerBalance-v0")
    assert isinstance(baseline("classical", env), EnergySwingUp)
    obs, _ = env.reset(seed=0)
    assert np.all(baseline("zero", env).predict(obs)[0] == 0)
    a1 = baseline("random", env, seed=1).predict(np.stack([obs] * 50))[0]
    a2 = baseline("random", env, seed=1).predict(np.stack([obs] * 50))[0]
    np.testing.assert_array_equal(a1, a2)
    assert a1.std() > 0.3
    with pytest.raises(ValueError, match="not one of"):
        baseline("pid", env)


def test_linear_schedule_decays_to_zero_and_never_below():
    schedule = Linear(1e-3)
    assert schedule(1.0) == 1e-3 and schedule(0.5) == pytest.approx(5e-4)
    # PPO's last rollout overshoots the requested steps: progress goes slightly negative.
    assert schedule(0.0) == 0.0 == schedule(-0.01)


def test_hyperparameters_cover_every_algorithm_and_task():
    assert set(HYPERPARAMS) == {(a, t) for a in ALGOS for t in TASKS}
    assert set(TASKS) == set(roller_gym.ENV_IDS)
    for params in HYPERPARAMS.values():
        assert params["total_steps"] > 0 and params["n_envs"] >= 1


# -- training, saving, loading -------------------------------------------------------------
_RUNS: dict[str, tuple] = {}


def _short_run(algo: str, tmp_path_factory) -> tuple:
    """(algo, run directory, model) of a short training run (2,000 steps), made once."""
    if algo not in _RUNS:
        run_dir = tmp_path_factory.mktemp(algo) / "run"
        run_dir, model = _load_script("train").main([
            "--algo", algo, "--env", "roller_gym/RollerStabilize-v0", "--steps", "2000",
            "--run-dir", str(run_dir), "--eval-freq", "1000", "--eval-episodes", "2",
            "--checkpoints", "1", "--no-progress-bar",
        ])
        _RUNS[algo] = (algo, run_dir, model)
    return _RUNS[algo]


@pytest.fixture(params=ALGOS)
def short_run(request, tmp_path_factory):
    return _short_run(request.param, tmp_path_factory)


def test_short_training_run_completes_and_saves(short_run):
    algo, run_dir, _ = short_run
    config = json.loads((run_dir / "config.json").read_text())
    assert config["algo"] == algo and config["env"] == "roller_gym/RollerStabilize-v0"
    assert config["trained_steps"] >= 2000 == config["total_steps"]
    assert config["wall_time_s"] > 0
    for name in ("model.zip", "best_model.zip", "evaluations.npz"):
        assert (run_dir / name).is_file(), name
    assert list((run_dir / "checkpoints").glob("model_*_steps.zip"))
    assert list((run_dir / "tb").iterdir())
    assert len(np.load(run_dir / "evaluations.npz")["timesteps"]) >= 2


def test_saved_model_loads_and_acts_identically(short_run):
    _, run_dir, model = short_run
    loaded = load_policy(run_dir)
    env = gym.make("roller_gym/RollerStabilize-v0")
    observations = np.stack([env.reset(seed=s)[0] for s in range(50)])
    expected, _ = model.predict(observations, deterministic=True)
    actual, _ = loaded.predict(observations, deterministic=True)
    np.testing.assert_array_equal(actual, expected)
    assert rollout(env, loaded, 7).total_return == rollout(env, model, 7).total_return


def test_normalized_run_saves_its_statistics_and_reloads_them(tmp_path, monkeypatch):
    key = ("ppo", "roller_gym/RollerStabilize-v0")
    monkeypatch.setitem(HYPERPARAMS, key, {
        **HYPERPARAMS[key], "n_envs": 2, "n_steps": 512,
        "normalize": {"norm_obs": True, "norm_reward": True},
    })
    run_dir, model = _load_script("train").main([
        "--algo", "ppo", "--steps", "1024", "--run-dir", str(tmp_path / "run"),
        "--eval-episodes", "1", "--checkpoints", "0", "--no-progress-bar",
    ])
    assert (run_dir / "vecnormalize.pkl").is_file()
    loaded = load_policy(run_dir)
    env = gym.make("roller_gym/RollerStabilize-v0")
    observations = np.stack([env.reset(seed=s)[0] for s in range(20)])
    normalized = model.get_env().normalize_obs(observations)
    assert not np.allclose(normalized, observations)
    expected, _ = model.predict(normalized, deterministic=True)
    np.testing.assert_array_equal(loaded.predict(observations)[0], expected)


# -- the scripts end to end ----------------------------------------------------------------
def test_evaluate_and_replay_scripts(tmp_path, tmp_path_factory):
    _, run_dir, _ = _short_run("sac", tmp_path_factory)
    out = tmp_path / "results"
    subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "evaluate.py"),
         "--env", "roller_gym/RollerStabilize-v0",
         "--models", str(run_dir), "--episodes", "3", "--out", str(out),
         "--report", str(tmp_path / "RESULTS.md")],
        check=True, cwd=tmp_path, capture_output=True,
    )
    table = (out / "RollerStabilize-v0.md").read_text()
    for label in ("SAC", "LQR", "zero torque", "random"):
        assert f"| {label} |" in table
    numbers = json.loads((out / "RollerStabilize-v0.json").read_text())
    lqr = next(p for p in numbers["policies"] if p["name"] == "classical")
    assert lqr["success_rate"] == 1.0 and len(lqr["returns"]) == 3
    for plot in ("learning", "trajectories"):
        assert (out / f"RollerStabilize-v0-{plot}.png").stat().st_size > 10_000
    assert "Target:" in (tmp_path / "RESULTS.md").read_text()

    gif = tmp_path / "replay.gif"
    subprocess.run([sys.executable, str(ROOT / "scripts" / "replay.py"), str(run_dir),
                    "--out", str(gif)], check=True, cwd=tmp_path, capture_output=True)
    assert gif.read_bytes()[:6] == b"GIF89a"
