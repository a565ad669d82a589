"""Starts doomed to slip on their way down (roller_gym.descent): the least speed against the
hardest braking simulated, the rolling set against a dense search, and the refusals."""

import itertools
import math
import re

import gymnasium as gym
import numpy as np
import pytest
from env_cases import cell_width
from roller_gym import Scene, descent
from roller_gym.physics import PRESETS, equations
from roller_gym.task import get_task
from scipy.integrate import solve_ivp

#: (scene, max_torque [N·m]) where every policy fails from some start of RollerStabilize:
#: on its way in, with damping too; on the drum, pushed out past the barrier; and from a
#: start the draw takes past every start at rest.
DOOMED = [(PRESETS["rim_mass"], 0.5), (Scene(e=0.2), 0.5), (Scene(e=0.2, damping=0.01), 0.5),
          (PRESETS["balance"], 0.5), (Scene(e=0.099, k=0.005), 0.5),
          (PRESETS["rim_mass"].replace(damping=1e-3), 0.6), (PRESETS["drum"], 0.5),
          (PRESETS["drum"], 1.0),
          # a start taken past every start at rest that rolls (21.2 rad against 15.2)
          (Scene(R=3.0, e=0.06698, k=0.02974, mu=0.4308), 0.5254)]
#: ... and where no start is doomed (the beam search of a review reached the target from
#: rim_mass at 1 N·m).
NOT_DOOMED = [(PRESETS["paper"], 0.5), (PRESETS["rim_mass"], 1.0), (Scene(e=0.09), 0.5),
              (PRESETS["drum"], 2.0), (PRESETS["floor"], 0.5)]


def _stabilize(max_torque):
    return get_task("RollerStabilize", current=True)(max_torque)


def _rolling_torque_exists(scene, phi, speed, max_torque, torques=801):
    """Whether some torque in [−max_torque, max_torque] rolls at (φ, φ' = ``speed``, signed):
    a dense search straight on the contact forces."""
    m, r, kappa, e, k, g, c = scene.params
    tau = np.linspace(-max_torque, max_torque, torques)
    a = equations.accel(phi, speed, tau, m, r, kappa, e, k, g, c)
    normal, friction = equations.contact_forces(phi, speed, a, m, r, kappa, e, g)
    return bool(np.any((normal > 0) & (np.abs(friction) <= scene.mu * normal)))


def _braked_speed(scene, start, where, max_torque, speed=0.0):
    """|φ'| [rad/s] at |φ| = ``where`` of the roller released at ``start`` at |φ'| =
    ``speed`` toward ``where`` under the full torque against that motion (the most a torque
    can slow it), by a tight reference integration."""
    m, r, kappa, e, k, g, c = scene.params
    brake = max_torque * math.copysign(1.0, start - where)

    def rhs(_, y):
        return [y[1], equations.accel(y[0], y[1], brake, m, r, kappa, e, k, g, c)]

    def arrive(_, y):
        return y[0] - where

    arrive.terminal = True
    sol = solve_ivp(rhs, (0.0, 20.0), [start, -speed * math.copysign(1.0, start - where)],
                    events=arrive, rtol=1e-11, atol=1e-12,
                    method="DOP853")
    assert sol.status == 1, "the braked roller never got there"
    return abs(sol.y_events[0][0][1])


#: (scene, max_torque [N·m], task) that an independent beam search over torque sequences at
#: dt = 0.05 s found accepted with a start it cannot bring down: the cylinders within NEAR
#: times the least torque the descent rule accepts, so refused at max_torque / NEAR; the
#: drums anywhere (every drum is warned).
NEAR = [(Scene(R=2.0, e=0.044038, k=0.0075265, mu=1.2004), 0.42738, "RollerHold"),
        (Scene(R=-2.0, e=0.0338, k=0.00787, mu=1.089), 0.917, "RollerHold"),
        (Scene(R=3.0, e=0.0349, k=0.00893, mu=1.17), 0.70, "RollerStabilize"),
        (Scene(R=3.0, e=0.073, k=0.0169, mu=0.592), 0.832, "RollerStabilize"),
        # 2.55 times that torque (a 2 ms greedy braking controller dies too)
        (Scene(R=1.31326, e=0.0310667, k=0.0172431, mu=1.23346), 0.146514, "RollerTrack"),
        # a drum with damping, from starts moving outward past 22 rad: 3.39 times
        (Scene(R=-2.206, e=0.02784, k=0.01892, mu=1.2833, damping=0.03), 0.755978,
         "RollerHold"),
        # a drum with more damping: 4.12 times (its start drawn by reset(seed=297) slips)
        (Scene(R=-0.5508533222128271, e=0.037198509293097, k=0.07398995705201489,
               mu=0.5022051696144412, damping=0.25289619347928777), 0.6195, "RollerHold")]


@pytest.mark.parametrize(("scene", "max_torque"),
                         DOOMED + [(s, t / descent.NEAR) for s, t, _ in NEAR[:2]])
def test_a_doomed_start_is_doomed_by_a_direct_search(scene, max_torque):
    """The reported speed is below what the hardest braking leaves at that point, and at
    that speed and above (up to the braked one) no torque rolls there."""
    found = descent.doomed(_stabilize(max_torque), scene)
    assert found is not None
    start, speed, where, least = found
    # The draw takes a start in the named one's cell (the cells between the task's
    # candidates: their far ends are the starts the check counts).
    task = _stabilize(max_torque)
    width = cell_width(task, scene)
    cell, speeds = np.meshgrid(np.linspace(start - width, start, 201), np.linspace(-1, 1, 41))
    assert task.start_accepted(cell.reshape(1, -1), speeds.reshape(1, -1), scene).any()
    braked = _braked_speed(scene, start, where, max_torque, speed)
    assert least <= braked * (1 + 1e-9)
    way = math.copysign(1.0, where - start)  # (in, or out past a barrier)
    for speed in np.linspace(least, max(braked, least) * 1.5, 25):
        assert not _rolling_torque_exists(scene, where, way * speed, max_torque), speed


@pytest.mark.parametrize(("scene", "max_torque"), NOT_DOOMED)
def test_scenes_a_controller_solves_are_not_doomed(scene, max_torque):
    assert descent.doomed(_stabilize(max_torque), scene) is None


@pytest.mark.parametrize(("scene", "max_torque", "task"), NEAR)
def test_a_scene_near_the_threshold_is_accepted_with_a_warning(scene, max_torque, task):
    """Not proven doomed, so accepted; but the warning says some starts may be, where a
    review found one (at construction, for a sub-environment, and for a reset's scene)."""
    env_id = get_task(task, current=True).env_id()
    assert descent.doomed(get_task(task, current=True)(max_torque), scene) is None
    within = (r"accepted, but on a drum the descent check gives no margin" if scene.R < 0
              else rf"accepted, but within {descent.NEAR:g} times the least torque")
    with pytest.warns(UserWarning, match=within):
        env = gym.make(env_id, scene=scene, max_torque=max_torque)
    with pytest.warns(UserWarning, match=r"^scene\[1\]: .*whatever the policy"):
        gym.make_vec(env_id, num_envs=2, scene=["paper", scene], max_torque=max_torque)
    with pytest.warns(UserWarning, match=r"^options\['scene'\]: .*whatever the policy"):
        env.reset(seed=0, options={"scene": scene})


@pytest.mark.parametrize("task", ["RollerStabilize", "RollerHold", "RollerTrack"])
def test_the_default_scenes_have_a_margin(task, recwarn):
    """No warning where the task is made as registered, nor far above the least torque the
    rule accepts (``floor`` at 0.5 N·m, ``paper`` at 0.1 N·m: it accepts both down to
    0.02 N·m)."""
    env_id = get_task(task, current=True).env_id()
    gym.make(env_id)
    for scene, max_torque in ((PRESETS["floor"], 0.5), (PRESETS["paper"], 0.1)):
        task_ = get_task(task, current=True)(max_torque)
        assert descent.fixed_scene_problem(task_, scene, 0.05) == (None, None)
    assert not [w for w in recwarn if "times the least torque" in str(w.message)]


def _torques_at(A, B, C, x, low, high):
    """The interval of u in [low, high] where every row A + B x + C u >= 0 holds at x, row
    by row (empty: lower end > upper end)."""
    lo, hi = low, high
    for a, b, c in zip(A, B, C, strict=True):
        if c > 0:
            lo = max(lo, -(a + b * x) / c)
        elif c < 0:
            hi = min(hi, -(a + b * x) / c)
        elif a + b * x < 0:
            return 1.0, -1.0
    return lo, hi


def test_the_rolling_set_ends_where_no_torque_is_left():
    """fastest_rolling's x, on random rows, against the torques left at each x, found row
    by row: some at x, none a little past it (or it is unbounded, or empty at x = 0...)."""
    rng = np.random.default_rng(7)
    n = 400
    A, B, C = (rng.normal(size=(3, n)) for _ in range(3))
    most = descent.fastest_rolling(A, B, C, -1.0, 1.0)
    seen = {"bounded": 0, "unbounded": 0, "empty": 0}
    for i in range(n):
        rows = A[:, i], B[:, i], C[:, i]
        if most[i] == -np.inf:
            seen["empty"] += 1
            for x in np.linspace(0.0, 100.0, 1001):
                lo, hi = _torques_at(*rows, x, -1.0, 1.0)
                assert lo > hi + 1e-12, (i, x)
        elif most[i] >= 1e30:
            seen["unbounded"] += 1
            lo, hi = _torques_at(*rows, 1e12, -1.0, 1.0)
            assert lo <= hi + 1e-9, i
        else:
            seen["bounded"] += 1
            lo, hi = _torques_at(*rows, most[i], -1.0, 1.0)
            assert lo <= hi + 1e-9 * (1 + abs(most[i])), i
            lo, hi = _torques_at(*rows, most[i] * (1 + 1e-6) + 1e-6, -1.0, 1.0)
            assert lo > hi, i
    assert min(seen.values()) >= 20, seen  # each case tried


def test_a_doomed_scene_is_refused_at_construction_and_reset():
    with pytest.raises(ValueError, match=r"max_torque=0.5 N·m: from a start the draw may take"):
        gym.make("roller_gym/RollerStabilize-v2", scene="rim_mass")
    with pytest.raises(ValueError, match=r"scene\[1\] \(sub-environment 1.*slips or lifts off"):
        gym.make_vec("roller_gym/RollerHold-v2", num_envs=2, max_torque=0.5,
                     scene=["paper", "rim_mass"])
    env = gym.make("roller_gym/RollerTrack-v1", max_torque=0.5)
    with pytest.raises(ValueError, match=r"options\['scene'\]: .*slips or lifts off"):
        env.reset(seed=0, options={"scene": "rim_mass"})
    env.reset(seed=0, options={"scene": "paper"})  # (the env still works)
    # A pump's target lies up: no descent is asked of it.
    gym.make("roller_gym/RollerBalance-v2")


#: RollerHoldRandomized-v1's ranges, whose corner R = 1 m, e = 0.07 m, k = 0.07 m, m = 1.6 kg
#: holds doomed starts (v2 draws R up to 0.8 m).
HOLD_RANDOMIZED_V1 = {"m": (0.8, 1.6), "e": (0.03, 0.07), "k": (0.07, 0.15), "R": (0.3, 1.0)}


def test_a_box_with_a_doomed_corner_is_refused_and_the_corner_is_doomed():
    """RollerHoldRandomized-v1's ranges are refused, naming a corner; there the braked
    roller from the named start meets a state where no torque rolls."""
    env_id = get_task("RollerHoldRandomized", current=True).env_id()
    with pytest.raises(ValueError, match=r"^randomize=.* draws scenes next to R=1, e=0\.07, "
                                         r"k=0\.07, m=1\.6, where .*narrow the ranges"):
        gym.make(env_id, randomize=HOLD_RANDOMIZED_V1)
    env = gym.make(env_id).unwrapped  # (its own ranges pass)
    assert env.config.randomize["R"][1] < HOLD_RANDOMIZED_V1["R"][1]
    scene = env.config.scene.replace(R=1.0, m=1.6, e=0.07, k=0.07)
    start, speed, where, least = descent.doomed(env.task, scene)
    assert least <= _braked_speed(scene, start, where, env.task.max_torque, speed) * (1 + 1e-9)
    assert not _rolling_torque_exists(scene, where, -least, env.task.max_torque)


def test_a_box_is_refused_for_a_doomed_corner_only_where_the_task_descends():
    """The same kind of box, on Stabilize's ``paper`` (the plain four fields around it), is
    refused at the corner the fixed scene is refused at; the pump tasks are not asked."""
    ranges = {"R": (0.4, 1.0), "e": (0.04, 0.09), "k": (0.05, 0.2), "m": (0.5, 2.0)}
    corner = Scene(R=0.4, e=0.09, k=0.05, m=2.0)
    with pytest.raises(ValueError, match=r"max_torque=0.5 N·m: from a start the draw may take"):
        gym.make("roller_gym/RollerStabilize-v2", scene=corner)
    with pytest.raises(ValueError, match=r"next to R=0\.4, e=0\.09, k=0\.05, m=2, where"):
        gym.make("roller_gym/RollerStabilize-v2", randomize=ranges)
    swing = get_task("RollerBalance", current=True)(0.4)
    assert descent.range_problem(swing, PRESETS["balance"], ranges) is None


#: Boxes a review found accepted with doomed scenes where the corners and the middle alone
#: miss them: inside a Track box (10 % of its draws), and at 2 of the 32 corners of a
#: five-field one. (task, scene, max_torque [N·m], ranges)
HIDDEN = [("RollerTrack", Scene(R=0.832713, e=0.0566826, k=0.00419765, mu=0.694797), 0.163674,
           {"damping": (0.0, 0.00505186), "e": (0.0508617, 0.0625034), "m": (0.888018, 1.11198)}),
          ("RollerTrack", Scene(R=-0.699891, e=0.0345929, k=0.00341056, mu=0.919267), 0.708234,
           {"damping": (0.0, 0.019943), "e": (0.0306501, 0.0385356), "k": (0.00284362, 0.0039775),
            "m": (0.965399, 1.0346), "mu": (0.699725, 1.13881)}),
          # a drum whose doomed band (15 % of its draws) lies between corners and middle
          ("RollerHoldRandomized",
           Scene(m=0.7300708837112043, r=0.12495976820625965, R=-1.0246306554167546,
                 e=0.06825072923978456, k=0.07829664538627237, mu=1.1175927572382944,
                 damping=0.08650938921270958), 0.5, {"R": (-3.0, -2.3)})]


@pytest.mark.parametrize(("task", "scene", "max_torque", "ranges"), HIDDEN)
def test_a_box_is_refused_for_a_doomed_scene_inside_it(task, scene, max_torque, ranges):
    """Refused, naming a scene of the box; there the named start, braked by a reference
    integration, is no slower than the bound where no torque rolls."""
    cls = get_task(task, current=True)
    with pytest.raises(ValueError, match=r"^randomize=.* draws scenes next to ") as refused:
        gym.make(cls.env_id(), scene=scene, max_torque=max_torque, randomize=ranges)
    named = re.search(r"next to (.*?), where", str(refused.value)).group(1)
    point = {k: float(v) for k, v in (pair.split("=") for pair in named.split(", "))}
    assert all(ranges[k][0] <= v <= ranges[k][1] for k, v in point.items())
    at = scene.replace(**point)
    start, speed, where, least = descent.doomed(cls(max_torque), at)
    way = math.copysign(1.0, where - start)
    assert least <= _braked_speed(at, start, where, max_torque, speed) * (1 + 1e-9)
    assert not _rolling_torque_exists(at, where, way * least, max_torque)


def test_a_box_that_draws_drums_is_warned_as_a_drum_is(recwarn):
    """No factor of the least torque held on a drum: a descending task warns on every drum,
    fixed or drawn by a box, and on neither kind of cylinder."""
    drum = "on a drum the descent check gives no margin"
    with pytest.warns(UserWarning, match=rf"^RollerHold on the drum .*{drum}"):
        gym.make("roller_gym/RollerHold-v2", scene="drum", max_torque=2.0)
    with pytest.warns(UserWarning, match=rf"^RollerHold with randomize=.*draws drums.*{drum}"):
        gym.make("roller_gym/RollerHold-v2", scene="drum", max_torque=2.0,
                 randomize={"m": (0.9, 1.1)})
    hold = get_task("RollerHold", current=True)(2.0)
    assert descent.range_caution(hold, PRESETS["paper"], {"R": (-0.8, -0.6)}) is not None
    assert descent.range_caution(hold, PRESETS["drum"], {"R": (0.4, 0.6)}) is None
    balance = get_task("RollerBalance", current=True)(0.4)  # (its target lies up: no descent)
    assert descent.range_caution(balance, PRESETS["drum"], {"m": (0.9, 1.1)}) is None
    for box in ({"R": (-1.0, 1.0)}, {"R": (-1.0, 0.05)}):  # no scene at R = 0 or R < r
        with pytest.raises(ValueError, match="R must be > r"):
            descent.range_caution(hold, PRESETS["paper"], box)
        with pytest.raises(ValueError, match="R must be > r"):
            descent.range_problem(hold, PRESETS["paper"], box)
    recwarn.clear()
    gym.make("roller_gym/RollerHold-v2", randomize={"m": (0.9, 1.1)})
    assert not [w for w in recwarn if drum in str(w.message)]


def test_a_box_is_checked_at_every_corner(monkeypatch):
    """A box of all eight Scene fields: each of its 2⁸ corners is checked (a review built an
    eight-field box whose 2 doomed corners a sample of 64 missed)."""
    ranges = {name: (0.99 * value, 1.01 * value) if value else (0.0, 0.001)
              for name, value in PRESETS["paper"].as_dict().items()}
    seen = set()

    def recording(task, scene):
        seen.add(tuple(scene.as_dict()[name] for name in ranges))

    monkeypatch.setattr(descent, "doomed", recording)
    assert descent.range_problem(_stabilize(0.5), PRESETS["paper"], ranges) is None
    corners = set(itertools.product(*ranges.values()))
    assert len(corners) == 2 ** 8
    assert corners <= seen


def test_the_helpers_refuse_what_they_cannot_check():
    """A batch of scenes (the checks take one scene), a step that is no duration, and ranges
    that are not a mapping of Scene fields to finite (low <= high): each a clear error naming
    the argument, as the environments give before these are reached."""
    task, batch = _stabilize(0.5), Scene(e=np.array([0.04, 0.05]))
    for call in (lambda: descent.doomed(task, batch),
                 lambda: descent.fixed_scene_problem(task, batch, 0.05),
                 lambda: descent.range_problem(task, batch, {"e": (0.03, 0.05)})):
        with pytest.raises(ValueError, match=r"scene=.* is a batch of 2 rollers: .*scene.item"):
            call()
    with pytest.raises(TypeError, match=r"scene='paper' must be a Scene"):
        descent.doomed(task, "paper")
    for not_a_task in (None, type(task), "RollerStabilize"):
        with pytest.raises(TypeError, match=r"^task=.* is not a task: pass an instance"):
            descent.doomed(not_a_task, PRESETS["paper"])
    for dt in (0.0, -0.05, math.nan, math.inf, "0.05"):
        with pytest.raises(ValueError, match=r"^dt=.* must be a finite real number > 0 \[s\]"):
            descent.fixed_scene_problem(task, PRESETS["paper"], dt)
    with pytest.raises(ValueError, match=r"ranges=.* is not allowed: it must be a mapping"):
        descent.range_problem(task, PRESETS["paper"], [("e", (0.03, 0.05))])
    for ranges, match in (({"e": (0.05, 0.03)}, r"ranges\['e'\]=.* needs finite low <= high"),
                          ({"e": (0.03, math.nan)}, r"ranges\['e'\]\[1\]=nan .* finite real"),
                          ({"e": (-math.inf, 0.05)}, r"ranges\['e'\]\[0\]=-inf .* finite re"),
                          ({"e": (0.03, 0.04, 0.05)}, r"ranges\['e'\]=.* must be a \(low, hig"),
                          ({"e": "0.03"}, r"ranges\['e'\]=.* must be a \(low, high\) pair"),
                          ({"x": (0.0, 1.0)}, r"ranges names 'x', not a Scene field"),
                          ({1: (0.0, 1.0)}, r"ranges names 1, not a Scene field")):
        with pytest.raises(ValueError, match=match):
            descent.range_problem(task, PRESETS["paper"], ranges)
