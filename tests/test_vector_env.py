"""The native vector environments: ``gymnasium.make_vec(ID, num_envs=N)``.

The independent source is N single environments (``gymnasium.make(ID)``, seeded
``seed + i``) driven in lockstep with the same actions, with Gymnasium's next-step
autoreset written out here: the step after an episode ends is a ``reset()`` of that
single environment, reported with reward 0 and both flags False.
"""

from __future__ import annotations

import math
from functools import partial

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from gymnasium import spaces
from gymnasium.vector import AsyncVectorEnv, AutoresetMode, SyncVectorEnv, VectorEnv
from roller_gym import Scene, preset

IDS = list(roller_gym.ENV_IDS)


def assert_info_row(vec_info: dict, i: int, info: dict) -> None:
    """Sub-environment i of a vector info equals a single environment's info, bit for bit
    (the environment's keys: rl-zoo3, once imported in the test process, patches Gymnasium's
    TimeLimit to add "TimeLimit.truncated" to a single environment's info)."""
    for key, value in info.items():
        if key == "TimeLimit.truncated":
            continue
        assert key in vec_info, key
        assert vec_info[f"_{key}"][i], key
        got = vec_info[key][i]
        # exactly: the same bits (NaN where both failed)
        assert got == value or (got != got and value != value), (key, got, value)


def lockstep(env_id, seed, actions, vec_kwargs, single_kwargs):
    """Run the vector env and its single envs side by side; compare every output.

    Returns the per-step (terminated, truncated) of the vector env.
    """
    n = len(single_kwargs)
    vec = gym.make_vec(env_id, num_envs=n, **vec_kwargs)
    singles = [gym.make(env_id, **kw) for kw in single_kwargs]
    obs, info = vec.reset(seed=seed)
    for i, env in enumerate(singles):
        o, inf = env.reset(seed=seed + i)
        np.testing.assert_array_equal(obs[i], o)
        assert_info_row(info, i, inf)
    done = np.zeros(n, dtype=bool)
    flags = []
    for a in actions:
        obs, reward, terminated, truncated, info = vec.step(a)
        assert obs.dtype == np.float32 and reward.shape == (n,)
        for i, env in enumerate(singles):
            if done[i]:  # next-step autoreset
                o, inf = env.reset()
                r, te, tr = 0.0, False, False
                assert reward[i] == 0.0 and not terminated[i] and not truncated[i]
                assert info["torque"][i] == 0.0 and info["substeps"][i] == 0
            else:
                o, r, te, tr, inf = env.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            assert reward[i] == r
            assert (bool(terminated[i]), bool(truncated[i])) == (te, tr)
            assert_info_row(info, i, inf)
            done[i] = te or tr
        flags.append((terminated.copy(), truncated.copy()))
    vec.close()
    return flags


@pytest.mark.parametrize("env_id", IDS)
def test_make_vec_returns_the_native_vector_env(env_id):
    vec = gym.make_vec(env_id, num_envs=4)
    assert type(vec) is roller_gym.vector_env.RollerVectorEnv
    assert vec.unwrapped.task.env_id() == env_id
    assert isinstance(vec, VectorEnv)
    assert not isinstance(vec, SyncVectorEnv | AsyncVectorEnv)
    assert vec.num_envs == 4
    assert vec.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    single = gym.make(env_id)
    assert vec.single_action_space == single.action_space
    assert vec.single_observation_space == single.observation_space
    n = single.observation_space.shape[0]
    assert vec.observation_space == spaces.Box(-1.0, 1.0, (4, n), np.float32)
    assert vec.action_space == spaces.Box(-1.0, 1.0, (4, 1), np.float32)
    obs, _ = vec.reset(seed=0)
    assert obs.shape == (4, n) and vec.observation_space.contains(obs)
    vec.close()


@pytest.mark.parametrize("env_id", IDS)
def test_same_trajectories_as_single_envs_across_autoresets(env_id):
    """Seeds s + i, random actions, episodes of 7 steps: 17 steps cross two autoresets."""
    actions = np.random.default_rng(0).uniform(-1, 1, (17, 3, 1)).astype(np.float32)
    flags = lockstep(env_id, 5, actions, {"max_episode_steps": 7},
                     [{"max_episode_steps": 7}] * 3)
    truncated = np.array([tr for _, tr in flags])
    np.testing.assert_array_equal(truncated.any(axis=1), [t in (6, 14) for t in range(17)])


def test_per_env_scenes_and_autoreset_after_termination():
    """scene=[...]: one scene per sub-environment; the low-friction one slips under
    bang-bang torques, terminates and starts over on the next step."""
    slippery = preset("paper").replace(mu=0.3)
    scenes = ["paper", slippery, "floor"]
    sign = np.where((np.arange(24) // 4) % 2 == 0, 1.0, -1.0)
    actions = np.repeat(sign[:, None, None], 3, axis=1).astype(np.float32)
    flags = lockstep("roller_gym/RollerStabilize-v2", 0, actions, {"scene": scenes},
                     [{"scene": s} for s in scenes])
    terminated = np.array([te for te, _ in flags])
    assert terminated[:, 1].any() and not terminated[:, [0, 2]].any()
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, scene=scenes)
    obs, _ = vec.reset(seed=0)
    assert vec.unwrapped.scenes == [preset("paper"), slippery, preset("floor")]
    assert obs[2, 0] == 1.0 and obs[2, 1] == 0.0  # ψ stays 0 on the floor
    assert obs[0, 0] != 1.0
    # None in the list: the task's own scene, as scene=None gives the single env
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, scene=[None, "floor", None])
    default = gym.make("roller_gym/RollerStabilize-v2").unwrapped.scene
    assert vec.unwrapped.scenes == [default, preset("floor"), default]


def test_batch_scene_and_randomize_match_single_envs():
    """A batch Scene gives each sub-environment its roller; randomize draws each episode's
    scene from the sub-environment's own generator, as the single env seeded s + i."""
    batch = Scene.stack([preset("paper"), preset("paper").replace(m=2.0, e=0.02)])
    actions = np.random.default_rng(1).uniform(-1, 1, (6, 2, 1)).astype(np.float32)
    lockstep("roller_gym/RollerHold-v2", 3, actions, {"scene": batch},
             [{"scene": batch.item(0)}, {"scene": batch.item(1)}])
    ranges = {"m": (0.8, 1.2), "k": (0.08, 0.12)}
    lockstep("roller_gym/RollerStabilize-v2", 11, actions[:, :2], {"randomize": ranges,
                                                        "max_episode_steps": 3},
             [{"randomize": ranges, "max_episode_steps": 3}] * 2)
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, randomize=ranges)
    vec.reset(seed=11)
    drawn = vec.unwrapped.scenes
    assert len({float(s.m) for s in drawn}) == 3
    for i, s in enumerate(drawn):
        single = gym.make("roller_gym/RollerStabilize-v2", randomize=ranges)
        single.reset(seed=11 + i)
        assert single.unwrapped.scene == s
        assert 0.8 <= float(s.m) <= 1.2 and 0.08 <= float(s.k) <= 0.12


def test_seed_list_and_reproducibility():
    vec = gym.make_vec("roller_gym/RollerHold-v2", num_envs=3)
    obs_a, _ = vec.reset(seed=[4, 9, 2])
    for i, s in enumerate((4, 9, 2)):
        o, _ = gym.make("roller_gym/RollerHold-v2").reset(seed=s)
        np.testing.assert_array_equal(obs_a[i], o)
    a = np.full((3, 1), 0.5, np.float32)
    run1 = [vec.reset(seed=1)[0]] + [vec.step(a)[0] for _ in range(3)]
    run2 = [vec.reset(seed=1)[0]] + [vec.step(a)[0] for _ in range(3)]
    for x, y in zip(run1, run2, strict=True):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(run1[0][0], run1[0][1])


def test_actions_are_clipped_and_nonfinite_rejected():
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=2)
    vec.reset(seed=0, options={"state": (0.0, 0.0)})
    _, _, _, _, info = vec.step(np.array([[3.0], [-0.5]], np.float32))
    np.testing.assert_allclose(info["torque"], [0.5, -0.25])
    before, torque = vec.unwrapped.phi.copy(), vec.unwrapped.torque.copy()
    for bad in (math.nan, math.inf):
        with pytest.raises(ValueError, match="not finite"):
            vec.step(np.array([[0.7], [bad]], np.float32))
    np.testing.assert_array_equal(vec.unwrapped.phi, before)
    # the torques are written in place only once every action is known to be finite
    np.testing.assert_array_equal(vec.unwrapped.torque, torque)


def test_reset_options_and_mask():
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=2)
    _, info = vec.reset(seed=0, options={"state": (0.2, 0.1)})
    np.testing.assert_array_equal(info["phi"], [0.2, 0.2])
    np.testing.assert_array_equal(info["phi_dot"], [0.1, 0.1])
    vec.step(np.full((2, 1), 0.5, np.float32))
    kept = vec.unwrapped.phi[1]
    vec.reset(options={"reset_mask": [True, False], "state": (-0.3, 0.0)})
    assert vec.unwrapped.phi[0] == -0.3 and vec.unwrapped.phi[1] == kept


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"num_envs": 2, "scene": ["paper"]}, "scene has 1 entries"),
        ({"num_envs": 3, "scene": Scene.stack([preset("paper")] * 2)}, "batch of 2"),
        ({"num_envs": 2, "integrator": "dop853"}, "dop853"),
        ({"num_envs": 2, "dt": -1.0}, "dt=-1.0"),
        ({"num_envs": 2, "scene": ["paper", "nope"]}, "'nope'"),
    ],
)
def test_bad_vector_arguments_raise(kwargs, message):
    with pytest.raises(ValueError) as excinfo:
        gym.make_vec("roller_gym/RollerStabilize-v2", **kwargs)
    assert message in str(excinfo.value)


def test_balance_rejects_a_sub_scene_without_an_unstable_rest_position():
    with pytest.raises(ValueError, match="no unstable rest position"):
        gym.make_vec("roller_gym/RollerBalance-v2", num_envs=2, scene=["balance", "tight_fit"])


def test_info_keys_choose_what_the_info_holds():
    """info_keys=[...] in both environments: exactly those keys (and, in the vector env,
    their masks, also in final_info), each with the value the full info has; observations,
    rewards and flags are those of the full environment, across autoresets."""
    env_id, keys = IDS[0], ["energy", "substeps", "is_success"]
    actions = np.random.default_rng(1).uniform(-1, 1, (12, 3, 1)).astype(np.float32)
    for mode in (AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP):
        kw = {"num_envs": 3, "max_episode_steps": 5, "autoreset_mode": mode}
        full, part = gym.make_vec(env_id, **kw), gym.make_vec(env_id, info_keys=keys, **kw)
        (o1, i1), (o2, i2) = full.reset(seed=3), part.reset(seed=3)
        outputs = [((o1, i1), (o2, i2))]
        for a in actions:
            one, two = full.step(a), part.step(a)
            for x, y in zip(one[:4], two[:4], strict=True):
                np.testing.assert_array_equal(x, y)
            outputs.append(((one[0], one[4]), (two[0], two[4])))
        for (_, info1), (_, info2) in outputs:
            extra = {"final_obs", "_final_obs", "final_info", "_final_info"} & set(info2)
            assert set(info2) - extra == set(keys) | {f"_{k}" for k in keys}
            for key in keys:
                np.testing.assert_array_equal(info2[key], info1[key])
                np.testing.assert_array_equal(info2[f"_{key}"], info1[f"_{key}"])
            if "final_info" in info2:
                assert set(info2["final_info"]) == set(keys) | {f"_{k}" for k in keys}
    single_full, single = gym.make(env_id), gym.make(env_id, info_keys=keys)
    (o1, i1), (o2, i2) = single_full.reset(seed=4), single.reset(seed=4)
    for a in actions[:, 0]:
        assert set(i2) == set(keys)
        assert all(i2[k] == i1[k] and type(i2[k]) is type(i1[k]) for k in keys)
        np.testing.assert_array_equal(o1, o2)
        *rest1, i1 = single_full.step(a)
        *rest2, i2 = single.step(a)
        o1, o2 = rest1[0], rest2[0]
        assert rest1[1:] == rest2[1:]


def test_info_keys_may_be_a_numpy_array_of_names():
    """A 1-d NumPy array of names chooses the same keys as the list of them (a NumPy array is
    how names often arrive, from a config or a sweep)."""
    names = ["substeps", "energy"]
    for make in (gym.make, partial(gym.make_vec, num_envs=2)):
        listed = make(IDS[0], info_keys=names).unwrapped.config.info_keys
        assert make(IDS[0], info_keys=np.array(names)).unwrapped.config.info_keys == listed
        assert set(listed) == set(names)


@pytest.mark.parametrize(("value", "message"), [
    (["nope"], r"info_keys=\['nope'\] has unknown names \['nope'\]; allowed: phi, "),
    ("energy", r"info_keys='energy' is not allowed: it must be None \(all\) or a list"),
    (["energy", "energy"], r"info_keys=.* has repeated names"),
    ([1], r"info_keys=\[1\] is not allowed"),
    (np.array([["energy"]]), r"info_keys=array\(\[\['energy'\]\], .* is not allowed"),
    (np.array([1, 2]), r"info_keys=\[1, 2\] is not allowed"),
])
def test_bad_info_keys_are_refused_naming_the_argument(value, message):
    for make in (lambda: gym.make(IDS[0], info_keys=value),
                 lambda: gym.make_vec(IDS[0], num_envs=2, info_keys=value)):
        with pytest.raises(ValueError, match=message):
            make()


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP,
                                  AutoresetMode.DISABLED])
def test_what_a_step_returns_never_changes_afterwards(mode):
    """Episode starts (autoreset, or reset with a mask) write the new episodes' state into the
    environment; the observation, reward, flags and info a caller already holds stay as they
    were (Hold draws a new target per episode, so a shared target array would show)."""
    env = gym.make_vec("roller_gym/RollerHold-v2", num_envs=6, max_episode_steps=3,
                       autoreset_mode=mode)
    rng = np.random.default_rng(2)
    held = [env.reset(seed=1)]
    taken = [_snapshot(held[0])]  # each output as it was when returned
    for _ in range(8):
        out = env.step(rng.uniform(-1, 1, (6, 1)).astype(np.float32))
        held.append(out)
        taken.append(_snapshot(out))
        if mode == AutoresetMode.DISABLED and (out[2] | out[3]).any():
            held.append(env.reset(options={"reset_mask": out[2] | out[3]}))
            taken.append(_snapshot(held[-1]))
        for then, now in zip(taken, held, strict=True):
            assert _same(then, _snapshot(now))
    assert sum(bool((h[2] | h[3]).any()) for h in held[1:] if len(h) == 5) >= 2  # episodes ended


@pytest.mark.parametrize("mode", list(AutoresetMode))
def test_what_a_caller_does_to_the_returned_arrays_never_changes_the_environment(mode):
    """The converse: a caller that writes into every array a step or reset returned (the
    observation, reward, flags and each info array, the state's among them) does not change
    what the environment does next, nor what a partial reset (``reset_mask``) returns for
    the sub-environments it leaves alone; a twin whose outputs are left alone gives the
    same."""
    def scribble(value):
        if isinstance(value, dict):
            for v in value.values():
                scribble(v)
        elif isinstance(value, tuple):
            for v in value:
                scribble(v)
        elif isinstance(value, np.ndarray) and value.dtype != object:
            value[...] = ~value if value.dtype == bool else value + 1

    kwargs = {"num_envs": 5, "max_episode_steps": 3, "autoreset_mode": mode}
    vandal = gym.make_vec("roller_gym/RollerHold-v2", **kwargs)
    twin = gym.make_vec("roller_gym/RollerHold-v2", **kwargs)
    rng = np.random.default_rng(4)
    ours, theirs = vandal.reset(seed=3), twin.reset(seed=3)
    ended = 0
    for k in range(9):
        assert _same(_snapshot(ours), _snapshot(theirs))
        scribble(ours)
        a = rng.uniform(-1, 1, (5, 1)).astype(np.float32)
        ours, theirs = vandal.step(a), twin.step(a)
        done = theirs[2] | theirs[3]
        ended += int(done.sum())
        mask = done if mode == AutoresetMode.DISABLED else np.arange(5) == k % 5
        if mask.any():  # a partial reset, after the step's arrays were written into
            assert _same(_snapshot(ours), _snapshot(theirs))
            scribble(ours)
            options = {"reset_mask": mask}
            ours, theirs = vandal.reset(options=options), twin.reset(options=options)
    assert _same(_snapshot(ours), _snapshot(theirs))
    assert ended >= 5  # autoresets happened in between


def _snapshot(value):
    if isinstance(value, dict):
        return {k: _snapshot(v) for k, v in value.items()}
    if isinstance(value, tuple):
        return tuple(_snapshot(v) for v in value)
    return np.array(value, copy=True) if isinstance(value, np.ndarray) else value


def _same(a, b) -> bool:
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, tuple):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, np.ndarray) and a.dtype != object:
        return np.array_equal(a, b, equal_nan=True)
    if isinstance(a, np.ndarray):
        return all(_same(x, y) for x, y in zip(a, b, strict=True))
    return a is b or a == b


def test_reseeding_mid_run_restarts_the_streams_of_later_autoresets():
    """Autoresets after ``reset(seed=...)`` follow the new seeds (the vector env draws its
    next starts ahead of need: a reseed must not leave the old seeds' starts in use), as
    single environments reseeded the same way."""
    env_id, n, length = "roller_gym/RollerHold-v2", 3, 3
    rng = np.random.default_rng(2)
    vec = gym.make_vec(env_id, num_envs=n, max_episode_steps=length)
    singles = [gym.make(env_id, max_episode_steps=length) for _ in range(n)]
    # one autoreset before the reseed: the starts drawn for episode 1 of the old seeds are
    # what a careless cache would hand out again after it
    for seed, steps in ((4, 5), (40, 8)):
        run = rng.uniform(-1, 1, (steps, n, 1)).astype(np.float32)
        obs, _ = vec.reset(seed=seed)
        for i, env in enumerate(singles):
            np.testing.assert_array_equal(obs[i], env.reset(seed=seed + i)[0])
        done = np.zeros(n, dtype=bool)
        for a in run:
            obs, _, terminated, truncated, info = vec.step(a)
            for i, env in enumerate(singles):
                o = env.reset()[0] if done[i] else env.step(a[i])[0]
                np.testing.assert_array_equal(obs[i], o)
                assert info["target_phi"][i] == env.unwrapped.target
            done = terminated | truncated


@pytest.mark.parametrize("integrator", ["taylor", "rk8"])
def test_a_batch_on_all_cores_matches_single_envs(integrator):
    """Above the parallel threshold a step is one pass over chunks on all cores (each chunk's
    physics, then its outcome): sub-environments at the start, the end and a chunk boundary
    still reproduce the single environments with their seeds, across autoresets."""
    from roller_gym.physics.integrators import CHUNK, PARALLEL_THRESHOLD

    env_id, n, length = "roller_gym/RollerHold-v2", PARALLEL_THRESHOLD + 37, 4
    vec = gym.make_vec(env_id, num_envs=n, max_episode_steps=length, integrator=integrator)
    assert vec.unwrapped._stepper.parallel
    watched = [0, CHUNK - 1, CHUNK, n - 1]
    singles = {i: gym.make(env_id, max_episode_steps=length, integrator=integrator)
               for i in watched}
    obs, _ = vec.reset(seed=9)
    for i, env in singles.items():
        np.testing.assert_array_equal(obs[i], env.reset(seed=9 + i)[0])
    rng = np.random.default_rng(3)
    done = np.zeros(n, dtype=bool)
    for _ in range(9):
        a = rng.uniform(-1, 1, (n, 1)).astype(np.float32)
        obs, reward, terminated, truncated, info = vec.step(a)
        for i, env in singles.items():
            if done[i]:
                o, inf = env.reset()
                r = 0.0
            else:
                o, r, _, _, inf = env.step(a[i])
            np.testing.assert_array_equal(obs[i], o)
            assert reward[i] == r
            assert_info_row(info, i, inf)
        done = terminated | truncated
    assert done.any()


def test_a_scene_option_lasts_one_episode_as_in_the_single_env():
    """``reset(options={"scene": ...})`` sets the scene of that episode only: the next start
    (an explicit reset or an autoreset) goes back to the base scene, in both environments."""
    env_id, n, length = "roller_gym/RollerStabilize-v2", 2, 3
    vec = gym.make_vec(env_id, num_envs=n, max_episode_steps=length)
    singles = [gym.make(env_id, max_episode_steps=length) for _ in range(n)]
    obs, _ = vec.reset(seed=5)
    for i, env in enumerate(singles):
        env.reset(seed=5 + i)
    obs, _ = vec.reset(options={"scene": "floor", "reset_mask": np.array([True, False])})
    np.testing.assert_array_equal(obs[0], singles[0].reset(options={"scene": "floor"})[0])
    assert vec.unwrapped.scenes[0] == preset("floor") != vec.unwrapped.scenes[1]
    rng = np.random.default_rng(4)
    done = np.zeros(n, dtype=bool)
    for _ in range(2 * length + 1):  # the option's episode, an autoreset, the next episode
        a = rng.uniform(-1, 1, (n, 1)).astype(np.float32)
        obs, _, terminated, truncated, info = vec.step(a)
        for i, env in enumerate(singles):
            o = env.reset()[0] if done[i] else env.step(a[i])[0]
            np.testing.assert_array_equal(obs[i], o)
            assert info["psi"][i] == env.unwrapped.phi * env.unwrapped._psi_rate
        done = terminated | truncated
    assert vec.unwrapped.scenes[0] == vec.unwrapped.scenes[1] == singles[0].unwrapped.scene


def test_a_target_option_resets_sub_environments_that_share_a_scene():
    """``reset(options={"target": x})`` of several sub-environments of one shared scene gives
    each the single environment's target for x."""
    env_id, n = "roller_gym/RollerHold-v2", 3
    vec = gym.make_vec(env_id, num_envs=n)
    single = gym.make(env_id)
    vec.reset(seed=1)
    single.reset(seed=1)
    _, info = vec.reset(options={"target": 0.3})
    _, one = single.reset(options={"target": 0.3})
    np.testing.assert_array_equal(info["target_phi"], np.full(n, one["target_phi"]))


def test_a_pickled_scheme_is_its_row_of_the_table():
    """A scheme pickles by name (its compiled functions are this process's), so that an
    unpickled vector environment still finds its fused kernel."""
    import pickle

    from roller_gym.physics.integrators import SCHEMES

    for s in SCHEMES.values():
        assert pickle.loads(pickle.dumps(s)) is s
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=4)
    assert pickle.loads(pickle.dumps(vec)).unwrapped._stepper.scheme is SCHEMES["taylor"]


@pytest.mark.parametrize("n", [1, 70])
def test_a_moving_target_has_the_same_bits_alone_and_in_a_batch(n):
    """RollerTrack's target is a function of the step count, evaluated alone (the single
    env, numbers) and for a batch (arrays, here of 1 and of 70): the target, its holding
    torque and the reward agree bit for bit over an episode."""
    env_id = "roller_gym/RollerTrack-v1"
    vec = gym.make_vec(env_id, num_envs=n)
    single = gym.make(env_id)
    vec.reset(seed=1)
    single.reset(seed=1)
    rng = np.random.default_rng(2)
    done = False
    for _ in range(60):
        a = rng.uniform(-1, 1, (n, 1)).astype(np.float32)
        _, reward, terminated, truncated, info = vec.step(a)
        if done:  # next-step autoreset
            r, one = 0.0, single.reset()[1]
        else:
            _, r, _, _, one = single.step(a[0])
        assert (info["target_phi"][0], info["target_torque"][0], reward[0]) == (
            one["target_phi"], one["target_torque"], r)
        done = terminated[0] or truncated[0]


def test_a_sub_environment_never_started_cannot_be_stepped():
    """A first reset with a reset_mask starts only the masked sub-environments: step()
    refuses, naming the others, until a reset has started them too."""
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=4)
    vec.reset(seed=0, options={"reset_mask": np.array([True, False, True, False])})
    a = np.zeros((4, 1), np.float32)
    with pytest.raises(RuntimeError, match=r"sub-environments \[1, 3\] have not started"):
        vec.step(a)
    vec.reset(seed=0, options={"reset_mask": np.array([False, True, False, True])})
    obs = vec.step(a)[0]
    reference = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=4)
    reference.reset(seed=0)
    np.testing.assert_array_equal(obs, reference.step(a)[0])


def test_disabled_autoreset_refuses_to_step_an_ended_episode():
    """With autoreset_mode=DISABLED an ended episode waits for reset(reset_mask): stepping
    it before (as Gymnasium's SyncVectorEnv refuses to) raises, naming it."""
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, max_episode_steps=2,
                       autoreset_mode=AutoresetMode.DISABLED)
    vec.reset(seed=0, options={"reset_mask": np.array([True, True, True])})
    a = np.zeros((3, 1), np.float32)
    vec.step(a)
    vec.reset(options={"reset_mask": np.array([False, True, False])})
    truncated = vec.step(a)[3]
    np.testing.assert_array_equal(truncated, [True, False, True])
    with pytest.raises(RuntimeError, match=r"sub-environments \[0, 2\] have ended"):
        vec.step(a)
    vec.reset(options={"reset_mask": truncated})
    np.testing.assert_array_equal(vec.step(a)[3], [False, True, False])  # 1's second step


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
def test_each_info_key_has_a_mask_of_its_own(mode):
    """The info's ``_key`` masks (of a reset, a step, and SAME_STEP's final info) are arrays
    of their own, as Gymnasium's vector envs give them (its ``_add_info`` writes into them):
    writing into ``info["_phi"]`` leaves ``info["_energy"]`` as it was."""
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, max_episode_steps=1,
                       autoreset_mode=mode)
    infos = [vec.reset(seed=0)[1], vec.step(np.zeros((3, 1), np.float32))[4]]
    if mode == AutoresetMode.SAME_STEP:
        infos.append(infos[-1]["final_info"])
    for info in infos:
        before = info["_energy"].copy()
        info["_phi"][0] = not info["_phi"][0]
        np.testing.assert_array_equal(info["_energy"], before)
        assert info["_phi"][0] != info["_energy"][0]
