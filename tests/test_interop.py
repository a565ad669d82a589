"""Other RL clients on the environments, as their users would wrap them: TorchRL (single
and vector, with its own spec checker) and skrl (``wrap_env``). Skipped without the
``interop`` extra."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from gymnasium.vector import AutoresetMode

torch = pytest.importorskip("torch", reason="the interop extra is not installed")
torchrl_envs = pytest.importorskip("torchrl.envs", reason="the interop extra is not installed")
skrl_wrappers = pytest.importorskip("skrl.envs.wrappers.torch",
                                    reason="the interop extra is not installed")
from torchrl.envs.utils import check_env_specs  # noqa: E402

IDS = list(roller_gym.ENV_IDS)


@pytest.mark.parametrize("env_id", IDS)
def test_torchrl_gym_env_passes_its_spec_check_and_reads_the_info(env_id):
    """GymEnv with the info registered automatically (every value has a dtype): the spec
    check passes, and is_success read through TorchRL agrees with the success band applied
    to the position error and speeds read alongside it."""
    env = torchrl_envs.GymEnv(env_id)
    env.auto_register_info_dict()
    check_env_specs(env)
    td = env.rollout(30, break_when_any_done=False)
    nxt = td["next"]
    assert nxt["is_success"].dtype == torch.bool and nxt["substeps"].dtype == torch.int64
    task = roller_gym.TASKS[env_id.split("/")[1].split("-v")[0]]
    inside = ((nxt["position_error"].abs() <= task.success_band)
              & ((nxt["phi_dot"] - nxt["target_phi_dot"]).abs() <= task.success_speed))
    assert torch.equal(nxt["is_success"], inside)


def test_torchrl_wraps_the_native_vector_env_in_same_step_mode():
    vec = gym.make_vec(IDS[0], num_envs=4, autoreset_mode=AutoresetMode.SAME_STEP,
                       max_episode_steps=5)
    env = torchrl_envs.GymWrapper(vec)
    check_env_specs(env)
    td = env.rollout(12, break_when_any_done=False)
    assert td["next", "reward"].shape == (4, 12, 1)
    assert td["next", "truncated"].sum() == 8  # every sub-environment ends twice


def skrl_seed() -> int:
    """The seed skrl's wrappers pass to the first ``reset`` (its global random key)."""
    from skrl import config

    return int(config.torch.key)


def test_skrl_wraps_the_single_environment():
    """skrl's wrapper steps the environment as it is: the same observations and rewards as
    a twin stepped directly, reset with the seed skrl uses."""
    env, twin = gym.make(IDS[1]), gym.make(IDS[1])
    wrapped = skrl_wrappers.wrap_env(env)
    obs, _ = wrapped.reset()
    np.testing.assert_allclose(obs.numpy()[0], twin.reset(seed=skrl_seed())[0])
    for a in np.linspace(-1, 1, 7):
        obs, reward, terminated, truncated, _ = wrapped.step(torch.tensor([[a]]))
        o, r, te, tr, _ = twin.step(np.array([a], np.float32))
        np.testing.assert_allclose(obs.numpy()[0], o)
        assert reward.item() == pytest.approx(r, rel=1e-6)
        assert bool(terminated.item()) == te and bool(truncated.item()) == tr


def test_skrl_wraps_the_native_vector_environment():
    vec, twin = (gym.make_vec(IDS[0], num_envs=3, autoreset_mode=AutoresetMode.SAME_STEP)
                 for _ in range(2))
    wrapped = skrl_wrappers.wrap_env(vec)
    assert wrapped.num_envs == 3
    obs, _ = wrapped.reset()
    np.testing.assert_allclose(obs.numpy(), twin.reset(seed=skrl_seed())[0])
    actions = np.random.default_rng(0).uniform(-1, 1, (5, 3, 1)).astype(np.float32)
    for a in actions:
        obs, reward, _, _, _ = wrapped.step(torch.from_numpy(a))
        o, r, _, _, _ = twin.step(a)
        np.testing.assert_allclose(obs.numpy(), o)
        np.testing.assert_allclose(reward.numpy()[:, 0], r, rtol=1e-6)
