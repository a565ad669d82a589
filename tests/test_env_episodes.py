"""The single environments' episodes: reset and its options, seeding, the targets, the info
against the physics, the reward, success, termination and truncation.

The documented numbers and the physics they are checked against are in ``env_cases``.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from env_cases import (
    DOCUMENTED,
    IDS,
    act,
    balances,
    check_info_physics,
    model,
    posable,
    psi_rate,
)
from roller_gym import Scene, preset

INFO_KEYS = ("phi", "phi_dot", "psi", "torque", "normal_force", "friction_force", "energy",
             "substeps", "lifting", "slipping")


def near(x: float, margin: float) -> float:
    """The reward term of the docstrings: exp(ln(0.1) (x/m)²)."""
    return math.exp(math.log(0.1) * (x / margin) ** 2)


def documented_reward(env_id: str, scene: Scene, info: dict) -> float:
    """The reward of the task docstrings: (0.4 tolerance(ε, b, m) + 0.6 near(ε, 3b))
    (0.5 + 0.5 near(φ' − φ*', 5)) (0.8 + 0.2 near((τ − τ*)/max_torque, 1)), ε the distance
    within half the period of the pose either way (in rad of φ; Balance: to the nearer of
    ±φ_b), τ* = m g (r sin ψ* + e sin φ*). Swing's own: ((1 − w) near(E/E* − 1, margin) +
    w near(E/E* − 1, reach_margin)) (0.8 + 0.2 near(τ/max_torque, 1)), E* = V(φ*) of
    PHYSICS.md, m g ((R − r)(1 − cos ψ*) + e (1 − cos φ*))."""
    doc = DOCUMENTED[env_id]
    q = psi_rate(scene) or 1.0
    target = info["target_phi"]
    if "energy_margin" in doc:
        m, r, R, e, g = (float(getattr(scene, name)) for name in ("m", "r", "R", "e", "g"))
        e_star = m * g * ((R - r) * (1 - math.cos(q * target)) + e * (1 - math.cos(target)))
        x, w = info["energy"] / e_star - 1.0, doc["reach_weight"]
        return (((1 - w) * near(x, doc["energy_margin"]) + w * near(x, doc["reach_margin"]))
                * (0.8 + 0.2 * near(info["torque"] / doc["max_torque"], 1.0)))
    # the pose repeats after 2π/q where the roller turns 1/q whole times per turn of ψ; after
    # 2π where q is whole (the floor: q = 0); else never (no wrap)
    turns = 1.0 / abs(q)
    period = (2 * math.pi / abs(q) if abs(turns - round(turns)) < 1e-9 * turns
              else 2 * math.pi if abs(abs(q) - round(abs(q))) < 1e-9 * abs(q) or q == 0
              else math.inf)

    def error(t):
        x = info["phi"] - t
        return x if math.isinf(period) else (x + period / 2) % period - period / 2

    eps = error(target)
    if balances(env_id):
        eps = min((error(target), error(-target)), key=abs)
    band = doc["band"]

    def tolerance(x, margin):
        return 1.0 if abs(x) <= band else near(abs(x) - band, margin)

    m, r, e, g = (float(getattr(scene, name)) for name in ("m", "r", "e", "g"))
    holding = m * g * (r * math.sin(psi_rate(scene) * target) + e * math.sin(target))
    position = 0.4 * tolerance(eps, doc["margin"]) + 0.6 * near(eps, 3 * band)
    return (position * (0.5 + 0.5 * near(info["phi_dot"] - info["target_phi_dot"], 5.0))
            * (0.8 + 0.2 * near((info["torque"] - holding) / doc["max_torque"], 1.0)))


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
    scene = preset("drum") if balances(env_id) else Scene(m=2.0, e=0.02)
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
    + [(i, s) for i in IDS if not balances(i)
       for s in ("floor", "drum", "rim_mass") if posable(i, s)],
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
    # (2 N·m holds every start of the range on the drum: at less, some are pushed off)
    env = gym.make("roller_gym/RollerStabilize-v2", scene=scene, max_torque=2.0)
    _, info = env.reset(seed=0, options={"state": (0.0, 23.0)})
    assert model(scene, 0.0, 23.0, 0.0)["normal"] > 0
    assert not info["lifting"] and info["normal_force"] > 0
    _, _, terminated, truncated, info = env.step(act(1.0))
    assert terminated and not truncated and info["lifting"] and not info["nonfinite"]
    assert info["liftoff_margin"] <= 0


def test_reset_refuses_a_start_state_that_does_not_roll():
    """At φ' = 30 rad/s on top of the drum N < 0 (PHYSICS.md): no episode can start there."""
    scene = Scene(R=-0.5, e=0.0, k=0.07, mu=100.0)  # (holding every start: as above)
    assert model(scene, 0.0, 30.0, 0.0)["normal"] < 0
    env = gym.make("roller_gym/RollerStabilize-v2", scene=scene, max_torque=2.0)
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
