"""The single environments: registration, spaces, actions and observations, construction
arguments, the checkers of Gymnasium and Stable-Baselines3, pickling and SubprocVecEnv.

The documented numbers and the physics they are checked against are in ``env_cases``; reset,
seeding, info, reward and termination are in test_env_episodes.py.
"""

from __future__ import annotations

import functools
import math
import pickle
import subprocess
import sys
import warnings
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from env_cases import (
    DOCUMENTED,
    IDS,
    act,
    balances,
    check_info_physics,
    model,
    posable,
    psi_rate,
    randomizable,
)
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env as gym_check_env
from numba.core import event
from roller_gym import Scene, preset
from stable_baselines3.common.env_checker import check_env as sb3_check_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

ROOT = Path(__file__).resolve().parents[1]


def test_every_registered_task_has_its_documented_numbers_here():
    """A new task adds its documented numbers to DOCUMENTED, which the tests below check
    against the running environment."""
    assert set(DOCUMENTED) == set(roller_gym.ENV_IDS)


# -- 1. registration ---------------------------------------------------------------------
def test_import_registers_the_ids_and_the_namespace_form_imports_the_package():
    """In a fresh interpreter: nothing registered before; ``make("roller_gym:ID")`` imports
    the package, which registers all three with their time limits."""
    code = (
        "import gymnasium as gym\n"
        f"ids = {IDS!r}\n"
        "assert not any(i in gym.registry for i in ids)\n"
        "env = gym.make('roller_gym:roller_gym/RollerHold-v2')\n"
        "assert env.unwrapped.task.name == 'RollerHold'\n"
        "assert all(i in gym.registry for i in ids)\n"
        "print([gym.spec(i).max_episode_steps for i in ids])\n"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == str([DOCUMENTED[i]["steps"] for i in IDS])


@pytest.mark.parametrize("env_id", IDS)
def test_make_plain_and_namespaced(env_id):
    spec = gym.spec(env_id)
    assert spec.max_episode_steps == DOCUMENTED[env_id]["steps"]
    # A per-step reward in [0, 1] caps the return at the episode length.
    assert 0 < spec.reward_threshold <= spec.max_episode_steps
    for name in (env_id, f"roller_gym:{env_id}"):
        env = gym.make(name)
        assert env.spec.max_episode_steps == DOCUMENTED[env_id]["steps"]
        assert env.spec.reward_threshold == spec.reward_threshold
        assert isinstance(env.unwrapped, roller_gym.roller_env.RollerEnv)
        assert env.unwrapped.scene == preset(DOCUMENTED[env_id]["scene"])
        env.close()


# -- 2. spaces, actions, observations ----------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_spaces(env_id):
    env = gym.make(env_id)
    assert env.action_space == spaces.Box(-1.0, 1.0, (1,), np.float32)
    n = DOCUMENTED[env_id]["obs"]
    assert env.observation_space == spaces.Box(-1.0, 1.0, (n,), np.float32)
    obs, _ = env.reset(seed=0)
    assert obs.dtype == np.float32 and obs.shape == (n,)


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("max_torque", [None, 0.25])
def test_action_scales_to_torque_and_is_clipped(env_id, max_torque):
    kwargs = {} if max_torque is None else {"max_torque": max_torque}
    limit = DOCUMENTED[env_id]["max_torque"] if max_torque is None else max_torque
    env = gym.make(env_id, **kwargs)
    start = {"state": (0.05, 0.0)}
    for a in (0.3, -0.7, 1.0, -1.0, 2.5, -7.0, 0.0):
        env.reset(seed=1, options=start)
        obs, reward, _, _, info = env.step(act(a))
        assert info["torque"] == pytest.approx(float(np.clip(np.float32(a), -1, 1)) * limit,
                                               rel=1e-7, abs=0)
        if abs(a) > 1:  # clipped: the same step as the action at the bound
            env.reset(seed=1, options=start)
            obs_b, reward_b, _, _, info_b = env.step(act(math.copysign(1.0, a)))
            np.testing.assert_array_equal(obs, obs_b)
            assert reward == reward_b and info["phi"] == info_b["phi"]


@pytest.mark.parametrize("env_id", IDS)
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nonfinite_action_raises_and_leaves_the_state(env_id, bad):
    env = gym.make(env_id)
    env.reset(seed=0)
    before = (env.unwrapped.phi, env.unwrapped.phi_dot)
    with pytest.raises(ValueError, match="not finite"):
        env.step(np.array([bad], dtype=np.float32))
    assert (env.unwrapped.phi, env.unwrapped.phi_dot) == before


@pytest.mark.parametrize("env_id", IDS)
def test_observation_entries_match_the_state(env_id):
    """cos/sin ψ, cos/sin φ, tanh(φ'/10), and for Hold cos/sin ψ*, cos/sin φ*, with ψ
    recomputed from info["phi"] as rκφ/(1 − rκ) = rφ/(R − r)."""
    env = gym.make(env_id)
    obs, info = env.reset(seed=3)
    scene = env.unwrapped.scene
    q = psi_rate(scene)
    rng = np.random.default_rng(3)
    for t in range(12):
        phi, phi_dot = info["phi"], info["phi_dot"]
        psi = q * phi
        assert info["psi"] == pytest.approx(psi, rel=1e-12, abs=1e-15)
        assert env.observation_space.contains(obs)
        expected = [math.cos(psi), math.sin(psi), math.cos(phi), math.sin(phi),
                    math.tanh(phi_dot / 10.0)]
        fields = env.unwrapped.task.observation
        if "cos_psi_target" in fields:
            target = info["target_phi"]
            assert info["target_psi"] == pytest.approx(q * target, rel=1e-12)
            expected += [math.cos(q * target), math.sin(q * target), math.cos(target),
                         math.sin(target)]
        if "target_speed" in fields:
            expected += [math.tanh(info["target_phi_dot"] / 10.0)]
        np.testing.assert_allclose(obs, expected, rtol=0, atol=2e-7)
        if t < 11:
            obs, _, terminated, _, info = env.step(act(rng.uniform(-1, 1)))
            assert not terminated


# -- 3/4. construction arguments -----------------------------------------------------------
@pytest.mark.parametrize(
    ("env_id", "kwargs", "message"),
    [
        ("roller_gym/RollerStabilize-v2", {"dt": 0.0}, "dt=0.0"),
        ("roller_gym/RollerStabilize-v2", {"dt": -0.05}, "dt=-0.05"),
        ("roller_gym/RollerStabilize-v2", {"dt": math.inf}, "dt=inf"),
        ("roller_gym/RollerHold-v2", {"tolerance": math.nan}, "tolerance=nan"),
        ("roller_gym/RollerHold-v2", {"tolerance": 0.0}, "tolerance=0.0"),
        ("roller_gym/RollerStabilize-v2", {"integrator": "rk45"}, "integrator='rk45'"),
        ("roller_gym/RollerStabilize-v2", {"scene": "nope"}, "'nope'"),
        ("roller_gym/RollerStabilize-v2", {"scene": 3}, "scene=3"),
        ("roller_gym/RollerStabilize-v2", {"randomize": {"mass": (1.0, 2.0)}}, "'mass'"),
        ("roller_gym/RollerStabilize-v2", {"randomize": {"m": (2.0, 1.0)}},
         "randomize['m']=(2.0, 1.0)"),
        ("roller_gym/RollerStabilize-v2", {"randomize": {"m": (1.0,)}}, "randomize['m']=(1.0,)"),
        ("roller_gym/RollerStabilize-v2", {"randomize": {"m": (1.0, math.nan)}}, "randomize['m']"),
        ("roller_gym/RollerStabilize-v2", {"randomize": {"e": (-0.1, 0.05)}}, "Scene.e=-0.1"),
        ("roller_gym/RollerStabilize-v2", {"max_torque": 0.0}, "max_torque=0.0"),
        ("roller_gym/RollerStabilize-v2", {"max_torque": math.nan}, "max_torque=nan"),
        ("roller_gym/RollerStabilize-v2", {"substeps": 0}, "substeps=0"),
        ("roller_gym/RollerBalance-v2", {"scene": Scene(R=math.inf, e=0.0)},
         "no unstable rest position"),
        ("roller_gym/RollerBalance-v2", {"scene": "tight_fit"}, "no unstable rest position"),
        ("roller_gym/RollerBalance-v2", {"scene": "paper"}, "not reachable"),
    ],
)
def test_bad_construction_arguments_raise(env_id, kwargs, message):
    with pytest.raises(ValueError) as excinfo:
        gym.make(env_id, **kwargs)
    assert message in str(excinfo.value)


def test_bad_render_mode_raises():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Gymnasium warns about the mode as well
        with pytest.raises(ValueError, match="render_mode='ansi'"):
            gym.make("roller_gym/RollerStabilize-v2", render_mode="ansi")


@pytest.mark.parametrize("env_id", IDS)
def test_scene_argument_object_and_preset(env_id):
    custom = Scene(m=1.5, e=0.02, k=0.08) if not balances(env_id) else preset(
        "balance").replace(m=1.5)
    env = gym.make(env_id, scene=custom)
    assert env.unwrapped.scene == custom
    _, info = env.reset(seed=2)
    check_info_physics(env, info, 0.0)
    _, _, _, _, info = env.step(act(0.5))
    check_info_physics(env, info, info["torque"])
    name = "drum" if balances(env_id) else "floor"
    env = gym.make(env_id, scene=name)
    assert env.unwrapped.scene == preset(name)


def _reference(scene, phi, phi_dot, tau, dt):
    r = roller_gym.physics.step(scene, phi, phi_dot, tau, dt, integrator="dop853", tolerance=1e-13)
    return np.array([r.phi, r.phi_dot])


def test_dt_argument_sets_the_control_step():
    env = gym.make("roller_gym/RollerStabilize-v2", dt=0.02)
    env.reset(options={"state": (0.3, 0.0)})
    _, _, _, _, info = env.step(act(0.5))
    ref = _reference(env.unwrapped.scene, 0.3, 0.0, 0.25, 0.02)
    np.testing.assert_allclose([info["phi"], info["phi_dot"]], ref, rtol=0, atol=1e-8)
    assert abs(info["phi_dot"] - _reference(env.unwrapped.scene, 0.3, 0.0, 0.25, 0.05)[1]) > 0.1


@pytest.mark.parametrize(
    ("integrator", "tolerances"),
    [("rk4", (1e-4, 1e-9)), ("midpoint", (1e-4, 1e-8)), ("dop853", (1e-4, 1e-9)),
     ("rk8", (1e-4, 1e-10)),
     # Semi-implicit Euler (order 1) is capped by MAX_SUBSTEPS below ~1e-6 here.
     ("euler", (1e-3, 1e-5))],
)
def test_integrator_argument_and_tolerance(integrator, tolerances):
    """Each integrator meets its tolerance on one step against DOP853 at 1e-13, and a
    tighter tolerance takes more substeps."""
    if integrator not in roller_gym.physics.INTEGRATORS:
        pytest.skip(f"{integrator} is not an integrator here")
    scene = preset("paper")
    substeps = []
    for tol in tolerances:
        env = gym.make("roller_gym/RollerStabilize-v2", integrator=integrator, tolerance=tol)
        assert env.unwrapped.config.integrator == integrator
        env.reset(options={"state": (0.5, 2.0)})
        _, _, _, _, info = env.step(act(0.6))
        ref = _reference(scene, 0.5, 2.0, info["torque"], 0.05)
        err = np.abs(np.array([info["phi"], info["phi_dot"]]) - ref).max()
        assert err <= tol, (integrator, tol, err)
        substeps.append(info["substeps"])
    assert substeps[1] > substeps[0]


@pytest.mark.parametrize(("integrator", "substeps"), [("taylor", None), ("rk4", 1)])
def test_info_tol_met_is_the_integrators_flag(integrator, substeps):
    """info["tol_met"] of a step, in the single and the vector env, is what the integrator
    says of the same step taken alone (Stepper): True at the default tolerance with the
    automatic substeps, False with one fixed rk4 substep (which cannot meet it; fixed
    substeps inform, without a warning)."""
    from roller_gym.physics import Stepper

    scene, tol = preset("paper"), 1e-8
    kwargs = {"tolerance": tol, "integrator": integrator, "substeps": substeps}
    env = gym.make("roller_gym/RollerStabilize-v2", **kwargs)
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, **kwargs)
    env.reset(options={"state": (0.5, 2.0)})
    vec.reset(options={"state": (0.5, 2.0)})
    stepper = Stepper(scene, dt=0.05, **kwargs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        info = env.step(act(0.6))[4]
    warned = any("is not verified for some step" in str(w.message) for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        vinfo = vec.step(np.full((3, 1), 0.6, np.float32))[4]
        expected = stepper.advance(0.5, 2.0, info["torque"])[-1]
    assert expected == (substeps is None)
    assert not warned
    assert info["tol_met"] == expected and info["tol_met"].dtype == np.bool_
    np.testing.assert_array_equal(vinfo["tol_met"], [expected] * 3)


def test_a_loose_tolerance_steps_the_envs_at_its_degree():
    """At a tolerance the rule gives a lower Taylor degree, the single env (its fused
    one-roller kernel) and the vector env on one core and on all (their fused kernels) step
    as a Stepper of that degree does, bit for bit, and not as the default degree does."""
    from roller_gym.physics import Stepper, taylor
    from roller_gym.physics.integrators import PARALLEL_THRESHOLD

    tol, scene = 0.3, preset("paper")
    assert taylor.degree(tol) != taylor.ORDER
    env = gym.make("roller_gym/RollerStabilize-v2", tolerance=tol)
    env.reset(options={"state": (0.5, 2.0)})
    info = env.step(act(0.6))[4]
    got = [(env.unwrapped.phi, env.unwrapped.phi_dot)]
    for n in (3, PARALLEL_THRESHOLD):
        vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=n, tolerance=tol)
        vec.reset(options={"state": (0.5, 2.0)})
        vinfo = vec.step(np.full((n, 1), 0.6, np.float32))[4]
        got += list(zip(vinfo["phi"].tolist(), vinfo["phi_dot"].tolist(), strict=True))
        vec.close()
    ruled = Stepper(scene, dt=0.05, tolerance=tol).advance(0.5, 2.0, info["torque"])[:2]
    default = Stepper(scene, dt=0.05, tolerance=tol, degree=taylor.ORDER).advance(
        0.5, 2.0, info["torque"])[:2]
    assert ruled != default
    assert set(got) == {ruled}


def _accel(scene, phi, phi_dot, tau):
    return model(scene, phi, phi_dot, tau)["phi_ddot"]


@pytest.mark.parametrize(("integrator", "n"), [("rk4", 3), ("euler", 5)])
def test_substeps_argument_is_the_number_of_fixed_substeps(integrator, n):
    """With substeps=n the step is n steps of classical RK4 (or of semi-implicit Euler),
    written here on the φ'' of PHYSICS.md."""
    scene = preset("paper")
    env = gym.make("roller_gym/RollerStabilize-v2", integrator=integrator, substeps=n)
    env.reset(options={"state": (0.4, -1.0)})
    _, _, _, _, info = env.step(act(0.8))
    assert info["substeps"] == n
    phi, w, tau, h = 0.4, -1.0, info["torque"], 0.05 / n
    for _ in range(n):
        if integrator == "euler":
            w = w + h * _accel(scene, phi, w, tau)
            phi = phi + h * w
            continue
        k1p, k1w = w, _accel(scene, phi, w, tau)
        k2p, k2w = w + h / 2 * k1w, _accel(scene, phi + h / 2 * k1p, w + h / 2 * k1w, tau)
        k3p, k3w = w + h / 2 * k2w, _accel(scene, phi + h / 2 * k2p, w + h / 2 * k2w, tau)
        k4p, k4w = w + h * k3w, _accel(scene, phi + h * k3p, w + h * k3w, tau)
        phi = phi + h / 6 * (k1p + 2 * k2p + 2 * k3p + k4p)
        w = w + h / 6 * (k1w + 2 * k2w + 2 * k3w + k4w)
    assert info["phi"] == pytest.approx(phi, rel=0, abs=1e-12)
    assert info["phi_dot"] == pytest.approx(w, rel=0, abs=1e-11)


@pytest.mark.parametrize("env_id", IDS)
def test_randomize_draws_scenes_within_the_ranges(env_id):
    if not randomizable(env_id):
        pytest.skip("takes no randomize range (env_cases.randomizable): refused")
    ranges = {"m": (0.8, 1.2), "e": (0.06, 0.084)} if balances(env_id) else {
        "m": (0.8, 1.2), "e": (0.03, 0.05)}
    env = gym.make(env_id, randomize=ranges)
    base = preset(DOCUMENTED[env_id]["scene"])
    drawn = []
    for seed in range(6):
        _, info = env.reset(seed=seed)
        scene = env.unwrapped.scene
        for name, (low, high) in ranges.items():
            assert low <= float(getattr(scene, name)) <= high
        for name in ("r", "R", "k", "g", "mu", "damping"):
            assert getattr(scene, name) == getattr(base, name)
        check_info_physics(env, info, 0.0)  # the episode runs on the drawn scene
        drawn.append((float(scene.m), float(scene.e)))
    assert len(set(drawn)) == len(drawn)
    env.reset(seed=3)
    assert (float(env.unwrapped.scene.m), float(env.unwrapped.scene.e)) == drawn[3]


# -- 7. conformance, pickling, SubprocVecEnv -----------------------------------------------
CHECKED_KWARGS = [
    {}, {"scene": "floor"}, {"scene": "drum"}, {"render_mode": "rgb_array"},
    {"randomize": {"m": (0.8, 1.2), "k": (0.08, 0.12)}},
    *({"integrator": name} for name in ("rk8", "rk4", "midpoint")),
    # scipy's error control is relative to its own norm: at the default tolerance a step from
    # a far start (|φ| of several rad) may miss it absolutely, and says so (with a warning)
    {"integrator": "dop853", "tolerance": 1e-6},
    # first-order: at the default tolerance a step can need more than MAX_SUBSTEPS
    # substeps, and then says so (tol_met False, with a warning)
    {"integrator": "euler", "tolerance": 1e-4},
]


@pytest.mark.parametrize("kwargs", CHECKED_KWARGS, ids=repr)
@pytest.mark.parametrize("env_id", IDS)
def test_checkers_pass_without_warnings(env_id, kwargs, monkeypatch, tmp_path):
    """Gymnasium's and SB3's checkers on every task, on the floor and a drum, with every
    integrator, with domain randomization and with rendering."""
    if not posable(env_id, kwargs.get("scene", DOCUMENTED[env_id]["scene"])):
        pytest.skip("not posable there (env_cases.posable): refused at construction")
    if "randomize" in kwargs and not randomizable(env_id):
        pytest.skip("takes no randomize range (env_cases.randomizable): refused")
    pytest.importorskip("pygame", reason="Gymnasium's checker renders: the render extra")
    monkeypatch.setenv("SDL_VIDEODRIVER", "dummy")  # Gymnasium's checker also renders "human"
    monkeypatch.setenv("XDG_RUNTIME_DIR", str(tmp_path))
    env = gym.make(env_id, **kwargs)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gym_check_env(env.unwrapped)
        sb3_check_env(env, warn=True)
    assert not caught, [f"{w.category.__name__}: {w.message}" for w in caught]


@pytest.mark.parametrize("env_id", IDS)
def test_pickled_env_continues_the_same_episode(env_id):
    env = gym.make(env_id)
    env.reset(seed=9)
    env.step(act(0.3))
    copy = pickle.loads(pickle.dumps(env))
    for u in (0.5, -1.0, 0.25):
        a, b = env.step(act(u)), copy.step(act(u))
        np.testing.assert_array_equal(a[0], b[0])
        assert a[1:] == b[1:]
    np.testing.assert_array_equal(env.reset()[0], copy.reset()[0])  # the generator too


class _Compiles(event.Listener):
    """The names of the functions numba compiles while installed (loads from the disk cache
    are not compiles)."""

    def __init__(self) -> None:
        self.names: list[str] = []

    def on_start(self, ev) -> None:
        self.names.append(ev.data["dispatcher"].py_func.__qualname__)

    def on_end(self, ev) -> None:
        pass


def test_a_pickled_environment_runs_the_kernels_it_was_compiled_for():
    """Pickling copies the padded tables into compact ones, a layout of their own to numba:
    unpickled environments (a single one on the default scheme and on a fixed-substep one, a
    vector one through its autoresets) step and reset without compiling anything, and each
    task kernel has one signature."""
    envs = [gym.make(IDS[1]), gym.make(IDS[1], integrator="midpoint"),
            gym.make_vec(IDS[1], num_envs=3, max_episode_steps=5)]

    def run(env, seed):
        env.reset(seed=seed)
        for _ in range(12):  # past two autoresets of the vector env
            env.step(env.action_space.sample())
        env.reset(seed=seed + 1)  # a reset after observations were handed out

    for env in envs:
        run(env, 0)
    compiles = _Compiles()
    with event.install_listener("numba:compile", compiles):
        for env in envs:
            run(pickle.loads(pickle.dumps(env)), 1)
    assert compiles.names == []
    kernels = envs[0].unwrapped._outcome.kernels
    for kernel in (kernels.loop, *kernels.fused.values(), *kernels.one.values()):
        if hasattr(kernel, "signatures"):  # (not the parallel one: C functions, one signature)
            assert len(kernel.signatures) <= 1, (kernel.py_func.__qualname__, kernel.signatures)


@pytest.mark.parametrize("env_id", IDS)
def test_subproc_vec_env_matches_dummy_vec_env(env_id):
    """Two worker processes, each unpickling an environment made here, against DummyVecEnv
    under the same seeds and actions. ("fork" keeps the test quick: the default
    "forkserver" starts fresh interpreters that import torch; the env still crosses the
    pipe pickled.)"""
    blob = pickle.dumps(gym.make(env_id))
    sub = SubprocVecEnv([functools.partial(pickle.loads, blob)] * 2, start_method="fork")
    dummy = DummyVecEnv([functools.partial(gym.make, env_id)] * 2)
    try:
        sub.seed(7)
        dummy.seed(7)
        np.testing.assert_array_equal(sub.reset(), dummy.reset())
        actions = np.random.default_rng(1).uniform(-1, 1, (6, 2, 1)).astype(np.float32)
        for a in actions:
            obs_s, rew_s, done_s, info_s = sub.step(a)
            obs_d, rew_d, done_d, info_d = dummy.step(a)
            np.testing.assert_array_equal(obs_s, obs_d)
            np.testing.assert_allclose(rew_s, rew_d, rtol=1e-6)  # DummyVecEnv stores float32
            np.testing.assert_array_equal(done_s, done_d)
            assert [i["phi"] for i in info_s] == [i["phi"] for i in info_d]
            assert info_s[0]["phi"] != info_s[1]["phi"]  # seeds 7 and 8
    finally:
        sub.close()
        dummy.close()


def test_one_construction_signature_from_gym_make_down_to_the_physics():
    """RollerEnv, RollerVectorEnv and both entry points of every ID take the keywords of
    roller_gym.config.Settings, with its defaults and its documentation; the physics'
    steppers take the integrator and its tolerance under the same names."""
    import dataclasses
    import inspect

    from roller_gym.config import Settings, setting_docs
    from roller_gym.physics.integrators import BatchStepper, Stepper
    from roller_gym.roller_env import RollerEnv
    from roller_gym.vector_env import RollerVectorEnv

    declared = {f.name: f.default for f in dataclasses.fields(Settings)}
    spec = gym.spec("roller_gym/RollerStabilize-v2")
    for maker in (RollerEnv, RollerVectorEnv, spec.entry_point, spec.vector_entry_point):
        params = inspect.signature(maker).parameters
        assert {name: params[name].default for name in declared} == declared, maker
    for cls in (RollerEnv, RollerVectorEnv):
        assert setting_docs().strip() in cls.__doc__
    for stepper in (Stepper, BatchStepper):
        names = inspect.signature(stepper).parameters
        assert {"integrator", "tolerance", "dt", "substeps"} <= set(names)
    env = gym.make("roller_gym/RollerStabilize-v2", integrator="rk4", tolerance=1e-6)
    stepper = env.unwrapped._stepper
    assert (stepper.integrator, stepper.tolerance) == ("rk4", 1e-6)
    with pytest.raises(TypeError, match=r"'tol'.*allowed: num_envs, task, scene, dt, "):
        RollerVectorEnv(2, tol=1e-6)
