"""The task registry: what a task declares is what the environments do, and a new task
needs the registry alone. RollerTrack's moving target, checked independently."""

from __future__ import annotations

import importlib
import math
import re
from typing import ClassVar

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
import roller_gym.config
from gymnasium.envs.registration import register as gym_register
from gymnasium.vector import SyncVectorEnv
from roller_gym.agents import controller_for, rollout
from roller_gym.physics import Scene, contact, energy, holding_torque
from roller_gym.task import (
    OBSERVATION_FIELDS,
    PRECISION_MARGIN,
    START_TURNS,
    TASKS,
    Task,
    angle_rate,
    hold_range,
    hold_ranges,
    register,
)

TASK_CLASSES = list(TASKS.values())


def docstring_table(module) -> list[tuple[int, str]]:
    """(index, field) rows of the observation table in a task module's docstring."""
    return [(int(i), f) for i, f in re.findall(r"^(\d+)\s+``(\w+)``", module.__doc__, re.M)]


@pytest.mark.parametrize("task", TASK_CLASSES, ids=lambda t: t.name)
def test_docstring_table_is_the_declared_observation(task):
    module = importlib.import_module(task.__module__)
    assert docstring_table(module) == list(enumerate(task.observation))
    assert f"``Box(-1, 1, ({len(task.observation)},), float32)``" in module.__doc__
    assert f"roller_gym/{task.name}-v{task.version}" in module.__doc__.splitlines()[0]
    # every ID of the task the text names, but in its version history, is the current one
    text = module.__doc__.split("## Version History")[0]
    assert set(re.findall(rf"roller_gym/{task.name}-v\d+", text)) == {task.env_id()}


@pytest.mark.parametrize("task", TASK_CLASSES, ids=lambda t: t.name)
def test_docstring_reward_and_success_are_the_declared_numbers(task):
    """The reward formula and success band each task module states carry the task's own
    band, margins and weights (the formula itself is checked in test_env_episodes); a task with an
    objective of its own states each of its numbers."""
    doc = importlib.import_module(task.__module__).__doc__
    if task.reward is not Task.reward:
        numbers = [n for n in task.parameters if n not in ("max_torque", "symmetric_target",
                                                            "observes_target")]
        for name in numbers:
            assert f"{getattr(task, name):g}" in doc, name
        assert "## Version History" in doc
        return
    band, margin = task.success_band, task.position_margin
    w = task.precision_weight
    stated = (f"``({1 - w:g} tolerance(ε, {band:g} rad, {margin:g} rad) + {w:g} "
              f"near(ε, {PRECISION_MARGIN * band:.3g} rad))")
    assert f"* v{task.version}: " in doc.split("## Version History")[1]
    assert stated in " ".join(doc.split()), stated
    assert (f"(0.5 + 0.5 near(φ' − φ*', {task.speed_margin:g} rad/s))" in doc
            and task.speed_weight == 0.5 and task.control_weight == 0.2)
    assert f"|ε| <= {band:g} rad" in doc and f"<= {task.success_speed:g} rad/s" in doc


@pytest.mark.parametrize("task", TASK_CLASSES, ids=lambda t: t.name)
def test_every_registered_task_is_a_gymnasium_id_with_its_declarations(task):
    assert task.env_id() in roller_gym.ENV_IDS
    spec = gym.spec(task.env_id())
    assert spec.max_episode_steps == task.max_episode_steps
    assert spec.reward_threshold == task.reward_threshold
    env = gym.make(task.env_id())
    assert type(env.unwrapped.task) is task
    assert env.observation_space.shape == (len(task.observation),)
    vec = gym.make_vec(task.env_id(), num_envs=2)
    assert type(vec.unwrapped.task) is task  # make_vec passes the spec's task= on
    obs, _ = env.reset(seed=0)
    for field in task.observation:  # every field decodes by name, inside [-1, 1]
        assert -1.0 <= obs[task.index(field)] <= 1.0


def test_the_registry_refuses_a_duplicate_name_and_unknown_fields():
    with pytest.raises(ValueError, match="registered already"):
        register(type("Again", (Task,), {"name": "RollerHold"}))
    with pytest.raises(ValueError, match="unknown fields"):
        register(type("Odd", (Task,), {"name": "RollerOdd", "observation": ("cos_psi", "x")}))
    assert "RollerOdd" not in TASKS
    with pytest.raises(ValueError, match="not a registered task"):
        gym.make("roller_gym/RollerHold-v2", task="RollerNope")


def test_a_new_task_through_the_registry_alone():
    """A fourth static task declared here (rest at φ* = 0.3 rad with a narrower band): one
    class and one Gymnasium registration with the generic entry points; the single and
    the native vector environment serve it, and the vector one matches SyncVectorEnv."""

    class OffsetTask(Task):
        name = "RollerOffsetTest"
        reward_threshold = 100.0
        success_band: ClassVar[float] = 0.02

        def sample_targets(self, u, scene):
            return np.full(np.shape(u), 0.3)

    register(OffsetTask)
    try:
        gym_register(id=OffsetTask.env_id(), entry_point="roller_gym.roller_env:RollerEnv",
                     vector_entry_point="roller_gym.vector_env:RollerVectorEnv",
                     max_episode_steps=50, kwargs={"task": OffsetTask.name})
        env = gym.make(OffsetTask.env_id())
        _, info = env.reset(seed=0, options={"state": (0.31, 0.0)})
        assert info["target_phi"] == 0.3 and info["is_success"]
        native = gym.make_vec(OffsetTask.env_id(), num_envs=3)
        sync = SyncVectorEnv([lambda: gym.make(OffsetTask.env_id())] * 3)
        np.testing.assert_array_equal(native.reset(seed=4)[0], sync.reset(seed=4)[0])
        a = np.full((3, 1), 0.2, np.float32)
        np.testing.assert_array_equal(native.step(a)[0], sync.step(a)[0])
    finally:
        TASKS.pop(OffsetTask.name, None)
        gym.registry.pop(OffsetTask.env_id(), None)


def test_observation_fields_are_declared_once():
    declared = set(OBSERVATION_FIELDS)
    used = {f for task in TASK_CLASSES for f in task.observation}
    assert used <= declared


# -- RollerTrack ---------------------------------------------------------------------------
TRACK = "roller_gym/RollerTrack-v1"


def test_track_target_moves_smoothly_inside_the_holdable_range():
    """Over 20 seeded episodes: the target stays in the holdable range, it moves, and the
    reported rate φ*' is its time derivative (central differences of the reported φ*)."""
    env = gym.make(TRACK)
    dt = env.unwrapped.config.dt
    low, high = hold_range(env.unwrapped.scene, env.unwrapped.task.max_torque)
    for seed in range(20):
        _, info = env.reset(seed=seed)
        targets, rates = [info["target_phi"]], [info["target_phi_dot"]]
        for _ in range(400):
            _, _, terminated, truncated, info = env.step(np.zeros(1, np.float32))
            targets.append(info["target_phi"])
            rates.append(info["target_phi_dot"])
            if terminated or truncated:
                break
        targets, rates = np.array(targets), np.array(rates)
        assert low <= targets.min() and targets.max() <= high
        assert np.ptp(targets) > 0.05
        central = (targets[2:] - targets[:-2]) / (2 * dt)
        np.testing.assert_allclose(central, rates[1:-1], atol=0.01 * np.abs(rates).max() + 1e-3)


@pytest.mark.parametrize(("scene", "max_torque"), [
    (None, None), ({"R": 2.0}, None), ({"R": 5.0}, None), ({"R": 30.0}, None),
    ({"R": 1e3}, None), ({"R": -5.0, "e": 0.09}, 3.0),
    ({"m": 0.6628, "r": 0.2280, "R": -14.727, "e": 0.2151, "k": 0.1576, "mu": 2.407}, 8.754)],
    ids=["default", "R=2", "R=5", "R=30", "R=1e3", "drum R=-5", "drum R=-14.7"])
def test_track_target_can_be_followed_within_the_torque_and_the_friction(scene, max_torque):
    """Moving along the target never needs more than max_torque, nor more friction than μN,
    larger cylinders and drums included (R = 5 m needed 1.8× max_torque before the amplitudes
    were bounded; on the two drums a follower within 2e-5 and 9e-5 rad slipped): the torque
    that keeps the roller on φ*(t) over the episode's 20 s, from the equation of motion the
    simulation steps (affine in τ) and φ*'' by central differences of the target, and the
    contact forces it then takes (the physics' own), for 2,000 drawn trajectories."""
    from roller_gym.physics import equations

    kwargs = {} if max_torque is None else {"max_torque": max_torque}
    if scene is not None and scene.get("R", 0) >= 30:  # starts that far from the target reach
        kwargs["dt"] = 0.2  # it within the episode only with longer steps
    if scene is not None:
        kwargs["scene"] = Scene(**{**gym.make(TRACK).unwrapped.scene.as_dict(), **scene})
    env = gym.make(TRACK, **kwargs)
    task, scene = env.unwrapped.task, env.unwrapped.scene
    params = task.sample_target_params(np.random.default_rng(7).random((2000, 7)), scene)
    t, h = np.arange(0.0, 20.0, 0.01)[:, None], 1e-4
    phi, phi_dot = task.target_at(params, t)
    phi_ddot = (task.target_at(params, t + h)[1] - task.target_at(params, t - h)[1]) / (2 * h)
    m, r, kappa, e, k, g, c = scene.params
    free = equations.accel(phi, phi_dot, 0.0, m, r, kappa, e, k, g, c)
    per_torque = equations.accel(phi, phi_dot, 1.0, m, r, kappa, e, k, g, c) - free
    assert np.abs((phi_ddot - free) / per_torque).max() <= task.max_torque
    normal, friction = equations.contact_forces(phi, phi_dot, phi_ddot, m, r, kappa, e, g)
    assert normal.min() > 0 and (np.abs(friction) - scene.mu * normal).max() <= 0


def test_track_refuses_a_fixed_target_option():
    with pytest.raises(ValueError, match="moves"):
        gym.make(TRACK).reset(seed=0, options={"target": 0.1})


def test_lqr_tracking_follows_the_moving_target():
    """The classical reference (LQR about the moving target, holding torque as
    feedforward, feedback on the position and the relative speed) ends 20 seeded episodes
    inside the success band, with a return near the maximum (1 per step)."""
    env = gym.make(TRACK)
    policy = controller_for(env)
    episodes = [rollout(env, policy, seed) for seed in range(20)]
    assert np.mean([e.success for e in episodes]) >= 0.9
    assert all(not e.terminated for e in episodes)
    assert np.mean([e.total_return for e in episodes]) >= TASKS["RollerTrack"].reward_threshold
    worst = max(float(np.max(np.abs(e.error[50:]))) for e in episodes)
    assert worst < 0.05 * math.pi  # after the first 2.5 s it stays within 0.16 rad


@pytest.mark.parametrize("name", list(TASKS))
def test_start_accepted_is_the_rule_on_start_contacts(name):
    """A start is accepted exactly where the contact forces of ``start_contacts`` (NumPy, the
    form the feasibility proofs use) give N > 0 and |F| <= μN under every start torque: the
    compiled check over (torque, roller, candidate) lanes keeps them in order."""
    task = TASKS[name]()
    rng = np.random.default_rng(4)
    scene = roller_gym.Scene(m=rng.uniform(0.5, 2, 7), e=rng.uniform(0, 0.09, 7), R=1.0)
    phi, phi_dot = rng.uniform(-3, 3, (7, 9)), rng.uniform(-12, 12, (7, 9))
    got = task.start_accepted(phi, phi_dot, scene)
    col = {f: np.broadcast_to(np.asarray(getattr(scene, f), float), (7,))[:, None]
           for f in ("m", "r", "e", "k", "g", "damping", "mu", "kappa")}
    kappa = col["kappa"]
    want = np.ones(phi.shape, bool)
    for normal, friction in task.start_contacts(phi, phi_dot, col["m"], col["r"], kappa,
                                                col["e"], col["k"], col["g"], col["damping"]):
        want &= (normal > 0) & (np.abs(friction) <= col["mu"] * normal)
    assert got.shape == phi.shape and want.sum() > 0
    # with a torque of 0.1 N·m (Swing, BalanceWeak) every state rolls
    assert want.sum() < want.size or TASKS[name].default_max_torque <= 0.1
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("name", list(TASKS))
def test_the_start_state_is_the_first_accepted_candidate_in_draw_order(name):
    """Each episode starts at the first of its candidates (draws 2j, 2j + 1 of its stream)
    that the task accepts: found here roller by roller, candidate by candidate, against the
    batch draw (which tries a candidate only where no earlier one was accepted). A slippery
    scene makes later candidates matter."""
    from roller_gym import episode

    task = TASKS[name]()
    default = roller_gym.config.resolve_scene(None, task.default_scene)
    n = 60
    try:  # less friction where the task allows it: fewer first candidates roll
        scene = default.replace(mu=0.3 * default.mu)
        vec = gym.make_vec(task.env_id(), num_envs=n, scene=scene, randomize={})
    except ValueError:
        scene = default
        vec = gym.make_vec(task.env_id(), num_envs=n, scene=scene, randomize={})
    vec.reset(seed=3)  # sub-environment i: seed 3 + i, its episode 0
    phi, phi_dot = vec.unwrapped.phi, vec.unwrapped.phi_dot
    later = 0
    for i in range(n):
        for j in range(episode.ROUNDS * episode.CANDIDATES):
            u = episode.uniform(3 + i, 0, 32 + 2 * j + np.arange(2)).reshape(1, 1, 2)
            c_phi, c_dot = task.start_candidates(u[..., 0], u[..., 1], scene)
            if task.start_accepted(c_phi, c_dot, scene)[0, 0]:
                break
        later += j > 0
        assert (phi[i], phi_dot[i]) == (c_phi[0, 0], c_dot[0, 0]), (i, j)
    # a redraw happened, unless every state of the start range rolls (a start at or near rest
    # at the bottom: Balance, Swing), on a 21 x 21 grid of the uniforms
    grid = np.linspace(0.0, 1.0, 21)
    g_phi, g_dot = task.start_candidates(np.repeat(grid, 21)[None], np.tile(grid, 21)[None],
                                         scene)
    assert later > 0 or task.start_accepted(g_phi, g_dot, scene).all()


# -- the holdable range ---------------------------------------------------------------------
def grid_scan_hold_range(scene, max_torque, torque_share=0.8, friction_share=0.9, points=2001,
                         rising=False):
    """The reference: hold_range as it was written before its compiled walk, a NumPy scan of
    the whole grid of each side (one scalar scene); with ``rising``, also where the potential
    energy (the physics' own ``energy`` at rest) grows from each grid point to the next
    outward, up to this one."""
    half = min(math.pi / abs(angle_rate(scene)), 2 * math.pi * START_TURNS)
    bounds = []
    for sign in (1.0, -1.0):
        phi = sign * np.linspace(0.0, half, points)
        c = contact(scene, phi, 0.0, holding_torque(scene, phi))
        normal, friction = np.asarray(c.normal), np.asarray(c.friction)
        ok = (np.abs(holding_torque(scene, phi)) <= torque_share * max_torque) & (normal > 0)
        ok &= np.abs(friction) <= friction_share * scene.mu * normal
        if rising:
            potential = np.asarray(energy(scene, phi, 0.0))
            ok[1:] &= np.diff(potential) > 0
        last = int(np.argmin(ok)) - 1 if not ok.all() else points - 1
        bounds.append(float(phi[max(last, 0)]))
    return bounds[1], bounds[0]


def random_scenes(n, seed):
    """Scenes inside a cylinder, on the floor and on a drum, some with e = 0, a few without
    friction, over wide ranges of every field."""
    rng = np.random.default_rng(seed)
    scenes = []
    for i in range(n):
        r = rng.uniform(0.02, 0.3)
        R = (r * rng.uniform(1.01, 20), math.inf, -r * rng.uniform(0.5, 20))[i % 3]
        scenes.append(Scene(m=rng.uniform(0.2, 5.0), r=r, R=R,
                            e=0.0 if i % 5 == 0 else rng.uniform(0.0, 1.2) * r,
                            k=rng.uniform(0.1, 1.5) * r, g=rng.uniform(1.0, 20.0),
                            mu=0.0 if i % 17 == 0 else rng.uniform(0.0, 2.0),
                            damping=rng.uniform(0.0, 0.1)))
    return scenes


def same_bits(a, b) -> bool:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return a.shape == b.shape and bool(np.all(a == b)) and np.array_equal(np.signbit(a),
                                                                          np.signbit(b))


def test_hold_ranges_is_the_grid_scan_bit_for_bit():
    """The compiled walk (early exit) gives, for a batch, each scene's bounds exactly as the
    NumPy scan of the whole grid did (``==`` on every element, and the sign of −0.0), over
    300 random scenes and five torque limits: where the whole half-turn holds, where nothing
    beyond φ = 0 does, and between."""
    scenes = random_scenes(300, seed=11)
    batch = Scene.stack(scenes)
    whole = nothing = between = 0
    for max_torque in (0.05, 0.3, 1.0, 5.0, 100.0):
        low, high = hold_ranges(batch, max_torque)
        want = np.array([grid_scan_hold_range(s, max_torque) for s in scenes])
        assert same_bits(low, want[:, 0]) and same_bits(high, want[:, 1]), max_torque
        half = np.minimum(math.pi / np.abs(angle_rate(batch)), 2 * math.pi * START_TURNS)
        whole += int(np.sum(high == half) + np.sum(low == -half))
        nothing += int(np.sum(high == 0.0) + np.sum(low == 0.0))
        between += int(np.sum((high > 0.0) & (high < half)))
    assert whole > 100 and nothing > 50 and between > 300


def test_rising_hold_ranges_stop_where_the_potential_stops_rising():
    """With ``rising`` the walk also stops where the potential stops rising from the bottom
    on: the reference checks it as growth of the potential energy between grid points (not
    the sign of dV/dφ the walk uses); over 300 random scenes without a torque limit they agree
    but within a grid point (where the growth turns between two points), and the rising
    range is within the plain one and shorter for some."""
    scenes = random_scenes(300, seed=12)
    plain = hold_ranges(Scene.stack(scenes), math.inf)
    low, high = hold_ranges(Scene.stack(scenes), math.inf, rising=True)
    shorter = 0
    for i, scene in enumerate(scenes):
        want = grid_scan_hold_range(scene, math.inf, rising=True)
        spacing = min(math.pi / abs(angle_rate(scene)), 2 * math.pi * START_TURNS) / 2000
        assert abs(low[i] - want[0]) <= spacing * 1.000001 and abs(high[i] - want[1]) <= (
            spacing * 1.000001), (i, scene)
        assert plain[0][i] <= low[i] <= 0.0 <= high[i] <= plain[1][i]
        shorter += int(high[i] < plain[1][i])
    assert shorter > 20


@pytest.mark.parametrize("points", [1, 2, 3, 10, 2001])
def test_hold_range_grid_of_any_size_is_the_grid_scan(points):
    """Grids of any size, the shares included, give the reference's bounds (the scalar
    function, memoized, and the batch one)."""
    scenes = random_scenes(30, seed=points)
    low, high = hold_ranges(Scene.stack(scenes), 0.7, 0.6, 0.5, points)
    for i, scene in enumerate(scenes):
        want = grid_scan_hold_range(scene, 0.7, 0.6, 0.5, points)
        assert same_bits(hold_range(scene, 0.7, 0.6, 0.5, points), want), i
        assert same_bits((low[i], high[i]), want), i


def test_hold_ranges_of_a_batch_is_each_scene_alone():
    """A batch of distinct scenes (array fields next to scalar ones) gives each roller's
    range as that scene alone does, and a scalar scene gives arrays of one."""
    rng = np.random.default_rng(5)
    batch = Scene(m=rng.uniform(0.5, 2.0, 40), e=rng.uniform(0.0, 0.09, 40),
                  R=np.where(rng.uniform(size=40) < 0.5, 0.6, -0.6), mu=0.8)
    low, high = hold_ranges(batch, 1.0)
    assert low.shape == high.shape == (40,) and len(set(high)) > 20
    for i in range(40):
        alone = hold_ranges(batch.item(i), 1.0)
        assert alone[0].shape == (1,)
        assert same_bits((low[i], high[i]), (alone[0][0], alone[1][0]))
        assert same_bits(hold_range(batch.item(i), 1.0), (low[i], high[i]))
    # numbers of other types count as the floats they are
    assert same_bits(hold_ranges(Scene(m=1, R=np.float32(0.5)), 1.0),
                     hold_ranges(Scene(m=1.0, R=float(np.float32(0.5))), 1.0))
