"""The single environments: registration, spaces, reset and step, info, errors,
construction arguments, the checkers of Gymnasium and Stable-Baselines3, pickling and
SubprocVecEnv.

The independent source for the physics is :func:`model`, written here from
``docs/PHYSICS.md`` in its cylinder form (R − r, not the code's curvature form); the
documented numbers (episode lengths, default torques, observation layout, reward) are
copied from the docstrings of ``envs/__init__.py`` and the task modules.
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
from gymnasium import spaces
from gymnasium.utils.env_checker import check_env as gym_check_env
from roller_gym import Scene, preset
from stable_baselines3.common.env_checker import check_env as sb3_check_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

ROOT = Path(__file__).resolve().parents[1]

# From the docstrings: steps per episode, default max_torque [N·m], observation size,
# default preset.
DOCUMENTED = {
    "roller_gym/RollerStabilize-v2": {"steps": 200, "max_torque": 0.5, "obs": 5, "scene": "paper",
                                      "band": 0.05, "margin": 2.0},
    "roller_gym/RollerHold-v2": {"steps": 200, "max_torque": 1.0, "obs": 9, "scene": "paper",
                                 "band": 0.05, "margin": 2.0},
    "roller_gym/RollerBalance-v2": {"steps": 400, "max_torque": 0.4, "obs": 5, "scene": "balance",
                                    "band": 0.1, "margin": 3.0},
    "roller_gym/RollerTrack-v1": {"steps": 400, "max_torque": 1.0, "obs": 10, "scene": "paper",
                                  "band": 0.05, "margin": 1.0},
    # an objective of its own: the relative energy error's band and margin
    "roller_gym/RollerSwing-v0": {"steps": 400, "max_torque": 0.1, "obs": 9, "scene": "paper",
                                  "energy_band": 0.1, "energy_margin": 0.4},
    "roller_gym/RollerHoldRandomized-v0": {"steps": 200, "max_torque": 1.0, "obs": 9,
                                           "scene": "paper", "band": 0.05, "margin": 2.0},
}
IDS = list(roller_gym.ENV_IDS)


def test_every_registered_task_has_its_documented_numbers_here():
    """A new task adds its documented numbers to DOCUMENTED, which the tests below check
    against the running environment."""
    assert set(DOCUMENTED) == set(roller_gym.ENV_IDS)
INFO_KEYS = ("phi", "phi_dot", "psi", "torque", "normal_force", "friction_force", "energy",
             "substeps", "lifting", "slipping")


# -- the physics, from PHYSICS.md ------------------------------------------------------
def model(scene: Scene, phi: float, phi_dot: float, tau: float) -> dict[str, float]:
    """ψ, θ, φ'', N, F, E of PHYSICS.md at (φ, φ') under τ (the presets have no damping).

    Written in the cylinder form with R − r; the floor (R = inf) is its limit (the terms
    with 1/(R − r) or (R − r)(1 − cos ψ) vanish, r R/(R − r) → r).
    """
    m, r, R, e, k, g = (float(getattr(scene, name)) for name in ("m", "r", "R", "e", "k", "g"))
    assert float(scene.damping) == 0.0
    floor = math.isinf(R)
    psi = 0.0 if floor else r * phi / (R - r)
    theta = phi if floor else R * phi / (R - r)
    coriolis = e * r if floor else e * r * R / (R - r)
    phi_ddot = (
        tau / m - coriolis * phi_dot**2 * math.sin(theta)
        - g * (r * math.sin(psi) + e * math.sin(phi))
    ) / (k**2 + e**2 + r**2 - 2 * e * r * math.cos(theta))
    centripetal = 0.0 if floor else r**2 / (R - r)
    normal = m * (g * math.cos(psi) + centripetal * phi_dot**2
                  + e * (phi_ddot * math.sin(theta) + phi_dot**2 * math.cos(theta)))
    friction = m * (g * math.sin(psi) + (r - e * math.cos(theta)) * phi_ddot
                    + e * phi_dot**2 * math.sin(theta))
    j_i = m * (k**2 + r**2 + e**2 - 2 * r * e * math.cos(theta))
    height = 0.0 if floor else (R - r) * (1 - math.cos(psi))
    energy = 0.5 * j_i * phi_dot**2 + m * g * (height + e * (1 - math.cos(phi)))
    return {"psi": psi, "theta": theta, "phi_ddot": phi_ddot, "normal": normal,
            "friction": friction, "energy": energy}


def psi_rate(scene: Scene) -> float:
    """dψ/dφ = r/(R − r) (0 on the floor)."""
    R, r = float(scene.R), float(scene.r)
    return 0.0 if math.isinf(R) else r / (R - r)


def near(x: float, margin: float) -> float:
    """The reward term of the docstrings: exp(ln(0.1) (x/m)²)."""
    return math.exp(math.log(0.1) * (x / margin) ** 2)


def wrap(x: float) -> float:
    return (x + math.pi) % (2 * math.pi) - math.pi


def documented_reward(env_id: str, scene: Scene, info: dict) -> float:
    """The reward of the task docstrings: (0.4 tolerance(ε, b, m) + 0.6 near(ε, 3b))
    (0.5 + 0.5 near(φ' − φ*', 5)) (0.8 + 0.2 near((τ − τ*)/max_torque, 1)), ε one turn of ψ
    either way (in rad of φ; Balance: to the nearer of ±φ_b), τ* = m g (r sin ψ* + e sin φ*).
    Swing's own: near(E/E* − 1, margin) (0.8 + 0.2 near(τ/max_torque, 1)), E* = V(φ*) of
    PHYSICS.md, m g ((R − r)(1 − cos ψ*) + e (1 − cos φ*))."""
    doc = DOCUMENTED[env_id]
    q = psi_rate(scene) or 1.0
    target = info["target_phi"]
    if "energy_margin" in doc:
        m, r, R, e, g = (float(getattr(scene, name)) for name in ("m", "r", "R", "e", "g"))
        e_star = m * g * ((R - r) * (1 - math.cos(q * target)) + e * (1 - math.cos(target)))
        return (near(info["energy"] / e_star - 1.0, doc["energy_margin"])
                * (0.8 + 0.2 * near(info["torque"] / doc["max_torque"], 1.0)))

    def error(t):
        return wrap(q * (info["phi"] - t)) / q

    eps = error(target)
    if env_id == "roller_gym/RollerBalance-v2":
        eps = min((error(target), error(-target)), key=abs)
    band = doc["band"]

    def tolerance(x, margin):
        return 1.0 if abs(x) <= band else near(abs(x) - band, margin)

    m, r, e, g = (float(getattr(scene, name)) for name in ("m", "r", "e", "g"))
    holding = m * g * (r * math.sin(psi_rate(scene) * target) + e * math.sin(target))
    position = 0.4 * tolerance(eps, doc["margin"]) + 0.6 * near(eps, 3 * band)
    return (position * (0.5 + 0.5 * near(info["phi_dot"] - info["target_phi_dot"], 5.0))
            * (0.8 + 0.2 * near((info["torque"] - holding) / doc["max_torque"], 1.0)))


def act(a: float) -> np.ndarray:
    return np.array([a], dtype=np.float32)


def check_info_physics(env, info: dict, tau: float) -> None:
    """The info's state, ψ, forces and energy against :func:`model` at that state."""
    scene = env.unwrapped.scene
    ref = model(scene, info["phi"], info["phi_dot"], tau)
    weight = float(scene.m * scene.g)
    assert info["psi"] == pytest.approx(ref["psi"], rel=1e-12, abs=1e-12)
    assert info["normal_force"] == pytest.approx(ref["normal"], rel=1e-9, abs=1e-9 * weight)
    assert info["friction_force"] == pytest.approx(ref["friction"], rel=1e-9, abs=1e-9 * weight)
    assert info["energy"] == pytest.approx(ref["energy"], rel=1e-9, abs=1e-12)


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


# -- 3. reset, seeding, info, termination ------------------------------------------------
@pytest.mark.parametrize("env_id", IDS)
def test_same_seed_same_episode(env_id):
    a, b = gym.make(env_id), gym.make(env_id)
    actions = np.random.default_rng(0).uniform(-1, 1, 25)
    episodes = []
    for env in (a, b, a):  # the third run re-seeds an env that has already been used
        obs, info = env.reset(seed=42)
        run = [(obs, 0.0, info)]
        for u in actions:
            obs, reward, terminated, truncated, info = env.step(act(u))
            run.append((obs, reward, info))
            assert not (terminated or truncated)
        episodes.append(run)
    for other in episodes[1:]:
        for (o1, r1, i1), (o2, r2, i2) in zip(episodes[0], other, strict=True):
            np.testing.assert_array_equal(o1, o2)
            assert r1 == r2 and i1 == i2
    first = [a.reset(seed=s)[1]["phi"] for s in range(4)]
    assert len(set(first)) == 4  # and different seeds, different starts


@pytest.mark.parametrize("env_id", IDS)
def test_reset_options_state_and_scene(env_id):
    env = gym.make(env_id)
    obs, info = env.reset(seed=0, options={"state": (0.2, -0.3)})
    assert (info["phi"], info["phi_dot"]) == (0.2, -0.3)
    assert (env.unwrapped.phi, env.unwrapped.phi_dot) == (0.2, -0.3)
    assert obs[2] == pytest.approx(math.cos(0.2), abs=1e-7)
    scene = preset("drum") if env_id == "roller_gym/RollerBalance-v2" else Scene(m=2.0, e=0.02)
    obs, info = env.reset(seed=0, options={"scene": scene, "state": (0.1, 0.0)})
    assert env.unwrapped.scene == scene
    assert info["psi"] == pytest.approx(psi_rate(scene) * 0.1, rel=1e-12)
    check_info_physics(env, info, 0.0)
    obs, info = env.reset(seed=0, options={"scene": "floor", "state": (0.3, 0.0)})
    assert env.unwrapped.scene == preset("floor")
    assert info["psi"] == 0.0 and obs[0] == 1.0 and obs[1] == 0.0  # ψ stays 0 on the floor
    env.reset(seed=0)  # options are per episode: back to the base scene (or its ranges)
    ranges = env.unwrapped.task.scene_ranges or {}
    drawn = env.unwrapped.scene
    assert drawn.replace(**{f: getattr(preset(DOCUMENTED[env_id]["scene"]), f) for f in ranges}
                         ) == preset(DOCUMENTED[env_id]["scene"])
    assert all(low <= getattr(drawn, f) <= high for f, (low, high) in ranges.items())
    for bad in ({"speed": 1.0}, {"state": (0.1,)}, {"state": ("a", 0.0)},
                {"state": (math.nan, 0.0)}, {"scene": "nope"}):
        with pytest.raises(ValueError):
            env.reset(options=bad)


def test_reset_option_target_hold():
    env = gym.make("roller_gym/RollerHold-v2")
    scene = env.unwrapped.scene
    q = psi_rate(scene)
    obs, info = env.reset(seed=0, options={"target": 0.2})
    assert info["target_psi"] == pytest.approx(0.2, rel=1e-12)
    assert info["target_phi"] == pytest.approx(0.2 / q, rel=1e-12)  # 0.8 rad on "paper"
    np.testing.assert_allclose(obs[5:], [math.cos(0.2), math.sin(0.2), math.cos(0.8),
                                         math.sin(0.8)], atol=2e-7)
    with pytest.raises(ValueError, match=r"options\['target'\]=2\.0"):
        env.reset(options={"target": 2.0})
    assert env.reset(seed=0, options={"target": np.array(0.2)})[1]["target_psi"] == \
        info["target_psi"]  # a 0-d array is a number
    for bad in ("0.2", True, math.nan):  # text and bools are not numbers here
        with pytest.raises(ValueError, match=r"options\['target'\]=.* must be a finite real"):
            env.reset(options={"target": bad})
    for other in ("roller_gym/RollerStabilize-v2", "roller_gym/RollerBalance-v2"):
        with pytest.raises(ValueError, match="target"):
            gym.make(other).reset(options={"target": 0.1})


def test_hold_targets_can_be_held():
    """Each drawn target is a rest position whose holding torque m g (r sin ψ + e sin φ)
    is at most 80% of max_torque and whose friction at rest, |tan ψ|, at most 90% of μ."""
    env = gym.make("roller_gym/RollerHold-v2")
    scene = env.unwrapped.scene
    m, r, e, g, mu = (float(getattr(scene, n)) for n in ("m", "r", "e", "g", "mu"))
    targets = []
    for seed in range(20):
        _, info = env.reset(seed=seed)
        phi, psi = info["target_phi"], info["target_psi"]
        assert abs(m * g * (r * math.sin(psi) + e * math.sin(phi))) <= 0.8 * 1.0 + 1e-9
        assert abs(math.tan(psi)) <= 0.9 * mu + 1e-9
        targets.append(phi)
    assert min(targets) < -0.5 and max(targets) > 0.5  # the range is used, both sides


def test_balance_target_is_the_unstable_rest_position():
    """Documented: ψ ≈ ±23°, φ ≈ ±3.66 rad in "balance"; at rest there φ'' = 0 at zero
    torque, d²V/dφ² < 0 (unstable) and the roller still rolls (N > 0, |F| <= μN)."""
    env = gym.make("roller_gym/RollerBalance-v2")
    _, info = env.reset(seed=0)
    scene = env.unwrapped.scene
    phi_b = info["target_phi"]
    assert phi_b == pytest.approx(3.66, abs=0.01)
    assert math.degrees(info["target_psi"]) == pytest.approx(23.0, abs=1.0)
    ref = model(scene, phi_b, 0.0, 0.0)
    assert abs(ref["phi_ddot"]) < 1e-9
    r, R, e = float(scene.r), float(scene.R), float(scene.e)
    assert r**2 / (R - r) * math.cos(ref["psi"]) + e * math.cos(phi_b) < 0
    assert ref["normal"] > 0 and abs(ref["friction"]) <= float(scene.mu) * ref["normal"]
    # Either of ±φ_b counts: at rest at −φ_b the error is 0 and the episode a success.
    _, info = env.reset(seed=0, options={"state": (-phi_b, 0.0)})
    assert info["position_error"] == pytest.approx(0.0, abs=1e-12) and info["is_success"]


@pytest.mark.parametrize(
    ("env_id", "scene_name"),
    [(i, "default") for i in IDS]
    + [(i, s) for i in IDS if i != "roller_gym/RollerBalance-v2"
       for s in ("floor", "drum", "rim_mass")],
)
def test_info_forces_and_energy_follow_physics(env_id, scene_name):
    """N, F and E in the info against the formulas of PHYSICS.md, at the reset (τ = 0) and
    after each step (at the end state under the step's τ); the energy balance over a step
    at constant τ: ΔE = τ Δφ. Flags agree with the contact at the end of each step."""
    kwargs = {} if scene_name == "default" else {"scene": scene_name}
    env = gym.make(env_id, **kwargs)
    _, info = env.reset(seed=5)
    assert set(INFO_KEYS) <= set(info)
    assert info["torque"] == 0.0 and info["substeps"] == 0
    check_info_physics(env, info, 0.0)
    scene = env.unwrapped.scene
    mu = float(scene.mu)
    rng = np.random.default_rng(5)
    for _ in range(15):
        before = info
        _, _, terminated, _, info = env.step(act(rng.uniform(-1, 1)))
        tau = info["torque"]
        check_info_physics(env, info, tau)
        assert info["energy"] - before["energy"] == pytest.approx(
            tau * (info["phi"] - before["phi"]), abs=1e-8)
        assert isinstance(info["substeps"], np.int64) and info["substeps"] >= 1
        n, f = info["normal_force"], info["friction_force"]
        if n <= 0:
            assert info["lifting"]
        if abs(f) > mu * n:
            assert info["slipping"]
        assert terminated == (info["lifting"] or info["slipping"] or info["nonfinite"])
        if terminated:
            break


@pytest.mark.parametrize("env_id", IDS)
def test_reward_is_the_documented_formula(env_id):
    env = gym.make(env_id)
    _, info = env.reset(seed=11)
    scene = env.unwrapped.scene
    for a in (0.4, -0.9, 0.0, 1.0, 3.0, -0.2, 0.7, -2.0):
        _, reward, terminated, _, info = env.step(act(a))
        expected = documented_reward(env_id, scene, info)
        assert reward == pytest.approx(expected, rel=1e-12, abs=1e-15)
        assert 0.0 <= reward <= 1.0 and not terminated


def test_success_flag_is_the_documented_band():
    env = gym.make("roller_gym/RollerStabilize-v2")
    assert env.reset(options={"state": (0.0, 0.0)})[1]["is_success"]
    assert env.reset(options={"state": (0.04, -0.09)})[1]["is_success"]
    assert not env.reset(options={"state": (0.06, 0.0)})[1]["is_success"]
    assert not env.reset(options={"state": (0.0, 0.11)})[1]["is_success"]


def test_terminated_when_the_roller_slips():
    """μ = 0.3: it rolls at rest at the bottom under full torque (|F| <= μN by PHYSICS.md),
    but driven up the wall at full torque it needs more friction than μN and slips."""
    scene = preset("paper").replace(mu=0.3)
    ref = model(scene, 0.0, 0.0, 0.5)
    assert abs(ref["friction"]) < 0.3 * ref["normal"]  # the precondition, independently
    env = gym.make("roller_gym/RollerStabilize-v2", scene=scene)
    _, info = env.reset(seed=0, options={"state": (0.0, 0.0)})
    assert not info["slipping"]
    for _ in range(60):
        before = info
        _, _, terminated, truncated, info = env.step(act(1.0))
        if terminated:
            break
    assert terminated and not truncated
    assert info["slipping"] and not info["lifting"] and info["slip_margin"] < 0
    start = model(scene, before["phi"], before["phi_dot"], 0.5)
    assert abs(start["friction"]) <= 0.3 * start["normal"]  # it rolled when the step began
    end = model(scene, info["phi"], info["phi_dot"], 0.5)
    assert abs(end["friction"]) > 0.3 * end["normal"]  # and slips at its end


def test_terminated_when_the_roller_lifts_off():
    """A disc (e = 0) on top of a drum of radius 0.5 m: N/m = g cos ψ − r²/(|R| + r) φ'² by
    PHYSICS.md. At φ' = 23 rad/s it still rolls on top (N > 0); driven faster, it leaves
    the drum during the step (μ large, so it cannot slip first)."""
    scene = Scene(R=-0.5, e=0.0, k=0.07, mu=100.0)
    env = gym.make("roller_gym/RollerStabilize-v2", scene=scene)
    _, info = env.reset(seed=0, options={"state": (0.0, 23.0)})
    assert model(scene, 0.0, 23.0, 0.0)["normal"] > 0
    assert not info["lifting"] and info["normal_force"] > 0
    _, _, terminated, truncated, info = env.step(act(1.0))
    assert terminated and not truncated and info["lifting"] and not info["nonfinite"]
    assert info["liftoff_margin"] <= 0


def test_reset_refuses_a_start_state_that_does_not_roll():
    """At φ' = 30 rad/s on top of the drum N < 0 (PHYSICS.md): no episode can start there."""
    scene = Scene(R=-0.5, e=0.0, k=0.07)
    assert model(scene, 0.0, 30.0, 0.0)["normal"] < 0
    env = gym.make("roller_gym/RollerStabilize-v2", scene=scene)
    with pytest.raises(ValueError, match=r"options\['state'\]=\(0.0, 30.0\).*does not roll"):
        env.reset(seed=0, options={"state": (0.0, 30.0)})
    # (4π, 0) on the paper scene: ψ = π, the top of the cylinder, at rest.
    with pytest.raises(ValueError, match="does not roll"):
        gym.make("roller_gym/RollerStabilize-v2").reset(options={"state": (4 * math.pi, 0.0)})


@pytest.mark.parametrize("env_id", IDS)
def test_truncated_by_the_time_limit(env_id):
    """At rest at the bottom with no torque nothing happens until the documented limit."""
    env = gym.make(env_id)
    env.reset(seed=0, options={"state": (0.0, 0.0)})
    steps = DOCUMENTED[env_id]["steps"]
    for t in range(1, steps + 1):
        _, _, terminated, truncated, info = env.step(act(0.0))
        assert not terminated
        assert truncated == (t == steps), t
    assert abs(info["phi"]) < 1e-12
    short = gym.make(env_id, max_episode_steps=3)
    short.reset(seed=0)
    flags = [short.step(act(0.0))[3] for _ in range(3)]
    assert flags == [False, False, True]


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
    custom = Scene(m=1.5, e=0.02, k=0.08) if env_id != "roller_gym/RollerBalance-v2" else preset(
        "balance").replace(m=1.5)
    env = gym.make(env_id, scene=custom)
    assert env.unwrapped.scene == custom
    _, info = env.reset(seed=2)
    check_info_physics(env, info, 0.0)
    _, _, _, _, info = env.step(act(0.5))
    check_info_physics(env, info, info["torque"])
    name = "drum" if env_id == "roller_gym/RollerBalance-v2" else "floor"
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


@pytest.mark.parametrize("tol", [1e-8, 1e-15])
def test_info_tol_met_is_the_integrators_flag(tol):
    """info["tol_met"] of a step, in the single and the vector env, is what the integrator
    says of the same step taken alone (Stepper): True at a reachable tolerance, False (with
    a warning) at one below float64's reach."""
    from roller_gym.physics import Stepper

    scene = preset("paper")
    env = gym.make("roller_gym/RollerStabilize-v2", tolerance=tol)
    vec = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=3, tolerance=tol)
    env.reset(options={"state": (0.5, 2.0)})
    vec.reset(options={"state": (0.5, 2.0)})
    stepper = Stepper(scene, dt=0.05, tolerance=tol)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", RuntimeWarning)
        info = env.step(act(0.6))[4]
    warned = any("is out of reach for some step" in str(w.message) for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        vinfo = vec.step(np.full((3, 1), 0.6, np.float32))[4]
        expected = stepper.advance(0.5, 2.0, info["torque"])[-1]
    assert expected == (tol > 1e-12)
    assert warned == (not expected)
    assert info["tol_met"] == expected and info["tol_met"].dtype == np.bool_
    np.testing.assert_array_equal(vinfo["tol_met"], [expected] * 3)


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
    ranges = {"m": (0.8, 1.2), "e": (0.06, 0.09)} if env_id == "roller_gym/RollerBalance-v2" else {
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
    *({"integrator": name} for name in ("rk8", "rk4", "midpoint", "dop853")),
    # first-order: at the default tolerance a step can need more than MAX_SUBSTEPS
    # substeps, and then says so (tol_met False, with a warning)
    {"integrator": "euler", "tolerance": 1e-4},
]


@pytest.mark.parametrize("kwargs", CHECKED_KWARGS, ids=repr)
@pytest.mark.parametrize("env_id", IDS)
def test_checkers_pass_without_warnings(env_id, kwargs, monkeypatch, tmp_path):
    """Gymnasium's and SB3's checkers on every task, on the floor and a drum, with every
    integrator, with domain randomization and with rendering."""
    if env_id.startswith("roller_gym/RollerBalance") and "scene" in kwargs:
        pytest.skip("Balance needs an unstable rest position that rolls (not on floor, drum)")
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
    with pytest.raises(TypeError, match=r"'tol'.*allowed: scene, dt"):
        RollerVectorEnv(2, tol=1e-6)
