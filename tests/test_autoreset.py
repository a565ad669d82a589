"""The native vector environment against Gymnasium's own ``SyncVectorEnv`` over single
environments: an independent implementation of seeding, autoreset (all three modes), info
batching and reset masks. Also the episode core's random streams and failure rule.
"""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from gymnasium.vector import AutoresetMode, SyncVectorEnv
from roller_gym import episode
from roller_gym.physics import preset
from scipy import stats

IDS = list(roller_gym.ENV_IDS)
MODES = [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP, AutoresetMode.DISABLED]


def make_pair(env_id: str, n: int, mode: AutoresetMode, steps: int, **kwargs):
    native = gym.make_vec(env_id, num_envs=n, autoreset_mode=mode, max_episode_steps=steps,
                          **kwargs)
    sync = SyncVectorEnv([lambda: gym.make(env_id, max_episode_steps=steps, **kwargs)] * n,
                         autoreset_mode=mode)
    return native, sync


def assert_infos_equal(native: dict, sync: dict) -> None:
    """Every key Gymnasium's SyncVectorEnv reports, with its mask, in the native info (but
    ``TimeLimit.truncated``, which rl-zoo3 adds to Gymnasium's TimeLimit once it is imported
    in the process, by patching it: ``rl_zoo3.gym_patches``)."""
    for key, value in sync.items():
        if key.lstrip("_") == "TimeLimit.truncated":
            continue
        assert key in native, key
        if key in ("final_obs",):
            for a, b in zip(native[key], value, strict=True):
                assert (a is None) == (b is None)
                if b is not None:
                    np.testing.assert_array_equal(a, b)
        elif isinstance(value, dict):
            assert_infos_equal(native[key], value)
            for k, v in native[key].items():  # elsewhere 0 or False, as Sync's (or None)
                if not k.startswith("_"):
                    assert not np.asarray(v)[~native[key][f"_{k}"]].any(), k
        elif key.startswith("_"):
            np.testing.assert_array_equal(native[key], value, err_msg=key)
        else:
            mask = sync[f"_{key}"]
            got, want = np.asarray(native[key])[mask], np.asarray(value)[mask]
            if want.dtype.kind in "biuO":
                np.testing.assert_array_equal(got.astype(want.dtype), want, err_msg=key)
            else:
                np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12, err_msg=key)


@pytest.mark.parametrize("mode", MODES, ids=lambda m: m.value)
@pytest.mark.parametrize("env_id", IDS)
def test_matches_sync_vector_env_in_every_autoreset_mode(env_id, mode):
    """Seeds s + i, random actions, episodes of 5 steps, over 13 steps (two autoresets);
    in DISABLED mode the ended sub-environments are reset by mask, as Gymnasium documents."""
    n = 3
    native, sync = make_pair(env_id, n, mode, 5)
    assert native.metadata["autoreset_mode"] == mode == native.unwrapped.autoreset_mode
    obs_n, info_n = native.reset(seed=7)
    obs_s, info_s = sync.reset(seed=7)
    np.testing.assert_array_equal(obs_n, obs_s)
    assert_infos_equal(info_n, info_s)
    actions = np.random.default_rng(3).uniform(-1, 1, (13, n, 1)).astype(np.float32)
    ended_any = False
    for a in actions:
        out_n, out_s = native.step(a), sync.step(a)
        np.testing.assert_array_equal(out_n[0], out_s[0])
        np.testing.assert_allclose(out_n[1], out_s[1], rtol=1e-12, atol=1e-15)
        np.testing.assert_array_equal(out_n[2], out_s[2])
        np.testing.assert_array_equal(out_n[3], out_s[3])
        assert_infos_equal(out_n[4], out_s[4])
        done = out_s[2] | out_s[3]
        ended_any |= bool(done.any())
        if mode == AutoresetMode.DISABLED and done.any():
            obs_n, info_n = native.reset(options={"reset_mask": done})
            obs_s, info_s = sync.reset(options={"reset_mask": done})
            np.testing.assert_array_equal(obs_n, obs_s)
            assert_infos_equal(info_n, info_s)
            np.testing.assert_array_equal(info_n["_phi"], done)  # only the reset ones
    assert ended_any


def test_same_step_mode_reports_the_final_observation_and_info():
    vec = gym.make_vec(IDS[0], num_envs=2, autoreset_mode="same_step", max_episode_steps=2)
    vec.reset(seed=0)
    vec.step(np.zeros((2, 1), np.float32))
    obs, _, _, truncated, info = vec.step(np.zeros((2, 1), np.float32))
    assert truncated.all() and info["_final_obs"].all()
    for i in range(2):  # the final observation is the state the final info describes
        phi = info["final_info"]["phi"][i]
        assert info["final_obs"][i][2] == pytest.approx(np.cos(phi), abs=1e-6)
        assert obs[i][2] == pytest.approx(np.cos(info["phi"][i]), abs=1e-6)
    assert vec.unwrapped.steps.tolist() == [0, 0]


def test_bad_autoreset_mode_is_refused_with_the_allowed_ones():
    with pytest.raises(ValueError, match=r"autoreset_mode='sometimes'.*NEXT_STEP"):
        gym.make_vec(IDS[0], num_envs=2, autoreset_mode="sometimes")


def test_reset_mask_resets_only_the_masked_and_marks_only_them():
    vec = gym.make_vec(IDS[1], num_envs=3)
    vec.reset(seed=0)
    vec.step(np.full((3, 1), 0.4, np.float32))
    kept = vec.unwrapped.phi.copy()
    mask = np.array([False, True, False])
    _, info = vec.reset(options={"reset_mask": mask})
    np.testing.assert_array_equal(info["_phi"], mask)
    assert vec.unwrapped.phi[0] == kept[0] and vec.unwrapped.phi[2] == kept[2]
    assert vec.unwrapped.phi[1] == info["phi"][1] != kept[1]


@pytest.mark.parametrize(
    ("options", "message"),
    [({"reset_mask": np.array([0, 1, 2])}, "boolean array"),
     ({"reset_mask": np.array([True, False])}, r"shape \(3,\)"),
     ({"reset_mask": np.zeros(3, bool)}, "at least one True"),
     ([1, 2], r"options=\[1, 2\] must be a dict of reset options"),
     ("state", r"options='state' must be a dict")],
)
def test_bad_reset_masks_are_refused(options, message):
    """(Options that are not a dict at all, in the single environment too.)"""
    vec = gym.make_vec(IDS[0], num_envs=3)
    vec.reset(seed=0)
    with pytest.raises(ValueError, match=message):
        vec.reset(options=options)
    if not isinstance(options, dict):
        with pytest.raises(ValueError, match=message):
            gym.make(IDS[0]).reset(seed=0, options=options)


@pytest.mark.parametrize("seed", [1.5, -1, "3", [1, 2], 2**64 - 2, [0, 2**64, 1]])
def test_bad_seeds_are_refused(seed):
    """Not an integer in [0, 2⁶⁴ − 1] for every sub-environment (an int s gives them s + i:
    2⁶⁴ − 2 overflows at the third), or not one per sub-environment."""
    vec = gym.make_vec(IDS[0], num_envs=3)
    with pytest.raises(ValueError, match="seed"):
        vec.reset(seed=seed)


@pytest.mark.parametrize("seed", [2**64, -1, 1.5, "3", True])
def test_a_single_environment_refuses_seeds_outside_the_64_bit_range(seed):
    env = gym.make(IDS[0])
    with pytest.raises(ValueError, match=r"seed=.* must be None or an integer in \[0, 2\*\*64"):
        env.reset(seed=seed)
    assert env.reset(seed=2**64 - 1)[0].shape == env.observation_space.shape  # the largest


@pytest.mark.parametrize("steps", [0, -5, 2.7, True])
def test_bad_max_episode_steps_are_refused(steps):
    with pytest.raises(ValueError, match="max_episode_steps"):
        gym.make_vec(IDS[0], num_envs=2, max_episode_steps=steps)


def test_numpy_integers_are_counts():
    vec = gym.make_vec(IDS[0], num_envs=np.int64(2), max_episode_steps=np.int32(3))
    obs, _ = vec.reset(seed=np.int64(4))
    assert obs.shape == (2, 5) and vec.unwrapped.max_episode_steps == 3


@pytest.mark.parametrize("env_id", IDS)
def test_step_before_reset_raises_in_both_environments(env_id):
    with pytest.raises(RuntimeError, match="reset"):
        gym.make(env_id).unwrapped.step(np.zeros(1, np.float32))
    with pytest.raises(RuntimeError, match="reset"):
        gym.make_vec(env_id, num_envs=2).step(np.zeros((2, 1), np.float32))


# -- the random streams ----------------------------------------------------------------
def test_streams_are_uniform_and_independent():
    """Kolmogorov–Smirnov against U(0, 1) over consecutive seeds, episodes and draws; and
    no correlation between neighbouring seeds, episodes or draws."""
    seeds = np.arange(20_000, dtype=np.uint64)
    for episode_, draw in ((0, 0), (1, 0), (0, 1), (7, 33)):
        u = episode.uniform(seeds, np.uint64(episode_), draw)
        assert u.min() >= 0.0 and u.max() < 1.0
        assert stats.kstest(u, "uniform").pvalue > 1e-3
    a = episode.uniform(seeds, 0, 0)
    for b in (episode.uniform(seeds + np.uint64(1), 0, 0), episode.uniform(seeds, 1, 0),
              episode.uniform(seeds, 0, 1)):
        assert abs(np.corrcoef(a, b)[0, 1]) < 0.03


def test_a_seed_gives_the_same_episode_sequence_in_both_environments():
    """Sub-environment i of a vector env seeded s makes the draws of a single env seeded
    s + i, episode after episode (resets without a seed continue the stream)."""
    vec = gym.make_vec(IDS[1], num_envs=4)
    singles = [gym.make(IDS[1]) for _ in range(4)]
    first = vec.reset(seed=10)[0]
    for i, env in enumerate(singles):
        np.testing.assert_array_equal(env.reset(seed=10 + i)[0], first[i])
    for _ in range(3):
        obs = vec.reset()[0]
        for i, env in enumerate(singles):
            np.testing.assert_array_equal(env.reset()[0], obs[i])


def test_a_seed_list_reseeds_where_it_gives_a_seed_and_goes_on_where_it_gives_none():
    """``reset(seed=[0, None, 2])`` after a seeded reset, as Gymnasium's SyncVectorEnv over
    single environments: sub-environments 0 and 2 start their new seeds' streams, 1 goes on
    to the next episode of its seed (deterministic), also under a reset_mask (only the
    masked ones take their seeds)."""
    native = gym.make_vec(IDS[1], num_envs=3)
    sync = SyncVectorEnv([lambda: gym.make(IDS[1])] * 3)
    for seed, mask in ((10, None), ([0, None, 2], None), ([5, None, 7], [True, True, False]),
                       (None, [False, True, True])):
        options = None if mask is None else {"reset_mask": np.array(mask)}
        ours, theirs = native.reset(seed=seed, options=options), sync.reset(seed=seed,
                                                                            options=options)
        np.testing.assert_array_equal(ours[0], theirs[0])
        np.testing.assert_array_equal(ours[1]["target_phi"], theirs[1]["target_phi"])


# -- the failure rule --------------------------------------------------------------------
def test_a_failed_step_is_not_reported_as_lift_off_or_slip():
    """A step that could not stay finite: the state before it, NaN forces, energy and
    margins; lifting and slipping False; no reward; terminated, flagged as nonfinite."""
    task = roller_gym.stabilize.StabilizeTask()
    nan = float("nan")
    failed = episode.RestState(0.3, 0.1, nan, 12, False, nan, nan, nan, nan, nan, nan, False)
    context = {"torque": 0.25, "target_phi": 0.0, "target_phi_dot": 0.0, "target_torque": 0.0,
               "target_energy": 0.0, "wrap_rate": 0.25, "psi_rate": 0.25}
    out = episode.outcome(task, failed, context)
    assert out.reward == 0.0 and out.terminated
    assert out.info["nonfinite"] and not out.info["lifting"] and not out.info["slipping"]
    n = 3
    batch = episode.RestState(*(np.full(n, v) for v in (0.3, 0.1, nan, 12, 1.0, nan, nan, nan,
                                                         nan, nan)))
    finite = np.array([True, False, True])
    batch = episode.RestState(batch.phi, batch.phi_dot, batch.phi_ddot, batch.substeps, finite,
                              *(np.where(finite, 0.5, nan) for _ in range(5)))
    out = episode.outcome(task, batch, {**context, "torque": 0.0, "target_phi": np.zeros(n)})
    np.testing.assert_array_equal(out.terminated, [False, True, False])
    assert out.reward[1] == 0.0 and out.reward[0] > 0
    np.testing.assert_array_equal(out.info["lifting"], [False, False, False])


def test_a_step_that_blows_up_is_failed_not_handed_back_as_nan():
    """A coarse fixed-substep scheme (one rk4 substep of 0.3 s on "rim_mass", 1 N·m of torque
    both ways) blows up: φ' grows to ~1e32 rad/s and φ past 2⁵⁰ rad, where the sines of the
    observation are NaN (trig.DOMAIN). Such a step is failed (flagged nonfinite, the state
    before it kept), so no observation, final observation or reward is ever NaN, in the
    vector environment and in the single environment on the same seed and actions."""
    kwargs = {"scene": "rim_mass", "integrator": "rk4", "substeps": 1, "dt": 0.3,
              "max_torque": 1.0}
    n, steps = 64, 40
    vec = gym.make_vec(IDS[0], num_envs=n, autoreset_mode=AutoresetMode.SAME_STEP, **kwargs)
    vec.reset(seed=0)
    actions = np.where(np.arange(n) % 2, 1.0, -1.0).astype(np.float32)[:, None]
    failed = np.zeros(n, dtype=bool)
    for _ in range(steps):
        obs, reward, *_, info = vec.step(actions)
        assert np.isfinite(obs).all() and np.isfinite(reward).all()
        if "final_obs" in info:
            ended = info["_final_obs"]
            assert all(np.isfinite(o).all() for o in info["final_obs"][ended])
            failed |= ended & info["final_info"]["nonfinite"]
    assert failed.any()  # the blow-up happened, and was caught
    i = int(np.flatnonzero(failed)[0])
    single = gym.make(IDS[0], **kwargs)
    single.reset(seed=i)
    caught = False
    for _ in range(steps):
        obs, reward, terminated, truncated, info = single.step(actions[i])
        assert np.isfinite(obs).all() and np.isfinite(reward)
        caught |= bool(info["nonfinite"])
        if terminated or truncated:
            single.reset()
    assert caught


def test_a_huge_start_speed_is_refused_at_reset():
    env = gym.make(IDS[0])
    with pytest.raises(ValueError, match="phi_dot must be within"):
        env.reset(seed=0, options={"state": (0.0, 1e300)})
    with pytest.raises(ValueError, match="finite real numbers"):
        env.reset(seed=0, options={"state": "12"})


# -- pickling after rendering ------------------------------------------------------------
@pytest.mark.parametrize("vector", [False, True])
def test_an_environment_that_rendered_pickles_and_draws_again(vector, monkeypatch):
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")
    env = (gym.make_vec(IDS[0], num_envs=2, render_mode="rgb_array") if vector
           else gym.make(IDS[0], render_mode="rgb_array"))
    env.reset(seed=1)
    first = env.render()
    copy = pickle.loads(pickle.dumps(env))
    a = np.zeros((2, 1) if vector else (1,), np.float32)
    np.testing.assert_array_equal(copy.step(a)[0], env.step(a)[0])
    again = copy.render()
    assert np.shape(again) == np.shape(first)


def test_scene_of_a_preset_stays_shared_without_randomize():
    vec = gym.make_vec(IDS[0], num_envs=3)
    vec.reset(seed=0)
    assert vec.unwrapped.scenes == [preset("paper")] * 3
