"""The single environment's fast paths against the general ones, bit for bit.

Its info (a function written out for its keys, see ``roller_env._scalar_info``) against the
vector environment's info arrays: the vector env builds its info another way (one array per
key from the outcome's rows, ``episode.info_rows``) and its sub-environment i makes the
episodes of a single env seeded ``seed + i``. Its episode starts (one roller: a round of
candidates per call, ``starts._draw_one``) against a batch's (a candidate per call).
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym.episode import INFO_KEYS, starts
from roller_gym.episode.streams import uniform

IDS = list(roller_gym.ENV_IDS)
SCALAR = {float: np.float64, int: np.int64, bool: np.bool_}


def check_info(info: dict, vec_info: dict, i: int, keys: tuple[str, ...]) -> None:
    """A single env's info is a plain dict of ``keys`` in INFO_KEYS order, each value a NumPy
    scalar of its key's type with the bits of sub-environment i's entry of the vector info
    (but ``TimeLimit.truncated``, which rl-zoo3 adds to Gymnasium's TimeLimit once it is
    imported in the process: ``rl_zoo3.gym_patches``)."""
    ours = {key: value for key, value in info.items() if key != "TimeLimit.truncated"}
    assert type(info) is dict and tuple(ours) == keys
    for key, value in ours.items():
        kind = SCALAR[INFO_KEYS[key][0]]
        assert type(value) is kind, (key, type(value))
        expected = np.asarray(vec_info[key][i], dtype=kind)
        assert np.asarray(value).tobytes() == expected.tobytes(), (key, value, expected)


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("info_keys", [None, ["energy", "substeps", "is_success"], []])
def test_the_single_info_is_the_vector_info_with_numpy_types(env_id, info_keys):
    """Eight seeds, random actions, episodes of 6 steps (resets included): each step's info
    is a new dict, and one a caller changes changes nothing that comes after."""
    n, seed = 8, 11
    keys = tuple(INFO_KEYS) if info_keys is None else tuple(info_keys)
    vec = gym.make_vec(env_id, num_envs=n, max_episode_steps=6, info_keys=info_keys)
    singles = [gym.make(env_id, max_episode_steps=6, info_keys=info_keys) for _ in range(n)]
    _, vec_info = vec.reset(seed=seed)
    infos = [env.reset(seed=seed + i)[1] for i, env in enumerate(singles)]
    done = np.zeros(n, bool)
    seen = []
    actions = np.random.default_rng(seed).uniform(-1, 1, (20, n, 1)).astype(np.float32)
    for a in actions:
        for i, info in enumerate(infos):
            check_info(info, vec_info, i, keys)
            # a caller's changes: no later info sees them
            info.update(dict.fromkeys(info, "changed by a caller"), phi_ddot=0.0)
            seen.append(info)
        _, _, terminated, truncated, vec_info = vec.step(a)
        infos = []
        for i, env in enumerate(singles):
            if done[i]:  # next-step autoreset
                infos.append(env.reset()[1])
            else:
                infos.append(env.step(a[i])[4])
        done = terminated | truncated
    assert len({id(info) for info in seen}) == len(seen)
    vec.close()


@pytest.mark.parametrize("env_id", IDS)
def test_a_single_start_is_the_batch_start_of_its_seed(env_id):
    """The start of one episode (seed, episode number) drawn alone, as a single env's reset
    draws it, has the bits of its row of a batch of 4096 drawn together: scene, target and
    state; among the rollers compared, every one whose first round of candidates is all
    refused (the batch found its start in a later round)."""
    config = gym.make(env_id).unwrapped.config
    n = 4096
    seeds = np.arange(n, dtype=np.uint64) + np.uint64(2**63)
    episodes = np.arange(n, dtype=np.uint64) % np.uint64(7)
    batch = starts.start_episodes(config, config.scene, seeds, episodes, None)
    # the first round's candidates of each roller (draws 2j and 2j + 1 of the state's)
    u = uniform(seeds[:, None], episodes[:, None],
                starts._STATE_DRAW + np.arange(2 * starts.CANDIDATES))
    first = config.task.start_accepted(
        *config.task.start_candidates(u[:, 0::2], u[:, 1::2], batch.scene), batch.scene)
    later = np.flatnonzero(~first.any(axis=1))
    # (Balance's and Swing's starts lie near the bottom, where every candidate rolls)
    assert later.size or env_id.split("/")[1].startswith(("RollerBalance", "RollerSwing"))
    for i in [*range(24), *later]:
        one = starts.start_episodes(config, config.scene, seeds[i:i + 1], episodes[i:i + 1],
                                    None)
        for name in ("target_params", "target", "target_rate", "phi", "phi_dot"):
            got, expected = getattr(one, name), getattr(batch, name)[i:i + 1]
            assert got.dtype == expected.dtype and got.tobytes() == expected.tobytes(), name
        if config.randomize:
            for name in config.randomize:
                assert np.asarray(getattr(one.scene, name)).tobytes() == np.asarray(
                    getattr(batch.scene, name))[i:i + 1].tobytes(), name
