"""Other RL clients on the environments, as their users would wrap them: TorchRL (single
and vector, with its own spec checker), skrl (``wrap_env``), CleanRL's way of making and
reading its environments, and multiprocessing clients (SB3's ``SubprocVecEnv``, Gymnasium's
``AsyncVectorEnv``) from a script that does not import roller-gym at module level. The
autoreset mode each client is given is :data:`roller_gym.clients.CLIENTS`'s. Skipped without
the ``interop`` extra."""

from __future__ import annotations

import subprocess
import sys
import textwrap
import warnings

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from gymnasium.vector import AutoresetMode
from roller_gym.clients import CLIENTS, importing_id

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


@pytest.mark.parametrize("mode", [CLIENTS["torchrl"].autoreset_mode, AutoresetMode.SAME_STEP])
def test_torchrl_wraps_the_native_vector_env_in_its_advised_mode(mode):
    """TorchRL in the advised mode (disabled: it resets the ended ones by reset_mask) and in
    same_step: every sub-environment ends twice in 12 steps of 5-step episodes, and the step
    after an end starts a new episode (its observation is not the last one's)."""
    vec = gym.make_vec(IDS[0], num_envs=4, autoreset_mode=mode, max_episode_steps=5)
    env = torchrl_envs.GymWrapper(vec)
    check_env_specs(env)
    td = env.rollout(12, break_when_any_done=False)
    assert td["next", "reward"].shape == (4, 12, 1)
    ends = td["next", "truncated"][..., 0]
    assert ends.sum() == 8 and ends[:, [4, 9]].all()
    last, first = td["next", "observation"][:, 4], td["observation"][:, 5]
    assert not torch.isclose(last, first).all(dim=-1).any()


def test_torchrl_refuses_next_step_so_its_mode_is_not_miscounted():
    with pytest.raises(RuntimeError, match="SAME_STEP or DISABLED"):
        torchrl_envs.GymWrapper(gym.make_vec(IDS[0], num_envs=2))


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


def test_skrl_is_warned_about_next_step_and_not_about_its_advised_mode():
    advised = CLIENTS["skrl"].autoreset_mode
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        skrl_wrappers.wrap_env(gym.make_vec(IDS[0], num_envs=2, autoreset_mode=advised)).reset()
        gym.make_vec(IDS[0], num_envs=2).reset(seed=0)  # next_step, not reset by skrl
    with pytest.warns(UserWarning, match="skrl .*autoreset_mode='next_step'.*'same_step'"):
        skrl_wrappers.wrap_env(gym.make_vec(IDS[0], num_envs=2)).reset()


# -- clients that make the environments from an ID string, in processes of their own -------

MULTIPROCESSING_SCRIPT = '''
import multiprocessing
import sys

import gymnasium as gym
import numpy as np
from stable_baselines3.common.vec_env import SubprocVecEnv

ID = {env_id!r}


def make_env():
    # in a child: nothing has imported roller-gym; the ID's module part does
    assert multiprocessing.parent_process() is None or "roller_gym" not in sys.modules
    return gym.make(ID, integrator="euler")


def play(vec_reset, vec_step, actions):
    obs = [vec_reset()]
    for a in actions:
        obs.append(vec_step(a)[0])
    return np.array(obs)


if __name__ == "__main__":
    actions = np.linspace(-1, 1, 8, dtype=np.float32).reshape(4, 2, 1)
    sb3 = SubprocVecEnv([make_env, make_env], start_method="forkserver")
    sb3.seed(7)
    sb3_obs = play(sb3.reset, sb3.step, actions)
    sb3.close()
    agym = gym.vector.AsyncVectorEnv([make_env, make_env], context="forkserver")
    gym_obs = play(lambda: agym.reset(seed=7)[0], agym.step, actions)
    agym.close()
    assert "roller_gym" in sys.modules  # made in this process too: the ID imported it
    singles = [make_env() for _ in range(2)]
    reference = np.array([[env.reset(seed=7 + i)[0] for i, env in enumerate(singles)]]
                         + [[env.step(a[i])[0] for i, env in enumerate(singles)]
                            for a in actions])
    np.testing.assert_array_equal(sb3_obs, reference)
    np.testing.assert_array_equal(gym_obs, reference)
    print("ok", reference.shape)
'''


def test_subproc_and_async_vector_envs_from_a_script_without_a_module_level_import(tmp_path):
    """SB3's SubprocVecEnv and Gymnasium's AsyncVectorEnv (forkserver children, which import
    only what the script imports at module level) make the environments from the
    ``roller_gym:`` form of the ID, with no ``import roller_gym`` anywhere, and their
    observations are those of single environments stepped in the script's own process."""
    pytest.importorskip("stable_baselines3")
    script = tmp_path / "train.py"
    script.write_text(textwrap.dedent(MULTIPROCESSING_SCRIPT).format(
        env_id=importing_id(IDS[0])))
    result = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                            cwd=tmp_path, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    assert result.stdout.split() == ["ok", "(5,", "2,", "5)"]


def test_cleanrl_style_sync_vector_env_reports_every_episode_in_final_info():
    """CleanRL's way (its continuous-action scripts): SyncVectorEnv of single environments
    made from ``--env-id`` with RecordEpisodeStatistics, in its advised mode, reading episode
    returns from ``info["final_info"]``: they equal the returns of the same seeded episodes
    played directly."""
    mode = CLIENTS["cleanrl"].autoreset_mode
    env_id = importing_id(IDS[0])

    def make_env():
        return gym.wrappers.RecordEpisodeStatistics(gym.make(env_id, max_episode_steps=6))

    envs = gym.vector.SyncVectorEnv([make_env, make_env], autoreset_mode=mode)
    envs.reset(seed=3)
    action = np.full((2, 1), 0.3, np.float32)
    returns = []
    for _ in range(12):
        _, _, _, _, infos = envs.step(action)
        if "final_info" in infos:
            over = np.nonzero(infos["final_info"]["_episode"])[0]
            returns += list(infos["final_info"]["episode"]["r"][over])
    expected = []
    for i in range(2):
        env = gym.make(IDS[0], max_episode_steps=6)
        env.reset(seed=3 + i)
        for _ in range(2):  # each sub-environment plays two episodes of 6 steps
            total, done = 0.0, False
            while not done:
                _, r, te, tr, _ = env.step(action[i])
                total, done = total + r, te or tr
            expected.append(total)
            env.reset()
    assert sorted(returns) == pytest.approx(sorted(expected), rel=1e-6)


@pytest.mark.parametrize("mode", [CLIENTS["skrl"].autoreset_mode, AutoresetMode.NEXT_STEP])
def test_skrl_counts_episode_lengths_right_only_in_its_advised_mode(mode):
    """Episodes of 5 steps, as skrl's wrapper reports them (the steps between one
    ``terminated | truncated`` and the next): 5 in the advised mode; under next_step skrl
    counts the reset step, whose observation starts the next episode, as a step of it (6),
    which is why roller-gym warns there."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        wrapped = skrl_wrappers.wrap_env(gym.make_vec(IDS[0], num_envs=3, autoreset_mode=mode,
                                                      max_episode_steps=5))
        wrapped.reset()
    ends = []
    for _ in range(12):
        _, _, terminated, truncated, _ = wrapped.step(torch.zeros(3, 1))
        ends.append((terminated | truncated)[:, 0].numpy())
        wrapped.reset()
    ends = np.array(ends)
    lengths = {int(d) for env in ends.T for d in np.diff(np.flatnonzero(env), prepend=-1)}
    assert lengths == ({5} if mode == CLIENTS["skrl"].autoreset_mode else {5, 6})
