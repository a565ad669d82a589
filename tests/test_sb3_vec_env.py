"""The SB3 ``VecEnv`` over the native batch against SB3's own ``DummyVecEnv`` of single
environments (``make_vec_env``): the same episodes with the same seeds, and SB3's wrappers
and algorithms on top of it."""

from __future__ import annotations

import math

import gymnasium
import gymnasium.envs.registration
import gymnasium.wrappers.common
import numpy as np
import pytest

pytest.importorskip("stable_baselines3")

import roller_gym
from roller_gym.sb3 import RollerVecEnv, from_env_fns
from stable_baselines3 import A2C, PPO, SAC
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import (
    DummyVecEnv,
    VecCheckNan,
    VecEnv,
    VecMonitor,
    VecNormalize,
)
from zoo import HAVE_RL_ZOO3, import_rl_zoo3

IDS = list(roller_gym.ENV_IDS)


@pytest.mark.parametrize("env_id", IDS)
def test_same_episodes_as_dummy_vec_env(env_id):
    """Seeds 3 + i, random actions, episodes of 6 steps over 20 steps: observations,
    rewards, dones, the terminal observations, TimeLimit.truncated and the physics info."""
    n = 3
    ours = RollerVecEnv(env_id, n_envs=n, seed=3, max_episode_steps=6)
    ref = make_vec_env(env_id, n_envs=n, seed=3, env_kwargs={"max_episode_steps": 6})
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    for i in range(n):
        assert ours.reset_infos[i]["phi"] == pytest.approx(ref.reset_infos[i]["phi"], abs=0)
    actions = np.random.default_rng(0).uniform(-1, 1, (20, n, 1)).astype(np.float32)
    ended = 0
    for a in actions:
        obs, rew, done, info = ours.step(a)
        obs_r, rew_r, done_r, info_r = ref.step(a)
        np.testing.assert_array_equal(obs, obs_r)
        np.testing.assert_allclose(rew, rew_r, rtol=1e-6)
        np.testing.assert_array_equal(done, done_r)
        for mine, theirs in zip(info, info_r, strict=True):
            assert mine["TimeLimit.truncated"] == theirs["TimeLimit.truncated"]
            for key in ("phi", "phi_dot", "energy", "substeps", "is_success", "lifting"):
                assert mine[key] == pytest.approx(theirs[key], rel=1e-12, abs=1e-12), key
            if "terminal_observation" in theirs:
                ended += 1
                np.testing.assert_array_equal(mine["terminal_observation"],
                                              theirs["terminal_observation"])
            else:
                assert "terminal_observation" not in mine
    assert ended >= n * 3


def test_sb3_wrappers_and_algorithms_run_on_it():
    """PPO under VecNormalize(VecMonitor(VecCheckNan(...))) and SAC: the monitor's episode
    returns equal the sums of the rewards the env returned, and training moves the policy."""
    env = VecCheckNan(RollerVecEnv(IDS[0], n_envs=4, seed=0, max_episode_steps=16),
                      raise_exception=True)
    monitored = VecMonitor(env)
    sums, returns = np.zeros(4), []
    monitored.reset()
    rng = np.random.default_rng(0)
    for _ in range(40):
        _, rew, done, info = monitored.step(rng.uniform(-1, 1, (4, 1)).astype(np.float32))
        sums += rew
        for i in np.flatnonzero(done):
            assert info[i]["episode"]["r"] == pytest.approx(sums[i], abs=1e-4)
            assert info[i]["episode"]["l"] == 16
            returns.append(sums[i])
            sums[i] = 0.0
    assert len(returns) == 8
    venv = VecNormalize(monitored)
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, seed=0, device="cpu")
    before = [p.detach().clone() for p in model.policy.parameters()]
    model.learn(256)
    assert any(not np.allclose(b.numpy(), p.detach().numpy())
               for b, p in zip(before, model.policy.parameters(), strict=True))
    sac = SAC("MlpPolicy", RollerVecEnv(IDS[1], n_envs=2, seed=1), learning_starts=32,
              batch_size=32, seed=0, device="cpu")
    sac.learn(64)
    assert sac.num_timesteps == 64


def test_a2c_learns_the_same_policy_as_on_dummy_vec_env():
    """A2C with the same seeds, through the native batch and through DummyVecEnv of single
    environments (episodes of 16 steps, autoresets included): the same episodes give the
    same updates, so the trained policies' parameters are equal."""
    import torch

    params = []
    for env in (RollerVecEnv(IDS[0], n_envs=4, seed=5, max_episode_steps=16),
                make_vec_env(IDS[0], n_envs=4, seed=5, env_kwargs={"max_episode_steps": 16})):
        model = A2C("MlpPolicy", env, n_steps=8, seed=0, device="cpu")
        model.learn(256)
        params.append(torch.nn.utils.parameters_to_vector(model.policy.parameters()).detach())
    initial = A2C("MlpPolicy", make_vec_env(IDS[0], n_envs=4, seed=5), n_steps=8, seed=0,
                  device="cpu").policy.parameters()
    assert not torch.equal(params[0], torch.nn.utils.parameters_to_vector(initial).detach())
    torch.testing.assert_close(params[0], params[1], rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("time_limit", ["gymnasium", "rl_zoo3"])
def test_make_vec_env_builds_the_native_batch_with_the_same_episodes(time_limit, monkeypatch):
    """``vec_env_cls=from_env_fns`` (what ``roller-gym train`` gives rl-zoo3): SB3's own
    make_vec_env then steps the native batch, with DummyVecEnv's episodes; also in a process
    that imported rl-zoo3, whose own TimeLimit then wraps every environment."""
    if time_limit == "rl_zoo3":
        if not HAVE_RL_ZOO3:
            pytest.skip("rl-zoo3 is not installed (the zoo extra; CI installs it)")
        patched = import_rl_zoo3("rl_zoo3.gym_patches").PatchedTimeLimit
        for owner in (gymnasium.wrappers, gymnasium.wrappers.common,
                      gymnasium.envs.registration):  # where rl-zoo3 puts it
            monkeypatch.setattr(owner, "TimeLimit", patched, raising=False)
        assert type(gymnasium.make(IDS[1], max_episode_steps=5)).__name__ == "PatchedTimeLimit"
    kwargs = {"max_episode_steps": 5}
    ours = make_vec_env(IDS[1], n_envs=3, seed=7, env_kwargs=kwargs, vec_env_cls=from_env_fns)
    ref = make_vec_env(IDS[1], n_envs=3, seed=7, env_kwargs=kwargs)
    assert isinstance(ours, RollerVecEnv) and ours.monitor
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    for a in np.random.default_rng(2).uniform(-1, 1, (12, 3, 1)).astype(np.float32):
        obs, rew, done, info = ours.step(a)
        obs_r, rew_r, done_r, info_r = ref.step(a)
        np.testing.assert_array_equal(obs, obs_r)
        np.testing.assert_array_equal(done, done_r)
        np.testing.assert_allclose(rew, rew_r, rtol=1e-6)
        for mine, theirs in zip(info, info_r, strict=True):  # Monitor's episode statistics
            assert ("episode" in mine) == ("episode" in theirs)
            if "episode" in theirs:
                assert mine["episode"]["l"] == theirs["episode"]["l"] == 5
                assert mine["episode"]["r"] == pytest.approx(theirs["episode"]["r"], abs=1e-5)
    other = make_vec_env("Pendulum-v1", n_envs=2, vec_env_cls=from_env_fns)
    assert not isinstance(other, RollerVecEnv)


def test_make_vec_env_of_an_integrator_the_batch_does_not_take_is_dummy_vec_env():
    """scipy's DOP853 is a reference for the single environment, which the native batch
    refuses: from_env_fns then gives DummyVecEnv of the single environments, as make_vec_env
    does without it (so ``roller-gym train --env-kwargs integrator=dop853`` trains)."""
    from stable_baselines3.common.vec_env import DummyVecEnv

    with pytest.raises(ValueError, match="integrator='dop853' is a reference for the single"):
        RollerVecEnv(IDS[0], n_envs=2, integrator="dop853")
    kwargs = {"integrator": "dop853", "max_episode_steps": 3}
    ours = make_vec_env(IDS[0], n_envs=2, seed=1, env_kwargs=kwargs, vec_env_cls=from_env_fns)
    ref = make_vec_env(IDS[0], n_envs=2, seed=1, env_kwargs=kwargs)
    assert type(ours) is DummyVecEnv
    np.testing.assert_array_equal(ours.reset(), ref.reset())
    action = np.full((2, 1), 0.3, dtype=np.float32)
    np.testing.assert_array_equal(ours.step(action)[0], ref.step(action)[0])


def test_reset_options_are_each_sub_environments_own_as_in_dummy_vec_env():
    """``set_options`` with a list gives each sub-environment its own reset options (None:
    none), with one dict all of them the same: the same starts as DummyVecEnv's."""
    ours, ref = RollerVecEnv(IDS[1], n_envs=3, seed=0), make_vec_env(IDS[1], n_envs=3, seed=0)
    for options in ([None, {"target": 0.3}, {"target": -0.2}], [{"target": 0.3}, None, None],
                    {"target": 0.1}, None):
        ours.set_options(options)
        ref.set_options(options)
        np.testing.assert_array_equal(ours.reset(), ref.reset())
        assert [i["target_phi"] for i in ours.reset_infos] == \
            [i["target_phi"] for i in ref.reset_infos]


def test_attributes_per_sub_environment_as_in_dummy_vec_env():
    """get_attr gives each sub-environment in ``indices`` its own value (an array of the
    batch split, the spaces a single environment's), as DummyVecEnv over single
    environments; set_attr sets only those; what is one value for the whole batch, or a
    method, cannot be applied to some of them only, and says so."""
    ours, ref = RollerVecEnv(IDS[1], n_envs=3, seed=0), make_vec_env(IDS[1], n_envs=3, seed=0)
    ours.reset(), ref.reset()
    for name, indices in (("phi", None), ("phi", [1]), ("target", [2, 0]),
                          ("observation_space", 1)):
        assert ours.get_attr(name, indices) == ref.get_attr(name, indices), name
    ours.set_attr("phi", 0.5, [2])
    ref.set_attr("phi", 0.5, [2])
    assert ours.get_attr("phi") == ref.get_attr("phi")
    ours.set_attr("curriculum_level", 3)  # a new attribute, for all of them
    assert ours.get_attr("curriculum_level", [0, 2]) == [3, 3]
    with pytest.raises(ValueError, match="'render_mode' is the native batch's own"):
        ours.set_attr("render_mode", None)
    with pytest.raises(ValueError, match="'curriculum_level' is one value for the whole"):
        ours.set_attr("curriculum_level", 4, [1])
    with pytest.raises(ValueError, match=r"env_method\('reset', indices=\[0\]\)"):
        ours.env_method("reset", indices=[0])


@pytest.mark.parametrize(("value", "indices"), [("abc", None), (math.nan, [0]), (True, [1]),
                                                ([0.1, 0.2], [0]), (np.zeros((3, 1)), None)])
def test_set_attr_of_the_state_refuses_what_is_not_one_finite_angle_each(value, indices):
    """A state written through set_attr is checked as a reset's is (NaN was written and the
    next step handed back a NaN observation; text failed in NumPy's float conversion; a
    wrong count in NumPy's broadcasting); the state is left as it was."""
    venv = RollerVecEnv(IDS[0], n_envs=3, seed=0)
    venv.reset()
    before = venv.get_attr("phi")
    with pytest.raises(ValueError, match=r"(?s)set_attr\('phi', value=.*('phi' holds finite "
                                         r"real numbers|refused by a reset: .*finite)"):
        venv.set_attr("phi", value, indices)
    assert venv.get_attr("phi") == before


@pytest.mark.parametrize(("call", "message"), [
    (lambda v: v.set_attr("autoreset_mode", "next_step"), r"'autoreset_mode' is the native"),
    (lambda v: v.set_attr("max_episode_steps", "abc"), r"'max_episode_steps' is the native"),
    (lambda v: v.set_attr("num_envs", 7), r"'num_envs' is the native batch's own"),
    # (the settings of its config and task were taken as attributes of the user's own, and
    # get_attr then gave values not in force)
    (lambda v: v.set_attr("max_torque", 100.0), r"'max_torque' is the native batch's own"),
    (lambda v: v.set_attr("dt", 0.5), r"'dt' is the native batch's own"),
    # (accepted, then every later reset failed)
    (lambda v: v.set_options({"targt": 0.1}), r"reset options \['targt'\] are not known"),
    (lambda v: v.set_attr("phi", 1e300), r"sub-environment 0 would be refused by a reset: "
                                         r".*phi must be within"),
    (lambda v: v.set_attr("phi_dot", 1e300, [1]), r"sub-environment 1 would be refused by a "
                                                   r"reset: .*phi_dot must be within"),
    (lambda v: v.get_attr("phi", [5]), r"indices=\[5\] must be None \(all\), an integer or a "
                                       r"list of integers in \[0, 3\)"),
    (lambda v: v.set_attr("phi", 0.1, True), r"indices=True must be None"),
    (lambda v: v.env_is_wrapped(gymnasium.Wrapper, [9]), r"indices=\[9\] must be None"),
    (lambda v: v.set_options([{}]), r"options=\[\{\}\] must be None, a dict, or a list of 3"),
    (lambda v: v.set_options("x"), r"options='x' must be None"),
    # (SB3's reset() restarted only the masked ones, and zeroed every episode's length)
    (lambda v: v.set_options({"reset_mask": np.array([True, False, False])}),
     r"SB3's reset\(\) starts every sub-environment; a reset_mask does not apply")])
def test_what_would_break_the_batch_is_refused_where_it_is_given(call, message):
    """The batch's own settings set through set_attr broke later steps (autoreset_mode: a
    KeyError at the next episode's end; max_episode_steps: NumPy's UFuncTypeError); a state no
    reset would start from was written; indices out of range and options of the wrong count
    failed in NumPy or at the next reset (IndexError)."""
    venv = RollerVecEnv(IDS[0], n_envs=3, seed=0, max_episode_steps=2)
    venv.reset()
    with pytest.raises(ValueError, match=message):
        call(venv)
    for _ in range(3):  # the batch still steps through an episode's end
        venv.step(np.zeros((3, 1)))


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"n_envs": 0}, r"n_envs=0 must be a positive integer"),
    ({"n_envs": 2.0}, r"n_envs=2.0 must be"), ({"seed": -1}, r"seed=-1 must be None"),
    ({"seed": "x"}, r"seed='x' must be None"), ({"monitor": 3}, r"monitor=3 must be"),
    ({"seed": [0, 1]}, r"seed=\[0, 1\] must be None or an integer: SB3 seeds"),
    ({"autoreset_mode": "next_step"}, r"autoreset_mode: RollerVecEnv sets these itself"),
    ({"num_envs": 3, "vectorization_mode": "sync"},
     r"num_envs, vectorization_mode: RollerVecEnv sets these itself"),
    ({"env_id": "CartPole-v1"}, r"env_id='CartPole-v1' is not a roller-gym task ID"),
    ({"env_id": 3}, r"env_id=3 is not a roller-gym task ID"),
    # (Gymnasium's NameNotFound)
    ({"env_id": "roller_gym/Foo-v0"}, r"env_id='roller_gym/Foo-v0' is not a registered "
                                      r"roller-gym task ID; registered: .*RollerStabilize-v2")])
def test_bad_arguments_are_refused_naming_them(kwargs, message):
    """(Another task's ID failed in its own vector environment: "unexpected keyword
    argument 'autoreset_mode'".)"""
    with pytest.raises(ValueError, match=message):
        RollerVecEnv(**{"env_id": IDS[0], "n_envs": 2, **kwargs})


def test_a_seed_that_is_not_an_integer_is_refused_before_the_reset():
    """SB3's seed() took any value and the next reset failed inside SB3 (a list: "can only
    concatenate list"); it is refused where it is given."""
    venv = RollerVecEnv(IDS[0], n_envs=2)
    for bad in ("a", [0, 1], 1.5):
        with pytest.raises(ValueError, match=r"seed=.* must be None"):
            venv.seed(bad)
    venv.seed(3)
    assert venv._seeds == [3, 4]


def test_bad_actions_and_no_environments_are_refused_naming_them():
    """Actions go to the batch's own check (they were cast to float32 and reshaped first:
    a wrong count failed in NumPy's reshape, and 1e39 became inf and was refused where the
    batch clips it to 1); an empty list of environment functions is refused (IndexError)."""
    venv = RollerVecEnv(IDS[0], n_envs=2)
    venv.reset()
    for bad in (np.zeros(3), None, np.array([["a"], ["b"]])):
        with pytest.raises(ValueError, match=r"(?s)action=.* is not allowed"):
            venv.step(bad)
    *_, infos = venv.step(np.array([[1e39], [0.0]]))  # clipped, as the native batch does
    assert infos[0]["torque"] == venv.venv.unwrapped.task.max_torque
    with pytest.raises(ValueError, match=r"env_fns=\[\] must be a non-empty list"):
        from_env_fns([])


def test_from_env_fns_batches_only_environments_made_alike():
    """Environments that differ (another task, another dt, no time limit) were all made as
    the first one; now they go to DummyVecEnv, which makes each as asked. Bad functions and
    keyword arguments are refused by name (they failed in SB3 or were dropped), and so are
    environments of other spaces (they went to DummyVecEnv, whose reset then failed)."""
    same = from_env_fns([lambda: gymnasium.make(IDS[0]), lambda: gymnasium.make(IDS[0])])
    assert isinstance(same, RollerVecEnv)
    scaled = from_env_fns([lambda: gymnasium.make(IDS[0]), lambda: gymnasium.wrappers.
                           TransformReward(gymnasium.make(IDS[0]), lambda r: 100 * r)])
    assert isinstance(scaled, DummyVecEnv)  # (the second one's wrapper was dropped)
    balance = "roller_gym/RollerBalance-v2"  # another task of the same spaces
    for fns in ([lambda: gymnasium.make(IDS[0]), lambda: gymnasium.make(balance)],
                [lambda: gymnasium.make(IDS[0], dt=0.05), lambda: gymnasium.make(IDS[0], dt=0.1)],
                [lambda: gymnasium.make(IDS[0], max_episode_steps=-1)]):
        venv = from_env_fns(fns)
        assert isinstance(venv, DummyVecEnv)
        assert [e.spec.kwargs.get("dt") for e in venv.envs] == [
            fn().spec.kwargs.get("dt") for fn in fns]
    for bad, message in (((lambda: gymnasium.make(IDS[0])), r"must be a non-empty list"),
                         ([None], r"env_fns\[0\]=None must be a function .*not callable"),
                         ([lambda: 5], r"env_fns\[0\]=.* \(it made 5\)"),
                         ([lambda: gymnasium.make(IDS[0]), lambda: gymnasium.make(
                             "roller_gym/RollerHold-v2")], r"env_fns\[1\]=.* makes an environment "
                          r"whose observation space Box\(.*\(9,\).*\) differs from env_fns\[0\]'s, "
                          r"Box\(.*\(5,\).*\)"),
                         ([lambda: gymnasium.make(IDS[0]), lambda: gymnasium.wrappers.RescaleAction(
                             gymnasium.make(IDS[0]), np.float32(0), np.float32(2))],
                          r"env_fns\[1\]=.* whose action space Box\(0\.0, 2\.0, .*\) differs")):
        with pytest.raises(ValueError, match=message):
            from_env_fns(bad)
    with pytest.raises(ValueError, match=r"takes no keyword arguments \(got foo\)"):
        from_env_fns([lambda: gymnasium.make(IDS[0])], foo=1)


def test_set_options_refuses_values_a_reset_would_refuse_and_keeps_the_last_ones():
    """A value was accepted by set_options and refused by every later reset; now it is
    refused at once, by the reset's own checks, and the options set before stay in force."""
    env, twin = (RollerVecEnv(IDS[1], n_envs=2, seed=0) for _ in range(2))
    env.set_options({"target": 0.1}), twin.set_options({"target": 0.1})
    for bad, message in (({"state": "abc"}, r"options\['state'\]='abc' must be a pair"),
                         ([None, {"target": 99.0}],
                          r"options\['target'\]=99.0 rad cannot be held")):
        with pytest.raises(ValueError, match=message):
            env.set_options(bad)
    np.testing.assert_array_equal(env.reset(), twin.reset())
    assert env.get_attr("target") == twin.get_attr("target")


def test_set_options_judges_the_values_on_the_next_resets_own_scene():
    """In a scene drawn per episode, a target holdable in one episode's scene is not in
    another's: set_options judges it on the episode the next reset draws, with the seed set
    before it, so that what it accepts the reset takes and what it refuses the reset would
    have refused (checked by setting the options past the check)."""
    env = RollerVecEnv("roller_gym/RollerHoldRandomized-v2", n_envs=1, seed=0)
    env.reset()
    verdicts = []
    for seed in range(12):
        env.seed(seed)
        try:
            env.set_options({"target": 0.2})
            accepted = True
        except ValueError as exc:
            assert "options['target']=0.2 rad cannot be held" in str(exc)
            accepted = False
            VecEnv.set_options(env, {"target": 0.2})
        if accepted:
            env.reset()
        else:
            with pytest.raises(ValueError, match=r"options\['target'\]=0.2 rad cannot be held"):
                env.reset()
            env.set_options(None)
        verdicts.append(accepted)
    assert any(verdicts) and not all(verdicts)


def test_a_refused_reset_of_per_sub_environment_options_resets_none():
    """Options set per sub-environment reset in groups: where a later group's are refused,
    the earlier groups' sub-environments are as they were (they had already started anew),
    and the batch steps on as a twin that never saw the refused reset."""
    env, twin = (RollerVecEnv(IDS[0], n_envs=2, seed=0) for _ in range(2))
    env.reset(), twin.reset()
    before = env.get_attr("phi")
    # set_options checks the values on the streams as they stand, so only a scene drawn
    # anew could refuse them later: stood in for by setting them past that check
    VecEnv.set_options(env, [{"state": (0.1, 0.0)}, {"state": (1e6, 0.0)}])
    with pytest.raises(ValueError, match=r"options\['state'\]=\(1000000.0, 0.0\)"):
        env.reset()
    assert env.get_attr("phi") == before
    actions = np.full((2, 1), 0.3, np.float32)
    for _ in range(3):
        env.step_async(actions), twin.step_async(actions)
        np.testing.assert_array_equal(env.step_wait()[0], twin.step_wait()[0])


@pytest.mark.parametrize("kwargs", [{"info_keys": np.array(["phi", "is_success"])},
                                    {"randomize": {"m": np.array([0.9, 1.1])}}])
def test_from_env_fns_compares_numpy_arguments_by_value(kwargs):
    """Arguments holding NumPy arrays (which the environments take) made alike give the
    native batch (comparing them with == raised "truth value of an array is ambiguous")."""
    vec = make_vec_env(IDS[0], n_envs=2, vec_env_cls=from_env_fns, env_kwargs=kwargs)
    assert isinstance(vec, RollerVecEnv)
    differ = [lambda: gymnasium.make(IDS[0], **kwargs),
              lambda: gymnasium.make(IDS[0], info_keys=np.array(["phi"]))]
    assert isinstance(from_env_fns(differ), DummyVecEnv)


def test_from_env_fns_keeps_the_render_mode():
    """render_mode reaches the batch: frames as DummyVecEnv's (it was dropped: None)."""
    vec = make_vec_env(IDS[0], n_envs=2, vec_env_cls=from_env_fns,
                       env_kwargs={"render_mode": "rgb_array"})
    dummy = make_vec_env(IDS[0], n_envs=2, env_kwargs={"render_mode": "rgb_array"})
    assert isinstance(vec, RollerVecEnv) and vec.render_mode == "rgb_array"
    vec.seed(1), dummy.seed(1)
    vec.reset(), dummy.reset()
    for got, want in zip(vec.get_images(), dummy.get_images(), strict=True):
        np.testing.assert_array_equal(got, want)


def test_a_state_too_fast_and_an_unwritable_monitor_are_refused_naming_them():
    venv = RollerVecEnv("roller_gym/RollerHold-v2", n_envs=3)
    before = venv.get_attr("phi_dot")
    with pytest.raises(ValueError, match=r"set_attr\('phi_dot'.*sub-environment 0 would be "
                                         r"refused by a reset: .*phi_dot must be within"):
        venv.set_attr("phi_dot", 1e8, 0)
    np.testing.assert_array_equal(venv.get_attr("phi_dot"), before)
    with pytest.raises(ValueError, match=r"monitor='/proc/nonexistent/x' cannot be written"):
        RollerVecEnv("roller_gym/RollerHold-v2", n_envs=2, monitor="/proc/nonexistent/x")


def test_unknown_attributes_are_named_and_stay_attribute_errors():
    """SB3's has_attr catches AttributeError: a name the batch has not stays one, but says
    which call and which name; a name that is not a str is a TypeError saying so."""
    venv = RollerVecEnv("roller_gym/RollerHold-v2", n_envs=3)
    assert venv.has_attr("phi") and not venv.has_attr("nope")
    for call in (lambda: venv.get_attr("nope"), lambda: venv.env_method("nope")):
        with pytest.raises(AttributeError, match=r"\('nope'\): the native batch "
                                                 r"\(RollerVectorEnv\) has no attribute 'nope'"):
            call()
    with pytest.raises(TypeError, match=r"env_method\('phi_dot'\): the native batch's "
                                        r"'phi_dot' is not a method"):
        venv.env_method("phi_dot")
    for call in (lambda: venv.get_attr(5), lambda: venv.set_attr(5, 1),
                 lambda: venv.env_method(5)):
        with pytest.raises(TypeError, match=r"\(5.*the attribute's name must be a str, not int"):
            call()
