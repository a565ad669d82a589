"""What used to fail late or silently fails early and clearly: randomize ranges checked on
their whole interval at construction, arguments by one type rule, settings that cannot be
integrated, and the equilibria search at bounded cost (checked against independent
computations)."""

from __future__ import annotations

import math
import re
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym import Scene, preset
from roller_gym.physics import analysis, predicted_substeps, step
from roller_gym.rest import orbit_mean_speed
from roller_gym.roller_env import RollerEnv
from roller_gym.task import angle_rate
from scipy.optimize import brentq, minimize_scalar

STABILIZE, HOLD, BALANCE = (roller_gym.TASKS[f"Roller{t}"].env_id()
                            for t in ("Stabilize", "Hold", "Balance"))
#: A control step [s] long enough that the bottom is within reach, in an episode, of a start
#: on a nearly flat surface (up to 64 turns away: roller_gym.bounds.least_times).
FLAT_DT = 0.2


# -- 1. randomize ranges --------------------------------------------------------------------
@pytest.mark.parametrize(
    ("env_id", "ranges", "message"),
    [
        (STABILIZE, {"R": (-1.0, 1.0)}, r"passes through R in \[0, r\]"),
        (STABILIZE, {"mu": (0.2, 1.0)}, r"randomize\['mu'\].*feasible part of the range: \[0.2"),
        (HOLD, {"mu": (0.3, 1.0)}, r"randomize\['mu'\].*feasible part of the range: \[0.4"),
        (BALANCE, {"R": (0.5, 2.0)}, r"randomize\['R'\].*not reachable.*feasible part"),
        (BALANCE, {"e": (0.03, 0.05)}, r"randomize\['e'\].*not reachable.*feasible part of "
                                       r"the range: \[0.049"),
        (STABILIZE, {"r": (0.05, 0.6)}, r"Scene.R=0.5 is not allowed with r=0.6"),
    ],
)
def test_a_range_that_cannot_be_posed_is_refused_at_construction(env_id, ranges, message):
    for make in (lambda: gym.make(env_id, randomize=ranges),
                 lambda: gym.make_vec(env_id, num_envs=8, randomize=ranges)):
        with pytest.raises(ValueError, match=message):
            make()


def test_the_feasible_part_it_names_is_feasible_and_its_edge_is_the_boundary():
    """μ: the roller rolls at rest at the bottom under ±max_torque while μ g >= |F|/m, by
    PHYSICS.md at φ = φ' = 0: F/m = (r − e) τ/(m (k² + (r − e)²)), N/m = g (with e sin θ = 0
    there); the named lower end matches that threshold."""
    scene = preset("paper")
    m, r, e, k, g = (float(getattr(scene, f)) for f in ("m", "r", "e", "k", "g"))
    tau = 0.5
    threshold = (r - e) * tau / (m * (k * k + (r - e) ** 2)) / g
    with pytest.raises(ValueError) as info:
        gym.make(STABILIZE, randomize={"mu": (0.1, 1.0)})
    low = float(str(info.value).split("feasible part of the range: [")[1].split(",")[0])
    assert low == pytest.approx(threshold, rel=1e-4)
    env = gym.make(STABILIZE, randomize={"mu": (low * 1.001, 1.0)})
    vec = gym.make_vec(STABILIZE, num_envs=256, randomize={"mu": (low * 1.001, 1.0)})
    env.reset(seed=0)
    vec.reset(seed=0)  # every sub-environment starts: no late failure
    for _ in range(3):
        vec.step(np.zeros((256, 1), np.float32))


@pytest.mark.parametrize(("env_id", "ranges", "verdict"), [
    (HOLD, {"mu": (0.2, 1.0)}, "proven"),
    # the scan's edge (the scalar damping limit) lies past where the proof closes
    (BALANCE, {"damping": (0.0, 0.05)}, "a scan"),
    # m's part is scanned with e at the point where it failed; with e's range it is not proven
    (HOLD, {"m": (0.2, 5.0), "e": (0.02, 0.09)}, "a scan")])
def test_a_named_feasible_part_says_whether_it_is_proven_and_means_it(env_id, ranges,
                                                                      verdict):
    """A refused range names a feasible part of one field's range, found by a scan of
    scenes; it says whether that part, with the other ranges as given, is proven, and the
    narrower ranges are accepted exactly when it says so."""
    with pytest.raises(ValueError) as info:
        gym.make(env_id, randomize=ranges)
    found = re.search(r"randomize\['(\w+)'\].*feasible part of the range: \[([^,]+), "
                      r"([^\]]+)\] \((proven|a scan)", str(info.value))
    name, low, high, said = found.groups()
    assert said == verdict
    narrower = {**ranges, name: (float(low), float(high))}
    if said == "proven":
        gym.make(env_id, randomize=narrower)
    else:
        with pytest.raises(ValueError, match="could not be proven"):
            gym.make(env_id, randomize=narrower)


def test_feasible_ranges_construct_and_start():
    vec = gym.make_vec(BALANCE, num_envs=64, randomize={"R": (0.9, 1.5), "m": (0.8, 1.2)})
    vec.reset(seed=1)
    assert len({float(s.R) for s in vec.unwrapped.scenes}) == 64


# -- 2. equilibria at bounded cost, checked independently --------------------------------------
def test_equilibria_cost_is_bounded_and_near_floor_behaves_like_the_floor():
    """On a nearly flat surface the rest positions nearest the bottom approach the floor's
    (φ = 0 stable, φ = ±π unstable for e > 0); the search costs the same at R = 1e12."""
    floor = analysis.equilibria(Scene(R=math.inf, e=0.08, k=0.1), 0.0)
    assert [round(q.phi, 9) for q in floor] == [round(-math.pi, 9), 0.0]
    for R in (100.0, 300.0, 1e6, 1e12):
        start = time.process_time()
        found = analysis.equilibria(Scene(R=R, e=0.08, k=0.1), 0.0)
        assert time.process_time() - start < 5.0  # was MemoryError at 1e12
        near = [q for q in found if abs(q.phi) < 4.0]
        assert [q.stable for q in near] == [False, True, False]
        # r sin ψ + e sin φ = 0 near φ = π, ψ = r φ/(R − r) (PHYSICS.md's cylinder form)
        root = brentq(lambda x, R=R: 0.1 * math.sin(0.1 * x / (R - 0.1)) + 0.08 * math.sin(x),
                      3.0, 3.3, xtol=1e-14)
        assert near[2].phi == pytest.approx(root, abs=1e-9)
    env = gym.make(BALANCE, scene=Scene(R=1e12, e=0.08, k=0.1))
    assert env.unwrapped.target == pytest.approx(math.pi, abs=1e-9)


def test_nearly_coincident_rest_positions_near_the_largest_holding_torque():
    """Just below the largest holding torque two rest positions lie close together on each
    side of the maximum of dV/dφ; both are found (checked by bracketing them around the
    maximum, found here by a bounded minimization)."""
    scene = preset("paper")
    m, r, kappa, e, _, g, _ = scene.params

    def moment(phi):
        return m * g * (r * math.sin(r * kappa * phi / (1 - r * kappa)) + e * math.sin(phi))

    top = minimize_scalar(lambda x: -moment(x), bounds=(7.5, 7.8), method="bounded",
                          options={"xatol": 1e-12})
    peak, largest = top.x, -top.fun
    for gap in (1e-7, 1e-9):
        tau = largest * (1 - gap)

        def f(x, tau=tau):
            return moment(x) - tau

        expected = [brentq(f, peak - 0.3, peak, xtol=1e-15),
                    brentq(f, peak, peak + 0.3, xtol=1e-15)]
        found = [q for q in analysis.equilibria(scene, tau) if abs(q.phi - peak) < 0.3]
        assert [q.phi for q in found] == pytest.approx(expected, abs=1e-7)
        assert [q.stable for q in found] == [True, False]


def test_a_uniform_disc_on_the_floor_has_no_isolated_rest_position():
    assert analysis.equilibria(Scene(R=math.inf, e=0.0), 0.0) == []
    assert analysis.equilibria(Scene(R=math.inf, e=0.0), 0.1) == []
    with pytest.raises(ValueError, match="no unstable rest position"):
        gym.make(BALANCE, scene=Scene(R=math.inf, e=0.0))


# -- 3. types --------------------------------------------------------------------------------
def test_numpy_numbers_are_numbers():
    env = gym.make(STABILIZE, dt=np.float32(0.05), substeps=np.int64(3),
                   max_torque=np.float64(0.4), tolerance=np.float32(1e-7))
    _, info = env.reset(seed=0)
    _, _, _, _, info = env.step(np.array([0.5], np.float32))
    assert info["substeps"] == 3 and info["torque"] == pytest.approx(0.2)
    vec = gym.make_vec(STABILIZE, num_envs=np.int64(2), max_episode_steps=np.int32(5))
    assert vec.num_envs == 2


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [({"max_torque": "1"}, "max_torque"), ({"dt": "0.05"}, "dt"), ({"dt": True}, "dt"),
     ({"max_torque": [1, 2]}, "max_torque"), ({"integrator": []}, "integrator"),
     ({"randomize": ["m"]}, "randomize"), ({"randomize": "m"}, "randomize"),
     ({"randomize": {"m": (0.8, "1.2")}}, r"randomize\['m'\]\[1\]"),
     ({"randomize": {"m": (-1, 1)}}, r"randomize\['m'\]"),  # Scene.m=-1.0 is not allowed
     ({"substeps": 2.0}, "substeps"), ({"substeps": True}, "substeps"),
     ({"tolerance": complex(1e-8, 0)}, "tolerance"),
     # a Python int past float's range (OverflowError from float())
     ({"dt": 10**400}, "dt"), ({"max_torque": -10**400}, "max_torque"),
     ({"randomize": {"m": (1, 10**400)}}, r"randomize\['m'\]\[1\]")],
)
def test_wrong_types_are_refused_naming_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=rf"{name}=.*(not allowed|out of range)"):
        gym.make(STABILIZE, **kwargs)


@pytest.mark.parametrize("action", [np.array([1j]), np.array(["0.5"]), "0.5",
                                    np.array([0.1, 0.2]), np.array([[0.5]])])
def test_actions_must_be_real_numbers_of_the_right_shape(action):
    env = gym.make(STABILIZE).unwrapped
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action="):
        env.step(action)


def test_a_batch_of_actions_must_have_the_batch_shape_not_its_transpose():
    """(n, 1), the action space's shape, and (n,) are a batch's actions; (1, n), a
    transposed batch of as many numbers, is refused, naming the shapes allowed."""
    vec = gym.make_vec(STABILIZE, num_envs=3)
    vec.reset(seed=0)
    a = np.array([0.1, -0.2, 0.3], np.float32)
    first, second = gym.make_vec(STABILIZE, num_envs=3), gym.make_vec(STABILIZE, num_envs=3)
    first.reset(seed=0), second.reset(seed=0)
    np.testing.assert_array_equal(first.step(a[:, None])[0], second.step(a)[0])
    with pytest.raises(ValueError, match=r"of shape \(3, 1\) or \(3,\).*not float32 of "
                                         r"shape \(1, 3\)"):
        vec.step(a[None, :])


# -- 4. settings that cannot be integrated ----------------------------------------------------
@pytest.mark.parametrize(
    ("kwargs", "message"),
    [({"dt": 1e6}, r"dt=1000000.0 s is too long"),
     ({"scene": Scene(g=1e300)}, "cannot be integrated in float64"),
     ({"scene": Scene(r=1e-300, R=1e-299, e=0, k=1e-300)}, "cannot be integrated in float64"),
     ({"scene": Scene(e=0.1, k=1e-9)}, r"dt=0.05 s is too long")],
)
def test_settings_that_cannot_be_integrated_are_refused_at_construction(kwargs, message):
    with pytest.raises(ValueError, match=message):
        gym.make(STABILIZE, **kwargs)
    with pytest.raises(ValueError, match=message):
        gym.make_vec(STABILIZE, num_envs=2, **kwargs)


def test_every_registered_task_constructs_with_its_defaults():
    for env_id in roller_gym.ENV_IDS:
        gym.make(env_id).reset(seed=0)


# -- 5. per-sub-environment scenes, damping, actions of any dtype, sizes --------------------
def test_each_sub_environments_scene_is_proven_over_the_ranges_naming_it():
    """A range proven around one scene is not proven around another: r up to 0.21 m reaches
    R = 0.2 m of the second scene (no scene: R must be > r), which the single environment
    refuses; so must the vector env, naming the sub-environment, not fail at an autoreset."""
    ranges = {"r": (0.05, 0.21)}
    with pytest.raises(ValueError, match=r"randomize\['r'\]"):
        gym.make(STABILIZE, scene=Scene(R=0.2), randomize=ranges)
    with pytest.raises(ValueError, match=r"sub-environment 1\b.*randomize\['r'\].*R=0.2"):
        gym.make_vec(STABILIZE, num_envs=2, scene=["paper", Scene(R=0.2)], randomize=ranges)
    # and the checks are those of each scene, not of the task's default one
    vec = gym.make_vec(STABILIZE, num_envs=2, scene=[Scene(R=0.3), Scene(R=0.4)],
                       randomize={"r": (0.05, 0.25)})
    vec.reset(seed=0)
    assert all(0.05 <= s.r <= 0.25 for s in vec.unwrapped.scenes)
    with pytest.raises(ValueError, match=r"sub-environment 0 and 1 more"):
        gym.make_vec(STABILIZE, num_envs=2, scene=[Scene(R=0.2)] * 2, randomize=ranges)


def _fastest_rate(scene: Scene, max_torque: float) -> float:
    """(ω_max + spin + c/J_min) [1/s] of check_integrable's docstring, computed here from the
    scene's fields."""
    m, r, e, k, g, c = (float(getattr(scene, f)) for f in ("m", "r", "e", "k", "g", "damping"))
    kappa = float(scene.kappa)
    j_min = m * (k * k + (r - e) ** 2)
    omega = math.sqrt(m * g * (r * r * abs(kappa) / (1 - r * kappa) + e) / j_min)
    return omega + math.sqrt(max_torque / j_min) + c / j_min


def test_damping_beyond_what_can_be_integrated_is_refused_on_scenes_and_ranges():
    """Damping c [N·m·s/rad] decays φ' at c/J_min; from c = 1e6 on (paper) an adaptive step
    ran out of substeps and ended non-finite. Refused at construction, as a range too; just
    inside the limit a step is finite and within tolerance (the limit is not too generous)."""
    for kwargs in ({"scene": Scene(damping=1e6)}, {"randomize": {"damping": (0.0, 1e7)}}):
        for make in (lambda kw=kwargs: gym.make(STABILIZE, **kw),
                     lambda kw=kwargs: gym.make_vec(STABILIZE, num_envs=2, **kw)):
            with pytest.raises(ValueError, match=r"too long.*damping c/J_min"):
                make()
    base = _fastest_rate(preset("paper"), 0.5) * 0.05
    j_min = 1.0 * (0.1**2 + (0.1 - 0.04) ** 2)  # paper: m = 1, k = r = 0.1, e = 0.04
    limit = (1e4 - base) * j_min / 0.05  # c at 1e4 per step (0.05 s)
    with pytest.raises(ValueError, match=r"too long.*damping c/J_min"):
        gym.make(STABILIZE, scene=Scene(damping=limit * 1.01))
    # just inside (the tasks refuse such damping for their own reasons: the roller creeps)
    scene = Scene(damping=limit * 0.99)
    roller_gym.validation.check_integrable(scene, 0.05, 0.5, 1.0)
    for integrator in ("taylor", "rk8", "rk4"):
        stepper = roller_gym.physics.Stepper(scene, integrator=integrator, dt=0.05,
                                             tolerance=1e-8)
        step = stepper.advance(0.3, 0.0, 0.5)  # at rest: no damping force yet
        phi_dot, finite, tol_met = step[1], step[4], step[11]
        assert finite and tol_met, integrator
        # overdamped: φ' decays to the torque's creep (τ − dV/dφ)/c, near 0
        assert abs(phi_dot) < 1e-2


def test_an_action_of_any_real_dtype_steps_as_its_float64_value():
    """A longdouble action (or float16) steps the single env as float64 does, as the vector
    env's; one past float64's range is clipped to ±1 like any other."""
    def step(action):
        env = gym.make(STABILIZE)
        env.reset(seed=3)
        return env.step(action)[4]["phi"]

    assert step(np.array([0.3], np.longdouble)) == step(np.array([0.3]))
    assert step(np.array([0.5], np.float16)) == step(np.array([0.5]))
    huge = np.array([np.longdouble(10) ** 400])
    if np.isfinite(huge).all():  # where longdouble is wider than float64
        assert step(huge) == step(np.array([1.0]))


def test_a_masked_or_ragged_action_is_refused():
    masked = np.ma.array([0.5], mask=[True])
    env = gym.make(STABILIZE)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="masked"):
        env.step(masked)
    vec = gym.make_vec(STABILIZE, num_envs=2)
    vec.reset(seed=0)
    with pytest.raises(ValueError, match="masked"):
        vec.step(np.ma.array([[0.5], [0.1]], mask=[[False], [True]]))
    with pytest.raises(ValueError, match=r"action=\[\[0.1\], \[0.2, 0.3\]\] .* not a ragged"):
        vec.step([[0.1], [0.2, 0.3]])  # (NumPy's "inhomogeneous shape" before)


def test_a_torch_action_numpy_cannot_read_is_refused_by_name():
    """A tensor that requires grad, or of bfloat16, raised torch's RuntimeError or NumPy's
    TypeError, neither naming the action; now a ValueError that does and says what to pass.
    A plain tensor steps as its values."""
    torch = pytest.importorskip("torch")
    env = gym.make(STABILIZE)
    env.reset(seed=0)
    for bad in (torch.tensor([0.5], requires_grad=True), torch.tensor([0.5],
                                                                       dtype=torch.bfloat16)):
        with pytest.raises(ValueError, match=r"^action=.* cannot be read as numbers.*detach"):
            env.step(bad)
    _, _, _, _, info = env.step(torch.tensor([0.5]))
    assert info["torque"] == 0.5 * env.unwrapped.task.max_torque


def test_sizes_that_cannot_be_allocated_and_wrong_render_modes_are_refused_by_name():
    with pytest.raises(ValueError, match=r"num_envs=1099511627776 .*memory"):
        gym.make_vec(STABILIZE, num_envs=2**40)
    from roller_gym.roller_env import RollerEnv
    from roller_gym.vector_env import RollerVectorEnv

    for cls in (RollerEnv, RollerVectorEnv):
        with pytest.raises(ValueError, match="render_mode=1 is not allowed"):
            cls(render_mode=1)


def test_starts_on_a_nearly_flat_surface_stay_where_float64_meets_the_tolerance():
    """At R = 1e6 m, ψ = ±60° lies at φ ≈ ±1e7 rad, where float64's rounding of φ (≈ 2e-9
    rad) is a fifth of the default tolerance: 13 % of the steps from there reported
    tol_met=False. Starts stay within 64 turns of φ, and every step meets the tolerance.
    (Steps of FLAT_DT: in shorter episodes the bottom is out of reach from such a start.)"""
    env = gym.make(STABILIZE, scene=Scene(R=1e6), dt=FLAT_DT)
    starts, met = [], []
    for seed in range(30):
        _, info = env.reset(seed=seed)
        starts.append(info["phi"])
        for _ in range(3):
            met.append(env.step(env.action_space.sample())[4]["tol_met"])
    assert max(abs(p) for p in starts) <= 64 * 2 * math.pi
    assert max(abs(p) for p in starts) > 100.0  # still spread over many turns
    assert all(met)


def test_the_readmes_warning_on_a_first_reset_that_raised_holds_and_its_remedy_works():
    """Gymnasium's passive checker breaks after a first reset that raised (not this
    package's code): the README says so, and its remedy works."""
    readme = (Path(__file__).parent.parent / "README.md").read_text()
    assert "cannot unpack non-iterable NoneType" in readme
    assert "disable_env_checker=True" in readme
    for checked in (True, False):
        env = gym.make(STABILIZE, disable_env_checker=not checked)
        with pytest.raises(ValueError, match="options"):
            env.reset(seed=0, options={"bogus": 1})
        env.reset(seed=0)
        # The break comes with the checker's data-reuse check (Gymnasium 1.4; RLlib's 1.2.2
        # has no such check and recovers).
        checker = env.env.env if checked else None
        if checked and hasattr(checker, "checked_data_reuse"):  # what the README warns of
            assert isinstance(checker, gym.wrappers.PassiveEnvChecker)
            with pytest.raises(TypeError, match="cannot unpack non-iterable NoneType"):
                env.step(np.zeros(1, np.float32))
        else:
            assert np.isfinite(env.step(np.zeros(1, np.float32))[1])


# -- the physics API refuses what it cannot use, naming the argument -----------------------------
def _stepper(**kwargs):
    from roller_gym.physics import Stepper

    return Stepper(Scene(), **{"dt": 0.05, "tolerance": 1e-8, **kwargs})


def _batch(num=2, **kwargs):
    from roller_gym.physics import BatchStepper

    return BatchStepper(num, **{"dt": 0.05, "tolerance": 1e-8, **kwargs})


@pytest.mark.parametrize(
    ("call", "error", "message"),
    [
        (lambda: Scene(m=np.array([1.0, 2.0]), r=np.array([0.1, 0.1, 0.1])), ValueError,
         r"shapes \{'m': \(2,\), 'r': \(3,\)\} are not a batch"),
        (lambda: Scene(m=np.ones((2, 2))), ValueError, r"shapes \{'m': \(2, 2\)\} are not"),
        (lambda: Scene(m=np.array([])), ValueError, r"shapes \{'m': \(0,\)\} are not"),
        (lambda: Scene.stack([]), ValueError, r"scenes=\[\] must be a non-empty list"),
        (lambda: Scene.stack([Scene(m=np.ones(2))]), ValueError,
         r"scenes\[0\] is a batch of 2 rollers: stack takes scalar Scenes"),
        (lambda: Scene(m=np.ones(2)).item(True), ValueError, r"i=True is not a roller"),
        (lambda: preset([]), ValueError, r"unknown scene preset \[\]; allowed: "),
        (lambda: Scene(m=np.ma.array([1.0, 2.0], mask=[0, 1])), ValueError,
         r"Scene.m is a masked array"),
        (lambda: Scene(m=[[1.0], [1.0, 2.0]]), ValueError, r"Scene.m=.* is not a number or a 1-D"),
        (lambda: _batch().forget(7), ValueError, r"index=7 does not select rollers of the 2"),
        (lambda: _batch().advance(np.ma.array([0.1, 99.0], mask=[0, 1]), 0.0, 0.0), ValueError,
         r"phi is a masked array"),
        (lambda: analysis.equilibria(Scene(), resolution=0), ValueError,
         r"resolution=0 must be an integer in \[100, 1000000\]"),
        (lambda: analysis.equilibria(Scene(), tau=np.ones(2)), ValueError,
         r"tau=array\(\[1., 1.\]\) \[N·m\] must be a finite real number"),
        (lambda: analysis.holding_torque("paper", 0.0), TypeError,
         r"scene='paper' must be a Scene; for the preset"),
        (lambda: _stepper(dt=10**400), ValueError, r"dt=1000.* \[s\] must be a number, finite"),
        # a second pass: longdoubles past float64's range ran with dt = 0 or stepped from inf,
        # a timedelta passed as an integer, a bool index selected every roller, the analysis
        # took text and huge ints (TypeError, OverflowError), NumPy int16 scalars overflowed
        (lambda: _stepper(dt=np.longdouble("1e-4000")), ValueError, r"dt=.* must be a number"),
        (lambda: _stepper().advance(np.longdouble("1e4000"), 0.0, 0.0), ValueError,
         r"phi=.* is not finite \(as a float64\)"),
        (lambda: _stepper(integrator="rk4", substeps=np.timedelta64(5, "s")), ValueError,
         r"substeps=.* must be None"),
        (lambda: _batch(np.timedelta64(3, "s")), ValueError, r"num=.* must be an integer"),
        # a nineteenth review: a task took text for its torque, a timedelta was "out of range"
        (lambda: roller_gym.TASKS["RollerStabilize"]("1"), ValueError,
         r"max_torque='1' is not allowed: it must be a finite real number > 0 \[N·m\]"),
        (lambda: roller_gym.TASKS["RollerHold"](np.timedelta64(1, "s")), ValueError,
         r"max_torque=.* is not allowed: .*not timedelta64"),
        (lambda: _batch().set_scenes(Scene(m=2.0), True), ValueError,
         r"index=True does not select rollers"),
        (lambda: analysis.holding_torque(Scene(), "a"), ValueError, r"phi='a' must be numbers"),
        (lambda: analysis.energy(Scene(), 10**400, 0.0), ValueError, r"phi=1000.* must be num"),
        (lambda: _batch(10**400), ValueError, r"num=1000.* is too many"),
        (lambda: Scene(m=10**400), ValueError,
         r"Scene.m=1000.*\.\.\.0+ is out of range: an integer past float64's range"),
        (lambda: Scene(e=[0.05, -10**400]), ValueError, r"Scene.e=.* is out of range"),
        (lambda: Scene.stack([Scene(), "paper"]), TypeError,
         r"scenes\[1\]='paper' must be a Scene.*preset\('paper'\)"),
        (lambda: Scene().item(5), ValueError, r"i=5 is not a roller"),
        (lambda: Scene(m=np.ones(2)).item("a"), ValueError, r"i='a' is not a roller"),
        (lambda: _stepper().set_scene("paper"), TypeError, r"scene='paper' must be a Scene"),
        (lambda: _batch().set_scenes(None), TypeError, r"scene=None must be a Scene, not"),
        (lambda: _batch().set_scenes(Scene(), index=5), ValueError,
         r"index=5 does not select rollers of the 2"),
        (lambda: _stepper(dt=True), ValueError, r"dt=True \[s\] must be a number"),
        (lambda: _stepper(tolerance=np.True_), ValueError, r"tolerance=np\.True_ must be a number"),
        (lambda: _stepper(integrator="rk4", substeps=True), ValueError,
         r"substeps=True must be None"),
        (lambda: _batch(True), ValueError, r"num=True must be an integer >= 1"),
        (lambda: _stepper().advance(None, 0.0, 0.0), ValueError, r"phi=None must be a real number"),
        (lambda: _stepper().advance("1", 0.0, 0.0), ValueError, r"phi='1' must be a real number"),
        (lambda: _stepper().advance(0.0, math.nan, 0.0), ValueError, r"phi_dot=nan is not finite"),
        (lambda: _stepper().advance(True, 0.0, 0.0), ValueError,
         r"phi=True must be a real number, not bool"),
        (lambda: step(Scene(), np.zeros(2), np.zeros(3), 0.0, 0.05), ValueError,
         r"the shapes \{'phi': \(2,\), 'phi_dot': \(3,\), 'tau': \(\)\} and the scene's"),
        (lambda: _stepper().advance(0.0, np.True_, 0.0), ValueError,
         r"phi_dot=np\.True_ must be a real number"),
        (lambda: step(Scene(), 0.0, 0.0, np.array([0.0, math.inf]), 0.05), ValueError,
         r"tau=array\(\[ 0., inf\]\) is not finite"),
        (lambda: _batch(2**50), ValueError, r"num=1125899906842624 is too many: .* GiB"),
        (lambda: roller_gym.physics.integrators.contact_state(Scene(), 0.1, 0.2, 0.0),
         ValueError, r"phi=0.1 must be a 1-D array of states"),
        (lambda: _batch().advance(np.zeros(3), 0.0, 0.0), ValueError,
         r"phi has 3 values for 2 rollers"),
        (lambda: _batch().advance(np.zeros(2), 0.0, np.array([0.0, np.inf])), ValueError,
         r"tau=array\(\[ 0., inf\]\) is not finite"),
        (lambda: step(Scene(), "0.1", 0.0, 0.0, 0.05), ValueError,
         r"phi='0.1' must be real numbers \(a number or an array\)"),
        (lambda: predicted_substeps(Scene(), math.nan, 0.05, 1e-8, "euler"), ValueError,
         r"phi_dot=nan is not finite"),
        (lambda: RollerEnv(task="roller_gym/RollerStabilize-v0"), ValueError,
         r"not a registered ID; RollerStabilize's is 'roller_gym/RollerStabilize-v\d+'"),
        (lambda: RollerEnv(task="foo/RollerHold"), ValueError,
         r"task='foo/RollerHold' is not a registered ID"),
        (lambda: RollerEnv(task=roller_gym.task.Task), ValueError,
         r"is not a registered task"),
    ],
)
def test_the_physics_api_refuses_bad_arguments_naming_them(call, error, message):
    """Scenes whose fields are not one batch (they built, and failed later in NumPy), a
    preset's name or None where a Scene goes (AttributeError), bools where numbers go (a
    step of True seconds ran), an index past the rollers (IndexError); a task ID of another
    version or namespace (it built the current task), the base class Task (AttributeError);
    states that are not finite real numbers (None and NaN stepped to NaN, "1" and True to 1
    rad); a batch too large for the memory (NumPy's MemoryError), a Python int past float's
    range (OverflowError); masked arrays (the data under the mask was used), ragged lists,
    a batch where scalars go, the analysis's arguments (NumPy's and numba's errors)."""
    with pytest.raises(error, match=message):
        call()


#: An integer Python refuses to write in decimal (past ``sys.get_int_max_str_digits()``).
_HUGE = 10**5000


@pytest.mark.parametrize("call, argument", [
    (lambda: gym.make("roller_gym/RollerStabilize-v2", dt=_HUGE), "dt"),
    (lambda: gym.make("roller_gym/RollerStabilize-v2", randomize={"m": (1, _HUGE)}),
     r"randomize\['m'\]\[1\]"),
    (lambda: gym.make("roller_gym/RollerStabilize-v2", randomize={_HUGE: (1, 2)}),
     "randomize names"),
    (lambda: gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=_HUGE), "num_envs"),
    (lambda: gym.make("roller_gym/RollerStabilize-v2").reset(seed=_HUGE), "seed"),
    (lambda: gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=2).reset(seed=[_HUGE, 1]),
     "seed"),
    (lambda: gym.make("roller_gym/RollerHold-v2").reset(options={_HUGE: 1}), "reset options"),
    (lambda: gym.make("roller_gym/RollerHold-v2").reset(options={"state": (_HUGE, 0)}),
     r"options\['state'\]"),
    (lambda: RollerEnv(integrator=_HUGE), "integrator"),
    (lambda: Scene(R=_HUGE), r"Scene\.R"),
    (lambda: _stepper(substeps=_HUGE), "substeps"),
    (lambda: _stepper().advance(0.0, 0.0, _HUGE), "tau"),
])
def test_an_integer_too_long_to_write_is_refused_by_name(call, argument):
    """Python will not write an integer past 4,300 digits: the message names the argument and
    describes the value, instead of Python's own error about string conversion."""
    with pytest.raises(ValueError, match=f"^{argument}.*<an? (integer of about 5001 digits|"
                                         "(list|tuple) holding a value Python cannot write)>"):
        call()


def test_a_start_state_is_refused_for_its_own_reason():
    """φ past the sines' domain (2⁵⁰ rad) is named as such (it was refused as too fast, at
    zero speed, with N/(m g) = nan), and a state at rest that slips asks for another φ or
    more friction, not for less speed."""
    env = gym.make(STABILIZE)
    with pytest.raises(ValueError, match=r"phi must be within ±1.126e\+15 rad"):
        env.reset(options={"state": (1e17, 0.0)})
    slippery = gym.make(STABILIZE, scene=Scene(mu=0.3))
    with pytest.raises(ValueError, match=r"choose another phi, where the roller rests"):
        slippery.reset(options={"state": (2.7, 0.0)})
    env.reset(options={"state": (1e12, 0.0)})  # within the domain: a state like any other


def test_a_refused_reset_leaves_the_episodes_as_they_were():
    """A reset whose options are refused changes nothing: the next reset starts the episode
    a twin environment that never saw the refused call starts (the episode count and the
    vector env's seeds moved on before the options were checked)."""
    single, twin = gym.make(HOLD), gym.make(HOLD)
    single.reset(seed=3), twin.reset(seed=3)
    with pytest.raises(ValueError, match="target"):
        single.reset(options={"target": 1.0})
    np.testing.assert_array_equal(single.reset()[0], twin.reset()[0])
    vec, twin_vec = gym.make_vec(HOLD, num_envs=2), gym.make_vec(HOLD, num_envs=2)
    vec.reset(seed=5), twin_vec.reset(seed=5)
    with pytest.raises(ValueError, match="state"):
        vec.reset(seed=99, options={"state": "bad"})
    np.testing.assert_array_equal(vec.reset()[0], twin_vec.reset()[0])


def test_a_reset_option_a_sub_environments_scene_refuses_names_it():
    """With a scene per sub-environment, the one whose scene refuses a reset option is
    named with its scene (the message said "this scene")."""
    vec = gym.make_vec(STABILIZE, num_envs=3, scene=["paper", Scene(mu=0.3), "paper"])
    with pytest.raises(ValueError, match=r"the roller of sub-environment 1 \(Scene\(.*mu=0.3"):
        vec.reset(options={"state": (2.7, 0.0)})
    hold = gym.make_vec(HOLD, num_envs=2, scene=["paper", Scene(m=2.0)])
    with pytest.raises(ValueError, match=r"sub-environment 1 \(Scene\(m=2.0.*cannot be held"):
        hold.reset(options={"target": 0.3})  # (paper holds up to 0.43 rad)


def test_numpy_integer_fields_are_the_same_scene_as_floats():
    """A Scene of NumPy int16 scalars gave J_I = -10581 where floats give 54955 (k*k
    overflowed in int16): every field is stored as a float."""
    ints = Scene(m=np.int16(1), r=np.int16(150), R=np.int16(1000), e=np.int16(30),
                 k=np.int16(200), g=np.int16(10))
    floats = Scene(m=1.0, r=150.0, R=1000.0, e=30.0, k=200.0, g=10.0)
    assert analysis.moment_of_inertia(ints, 0.3) == analysis.moment_of_inertia(floats, 0.3)
    assert all(type(getattr(ints, name)) is float for name in ("m", "r", "R", "e", "k", "g"))


def test_a_masked_reset_mask_is_refused():
    """(Its mask was ignored: every sub-environment reset.)"""
    vec = gym.make_vec(STABILIZE, num_envs=3, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match=r"(?s)options\['reset_mask'\]=.*not a masked array"):
        vec.reset(options={"reset_mask": np.ma.array([True] * 3, mask=[1, 1, 0])})


def test_the_reference_scheme_gives_up_a_step_it_cannot_finish_in_the_budget():
    """dop853 (scipy, in Python) at 1e8 rad/s would take ~1e9 substeps: it fails the step,
    as the compiled schemes do past MAX_SUBSTEPS, instead of running for hours; at 1e3 rad/s
    it still finishes, within tol of rk8 at a tight tolerance relative to the state."""
    from roller_gym.physics.integrators import MAX_SUBSTEPS

    r = step(preset("paper"), 0.0, 1e8, 0.0, 0.05, integrator="dop853", tolerance=1e-8)
    assert not r.finite and not r.tol_met and 0 < r.substeps < MAX_SUBSTEPS
    # (an environment refuses such a start at reset: see the test below on fast starts)
    fast = step(preset("paper"), 0.0, 1e3, 0.0, 0.05, integrator="dop853", tolerance=1e-8)
    ref = step(preset("paper"), 0.0, 1e3, 0.0, 0.05, integrator="rk8", tolerance=1e-12)
    error = max(abs(fast.phi - ref.phi), abs(fast.phi_dot - ref.phi_dot))
    # (scipy's tolerance is relative, tol_met's absolute: at φ' ≈ 1e3 rad/s it is missed, and
    # the check against a tighter run says so)
    assert fast.finite and abs(fast.phi - ref.phi) <= 1e-8 * abs(ref.phi)
    assert not fast.tol_met and 0.5 * error <= fast.error_estimate <= 2.0 * error


@pytest.mark.parametrize("integrator", ["euler", "midpoint"])
def test_fixed_substeps_claim_the_tolerance_only_where_the_prediction_meets_it(integrator):
    """With ``substeps`` fixed, euler and midpoint have no error estimate: tol_met says what
    their prediction says, so it is never True on a step that misses tol against a reference
    (DOP853 at 1e-13), on 40 random states of rim_mass, and it is True where the substeps are
    as many as the prediction asks for."""
    scene, tol, dt = preset("rim_mass"), 1e-8, 0.05
    rng = np.random.default_rng(11)
    for phi, w, tau in zip(rng.uniform(-3, 3, 40), rng.uniform(-5, 5, 40),
                           rng.uniform(-0.3, 0.3, 40), strict=True):
        got = step(scene, phi, w, tau, dt, integrator=integrator, substeps=1, tolerance=tol)
        ref = step(scene, phi, w, tau, dt, integrator="dop853", tolerance=1e-13)
        if abs(got.phi - ref.phi) > tol or abs(got.phi_dot - ref.phi_dot) > tol:
            assert not got.tol_met, (phi, w, tau)
    mild = preset("paper")
    need = int(predicted_substeps(mild, 0.5, dt, 1e-3, integrator))
    assert 4 <= need < 1000
    for n, met in ((need, True), (need // 4, False)):
        assert step(mild, 0.0, 0.5, 0.0, dt, integrator=integrator, substeps=n,
                    tolerance=1e-3).tol_met is met


def test_a_refused_vector_step_leaves_the_torque_as_it_was():
    """A step refused (an ended episode under DISABLED autoreset, or before any reset)
    leaves the torque the environment holds (and render() draws) unchanged."""
    v = gym.make_vec(HOLD, num_envs=2, autoreset_mode="disabled", max_episode_steps=1)
    with pytest.raises(RuntimeError, match="call reset"):
        v.step(np.ones((2, 1)))
    np.testing.assert_array_equal(v.unwrapped.torque, [0.0, 0.0])
    v.reset(seed=0)
    v.step(np.zeros((2, 1)))
    with pytest.raises(RuntimeError, match="have ended"):
        v.step(np.ones((2, 1)))
    np.testing.assert_array_equal(v.unwrapped.torque, [0.0, 0.0])


def test_an_empty_batch_steps_to_an_empty_result_and_shapes_that_do_not_broadcast_say_so():
    r = step(preset("paper"), np.zeros(0), 0.0, 0.0, 0.05)
    ref = step(preset("paper"), np.zeros(1), 0.0, 0.0, 0.05)
    for name in ("phi", "substeps", "tol_met"):
        got, one = getattr(r, name), getattr(ref, name)
        assert got.shape == (0,) and got.dtype == one.dtype, name
    with pytest.raises(ValueError, match=r"phi_dot of shape \(2,\) and the scene's batch of 3"):
        predicted_substeps(Scene(m=[1.0, 1.0, 1.0]), np.zeros(2), 0.05, 1e-8, "euler")


def test_a_vector_seed_may_be_a_range_as_its_message_allows():
    vec, twin = gym.make_vec(STABILIZE, num_envs=3), gym.make_vec(STABILIZE, num_envs=3)
    np.testing.assert_array_equal(vec.reset(seed=range(3))[0], twin.reset(seed=[0, 1, 2])[0])


# -- a fourth adversarial pass -------------------------------------------------------------

def test_dop853_claims_the_tolerance_only_where_a_tighter_run_agrees():
    """scipy's error control is local to its own norm: on this tight_fit step it missed 1e-8
    by 20×, and tol_met said True. The step is now checked against a second run; its estimate
    is the true error (against taylor at 1e-13, an independent scheme) within a factor 2."""
    scene, state = preset("tight_fit"), (-0.7301288091051612, -9.94113466414542,
                                         -0.5197118831966243)
    truth = step(scene, *state, 0.05, integrator="taylor", tolerance=1e-13)
    for tol in (1e-6, 1e-8, 1e-10):
        r = step(scene, *state, 0.05, integrator="dop853", tolerance=tol)
        error = max(abs(r.phi - truth.phi), abs(r.phi_dot - truth.phi_dot))
        assert error > tol and not r.tol_met
        assert 0.5 * error <= r.error_estimate <= 2.0 * error
    rng = np.random.default_rng(20261127)  # fresh steps: the flag never overclaims
    for _ in range(12):
        scene = preset(str(rng.choice(["tight_fit", "balance", "rim_mass", "paper"])))
        phi, phi_dot, tau = rng.uniform(-3, 3), rng.uniform(-10, 10), rng.uniform(-0.5, 0.5)
        r = step(scene, phi, phi_dot, tau, 0.05, integrator="dop853", tolerance=1e-8)
        truth = step(scene, phi, phi_dot, tau, 0.05, integrator="taylor", tolerance=1e-13)
        if r.tol_met:
            assert max(abs(r.phi - truth.phi), abs(r.phi_dot - truth.phi_dot)) <= 2e-8


def test_a_step_that_ends_in_slip_or_lift_off_is_never_a_success():
    """On tight_fit, random torques make the roller slip within the success band: the step
    terminated and slipped, and is_success said True (9,131 of 57,766 terminating steps)."""
    env = gym.make_vec("roller_gym/RollerStabilize-v2", num_envs=64, scene="tight_fit",
                       vectorization_mode="vector_entry_point")
    env.reset(seed=1)
    rng = np.random.default_rng(1)
    failed = 0
    for _ in range(100):
        _, _, terminated, _, info = env.step(rng.uniform(-1, 1, (64, 1)))
        ended = info["slipping"] | info["lifting"] | info["nonfinite"]
        failed += int(ended.sum())
        assert not (info["is_success"] & ended).any()
        assert (terminated == ended).all()
    assert failed > 0  # the case arose


def test_a_start_too_fast_to_integrate_is_refused_at_reset():
    """φ' = 1e8 rad/s was accepted, and every first step then failed (taylor, rk8) or took a
    minute (dop853). The limit is 1e4 rad per step for the fastest angle: in a tight fit
    θ = φ/(1 − rκ), 101× φ on tight_fit, where 1.9e5 rad/s passed a limit on φ alone and
    the first step ended non-finite; 0.99× the limit steps there, as on the paper scene."""
    env = gym.make("roller_gym/RollerStabilize-v2").unwrapped  # (Gymnasium's checker breaks
    paper = roller_gym.physics.PRESETS["paper"]  # after a refusal)
    limit = 1e4 * (1 - paper.r / paper.R) / 0.05
    with pytest.raises(ValueError, match=r"options\['state'\]=\(0\.0, 100000000\.0\): phi_dot "
                                         + re.escape(f"must be within ±{limit:.4g} rad/s")):
        env.reset(options={"state": (0.0, 1e8)})
    tight = gym.make("roller_gym/RollerStabilize-v2", scene="tight_fit").unwrapped
    fit = roller_gym.physics.PRESETS["tight_fit"]
    tight_limit = 1e4 * (1 - fit.r / fit.R) / 0.05
    with pytest.raises(ValueError, match=re.escape(f"must be within ±{tight_limit:.4g} rad/s")):
        tight.reset(options={"state": (0.0, 1.9e5)})
    for e, fastest in ((env, limit), (tight, tight_limit)):
        e.reset(options={"state": (0.0, 0.99 * fastest)})  # within the limit: it steps
        with pytest.warns(RuntimeWarning, match="not verified"):
            assert not e.step(np.zeros(1, np.float32))[4]["nonfinite"]


def test_the_fourth_pass_inputs_get_messages_naming_them():
    class BadRepr:
        def __repr__(self):
            raise RuntimeError("repr boom")

    class Unregistered(roller_gym.task.Task):
        pass

    vector = gym.make_vec("roller_gym/RollerHold-v2", num_envs=3,
                          vectorization_mode="vector_entry_point")
    cases = [
        (lambda: gym.make("roller_gym/RollerHold-v2", dt=BadRepr()), r"dt=<a BadRepr object>"),
        (lambda: Scene(m=BadRepr()), r"Scene\.m=<a BadRepr object>"),
        (lambda: vector.reset(seed=np.array(3)), r"seed=array\(3\) must be None"),
        (lambda: analysis.nearest_unstable_rests([0.1], [1.0], [0.08], -1),
         r"resolution=-1 must be an integer in \[100, 1000000\]"),
        (lambda: analysis.nearest_unstable_rests([math.nan], [1.0], [0.08]),  # (it hung)
         r"r=\[nan\] must be finite numbers"),
        (lambda: analysis.nearest_unstable_rests([0.1, 0.2], [1.0], [0.08, 0.08]),
         r"kappa=array\(\[1\.\]\) must be finite real numbers, as many as r's 2"),
        (lambda: RollerEnv(Unregistered), r"task=.*Unregistered.* is not registered"),
    ]
    for call, message in cases:
        with pytest.raises(ValueError, match=message):
            call()


def test_the_analysis_takes_lists_as_arrays():
    scene = preset("paper")
    for f, args in ((analysis.energy, ([1.0, 2.0], [0.0, 0.5])),
                    (analysis.moment_of_inertia, ([1.0, 2.0],)),
                    (analysis.holding_torque, ([0.1, 0.2],))):
        np.testing.assert_array_equal(f(scene, *args), f(scene, *map(np.array, args)))


def test_the_analysis_refuses_what_is_not_finite_and_never_shows_rolling_it_did_not_compute():
    """The physics' analysis functions passed NaN and inf through (holding_torque, energy,
    acceleration, linearize, contact), and contact reported a roller rolling (lifting and
    slipping False) where its forces overflowed to NaN (φ' = 1e200 rad/s: refused now,
    see test_the_analysis_refuses_a_speed_whose_square_overflows)."""
    paper = roller_gym.physics.PRESETS["paper"]
    physics = roller_gym.physics
    cases = [(physics.holding_torque, (math.nan,), "phi=nan"),
             (physics.energy, (0.0, math.inf), "phi_dot=inf"),
             (physics.acceleration, (0.0, 0.0, np.array([0.1, math.nan])), r"tau=array"),
             (physics.linearize, (math.nan,), "phi=nan"),
             (physics.contact, (0.0, -math.inf, 0.0), "phi_dot=-inf")]
    for function, args, name in cases:
        with pytest.raises(ValueError, match=name + r".* must be finite numbers"):
            function(paper, *args)
    near = physics.contact(paper, 0.0, 1.0, 0.0)  # at rest speeds, as before: it rolls
    assert near.liftoff_margin > 0 and not near.lifting and not near.slipping


@pytest.mark.parametrize("env_id", ["roller_gym/RollerHold-v2", "roller_gym/RollerTrack-v1",
                                    "roller_gym/RollerSwing-v1"])
def test_a_nearly_flat_cylinder_or_drum_gives_finite_targets(env_id):
    """|R| near float64's top made π/|q| overflow, and reset handed back a NaN target and
    observation. The held range is within START_TURNS turns of φ, so it stays finite."""
    dt = {} if "RollerSwing" in env_id else {"dt": FLAT_DT}
    for scene in (Scene(R=1e307), Scene(R=-1e307)):
        env = gym.make(env_id, scene=scene, **dt).unwrapped
        for seed in range(3):
            obs, info = env.reset(seed=seed)
            assert np.isfinite(obs).all() and np.isfinite(info["target_phi"]), (scene, seed)
    if "RollerSwing" in env_id:  # (no randomize range: its scenes are checked one by one)
        vec = gym.make_vec(env_id, num_envs=4, scene=[Scene(R=1e307), "paper"] * 2)
    else:
        vec = gym.make_vec(env_id, num_envs=4, randomize={"R": (0.3, 1e307)}, **dt)
    obs, info = vec.reset(seed=0)
    assert np.isfinite(obs).all() and np.isfinite(info["target_phi"]).all()


@pytest.mark.parametrize("R", [2.0, 1000.0, 1e5, 1e15])
def test_every_held_target_needs_at_most_the_share_of_the_torque_it_promises(R):
    """On a large cylinder the grid of the held range was spaced wider than a turn of φ and
    missed the e sin φ of the holding torque: targets needed up to 1.2× max_torque. Every
    drawn target's holding torque (the physics' own, independent of the range's walk) is
    now within max_torque, with the 0.8 share up to what the grid between points can miss."""
    scene = Scene(R=R, e=0.07)  # (at e = 0.08 on R = 2 m a far start must slip: descent)
    env = gym.make("roller_gym/RollerHold-v2", scene=scene, dt=FLAT_DT).unwrapped
    torques = []
    for seed in range(100):
        _, info = env.reset(seed=seed)
        torques.append(abs(float(roller_gym.physics.holding_torque(scene,
                                                                   info["target_phi"]))))
    assert max(torques) <= 0.85 * env.task.max_torque, max(torques)


def test_swing_refuses_a_scene_whose_target_swing_has_no_energy():
    """A concentric roller on the floor has a flat potential: E* = 0 and the reward
    E/E* − 1 was NaN on every step; without friction in a cylinder, nothing beyond the
    bottom is held; on a drum with a concentric roller the potential falls from the top on
    (targets were drawn below the start, E* < 0: no swing turns back there, and the roller
    slips off). Refused by name at construction, on ranges too; a floor with an eccentric
    mass, a cylinder with friction, and a drum whose eccentric mass makes a well at the top
    (targets within it: the energy pump succeeds there, below) stay allowed."""
    for scene in (Scene(R=math.inf, e=0.0), Scene(mu=0.0), Scene(R=-0.5, e=0.0)):
        with pytest.raises(ValueError, match=r"gives a target swing no energy: E\* = 0 J"):
            gym.make("roller_gym/RollerSwing-v1", scene=scene)
    with pytest.raises(ValueError, match=r"randomize=\{'e': \(0\.0, 0\.05\)\} cannot be used "
                                         r"with RollerSwing: .* use a fixed scene"):
        gym.make("roller_gym/RollerSwing-v1", scene="floor", randomize={"e": (0.0, 0.05)})
    for kwargs in ({"scene": "floor"}, {"scene": "drum"}):
        env = gym.make("roller_gym/RollerSwing-v1", **kwargs)
        env.reset(seed=0)
        rewards = [env.step(np.zeros(1, np.float32))[1] for _ in range(3)]
        assert np.isfinite(rewards).all(), kwargs


@pytest.mark.parametrize("scene", ["balance", Scene(R=2.0), Scene(R=10.0), Scene(R=1e3)],
                         ids=["balance", "R=2", "R=10", "R=1e3"])
def test_swing_targets_lie_before_the_first_barrier_and_no_start_succeeds_unpumped(scene):
    """On a nearly flat cylinder the potential V(φ) = m g ((R − r)(1 − cos ψ) + e (1 − cos φ))
    has the eccentric mass's barriers long before friction stops holding: targets lay past
    them (E* = V(φ*) then is no swing turning back at φ*), and starts up to 64 turns out had
    the target's energy at rest (7–21 % of zero-torque episodes succeeded at R = 1e3 m).
    Every drawn amplitude now lies where V rises all the way from the bottom (checked on a
    grid of 2,000 points by the physics' own energy), and no zero-torque episode succeeds."""
    env = gym.make("roller_gym/RollerSwing-v1", scene=scene)
    physics_scene = env.unwrapped.scene
    for seed in range(20):
        _, info = env.reset(seed=seed)
        target = info["target_phi"]
        potential = np.asarray(roller_gym.physics.energy(
            physics_scene, np.linspace(0.0, target, 2000), 0.0))
        assert np.all(np.diff(potential) > 0.0), (seed, target)
        for _ in range(100):
            _, _, terminated, truncated, info = env.step(np.zeros(1, np.float32))
            assert not info["is_success"], (seed, info)
            if terminated or truncated:
                break


def test_swing_refuses_target_swings_that_cannot_roll_or_be_pumped_and_every_range():
    """The preset "rim_mass" was accepted, yet a swing of the target's energy lifted off in
    2–5 steps; damping 0.02 capped the energy at 0.32 J below every E* (0.59–1.21 J). Both are
    refused by name; the check's margins agree with the contact the environment reports on
    the paper preset's largest swing (independently: a zero-torque episode started on it
    rolls all 400 steps); and randomize ranges are refused, also where every corner poses
    the task, as no proof covers them."""
    with pytest.raises(ValueError, match=r"poses target swings that cannot roll: .*N/\(m g\) "
                                         r"falls to -"):
        gym.make("roller_gym/RollerSwing-v1", scene="rim_mass")
    with pytest.raises(ValueError, match=r"damping=0\.02 N·m·s/rad of .* more than 0\.8 of "
                                         r"max_torque=0\.1 N·m: the pump cannot reach"):
        gym.make("roller_gym/RollerSwing-v1", scene=Scene(damping=0.02))
    for ranges in ({"e": (0.02, 0.09), "R": (0.3, 1.5)}, {"m": (0.9, 1.1)}):
        with pytest.raises(ValueError, match=r"cannot be used with RollerSwing: .* use a fixed "
                                             r"scene"):
            gym.make("roller_gym/RollerSwing-v1", randomize=ranges)
    env = gym.make("roller_gym/RollerSwing-v1")
    task, scene = env.unwrapped.task, env.unwrapped.scene
    top = task.amplitude_ranges(scene)[1][0] * task.amplitude_shares[1]
    lift, slip, _ = task.rolling_margins(scene, np.array([top]))
    assert lift > 0.5 and slip > 0.3
    env.reset(seed=0, options={"state": (float(top), 0.0)})
    for _ in range(400):
        _, _, terminated, _, info = env.step(np.zeros(1, np.float32))
        assert not terminated and info["normal_force"] > 0, info


@pytest.mark.parametrize("scene", ["floor", "balance", Scene(R=2.0), Scene(R=5.0)])
def test_swing_targets_cannot_spin_over_the_top_within_the_success_band(scene):
    """On the floor 11 % of episodes drew a target whose success band's energy, 1.1 E*, lay
    above the barrier at φ = π: the roller spun over the top, reported a success on every
    step. Every drawn target's 1.1 E* is now below the potential's first barrier, found
    here independently (the physics' own energy on a grid out to ψ = ±π or 64 turns)."""
    env = gym.make("roller_gym/RollerSwing-v1", scene=scene)
    physics_scene = env.unwrapped.scene
    far = min(math.pi / abs(angle_rate(physics_scene)), 2 * math.pi * 64)
    grid = np.asarray(roller_gym.physics.energy(physics_scene, np.linspace(0, far, 40001), 0.0))
    barrier = grid[np.argmax(np.diff(grid) <= 0)] if np.any(np.diff(grid) <= 0) else grid[-1]
    for seed in range(200):
        _, info = env.reset(seed=seed)
        target_energy = float(roller_gym.physics.energy(physics_scene, info["target_phi"], 0.0))
        assert 1.1 * target_energy <= barrier * (1 + 1e-6), (seed, info["target_phi"])


def test_a_dt_too_long_for_the_tasks_own_start_speeds_is_refused_at_construction():
    """A slow, large scene passed the check of its own rates, but the drawn start speeds
    (up to 1 rad/s) turned 1e6 rad in a step: every episode failed its first step. The
    construction counts the task's start speed; a task starting at rest is not limited by
    it; and what is accepted steps finitely from its drawn starts."""
    big = Scene(r=1e10, R=5e10, e=4e9, k=1e10)  # (the swing's period: 2.9e5 s)
    with pytest.raises(ValueError, match=r"dt=100000\.0 s is too long .* starts up to 1 rad/s"):
        gym.make("roller_gym/RollerStabilize-v2", scene=big, dt=1e5)
    # starts at rest (with a torque that can pump the large scene's swing in its episode, and
    # a dt that samples the swing at least twice a period)
    gym.make("roller_gym/RollerSwing-v1", scene=big, dt=1e5, max_torque=1e9)
    for env_id in roller_gym.ENV_IDS:
        task = gym.make(env_id).unwrapped.task
        grid = np.linspace(0.0, 1.0, 11)[None]
        _, speeds = task.start_candidates(grid, grid, roller_gym.preset(task.default_scene))
        assert np.abs(speeds).max() <= task.start_speed, env_id
    # (with a torque that holds its starts: at 0.5 N·m one moving in at 1 rad/s must slip)
    env = gym.make("roller_gym/RollerStabilize-v2", scene=big, dt=4e3, max_torque=1e11)
    for seed in range(5):
        env.reset(seed=seed)
        assert not env.step(np.zeros(1, np.float32))[4]["nonfinite"]


def test_a_scene_past_float64s_range_is_refused_not_rounded_to_inf_or_zero():
    """A longdouble R of 1e400 became a floor (inf) and an e of 1e-400 became 0, silently;
    an |R| so small that 1/R overflows gave NaN everywhere and an error blaming dt."""
    for kwargs, message in (
            ({"R": np.longdouble("1e400")}, r"Scene\.R=.* past float64's range"),
            ({"e": np.longdouble("1e-400")}, r"Scene\.e=.* past float64's range"),
            ({"R": -5e-324}, r"Scene\.R=-5e-324 is out of range: its curvature 1/R"),
            ({"r": 5e-324, "R": 1e-323}, r"Scene\.R=1e-323 is out of range: its curvature")):
        with pytest.raises(ValueError, match=message):
            Scene(**kwargs)
    assert Scene(R=np.longdouble("0.5")) == Scene(R=0.5)


def test_the_analysis_refuses_an_angle_beyond_where_the_sines_are_defined():
    """φ = 1e300 gave NaN from the analysis, and an error naming tau, an argument the user
    never passed; the environments' own limit (trig.DOMAIN) now holds there too."""
    paper = preset("paper")
    for call in (lambda: roller_gym.physics.acceleration(paper, 1e300, 0.0, 0.0),
                 lambda: roller_gym.physics.small_oscillation_frequency(paper, 1e300),
                 lambda: roller_gym.physics.energy(paper, [0.0, 2.0**51], 0.0)):
        with pytest.raises(ValueError, match=r"^phi=.* must be within ±1\.126e\+15 rad"):
            call()
    assert np.isfinite(roller_gym.physics.acceleration(paper, 2.0**49, 0.0, 0.0))



def test_tracks_target_stays_within_the_sines_domain_wherever_a_dt_is_accepted():
    """The moving target's sines turned NaN once ω t passed 2⁵⁰ rad (dt = 1e16 s on a huge
    scene): observation and reward NaN, unflagged. Such a dt is refused by the start speeds'
    rate; the longest dt any accepted scene allows, 1e4 rad per step at 1 rad/s, keeps the
    target's phase (0.8 rad/s, 400 steps) far inside the domain."""
    big = Scene(r=1e29, R=5e29, e=4e28, k=1e29)
    with pytest.raises(ValueError, match=r"dt=1e\+16 s is too long .* starts up to 1 rad/s"):
        gym.make("roller_gym/RollerTrack-v1", scene=big, dt=1e16)
    assert 0.8 * 400 * 1e4 / 1.0 + 2 * math.pi < 2.0**50


def test_a_surface_so_flat_that_r_kappa_underflows_is_the_floor_not_a_crash():
    """r κ = 1e-17/1e308 underflows to 0: the equilibria's window divided by it
    (ZeroDivisionError, through Balance's construction too). Such a surface is the floor's
    case: a uniform roller has no isolated rest position, and Balance refuses it by name."""
    flat = Scene(r=1e-17, R=1e308, e=0.0, k=1e-17)
    assert roller_gym.physics.equilibria(flat) == []
    for env_id in ("roller_gym/RollerBalance-v2", "roller_gym/RollerBalanceWeak-v0"):
        with pytest.raises(ValueError, match=r"has no unstable rest position to balance at"):
            gym.make(env_id, scene=flat, max_torque=1e-30)


def test_the_analysis_refuses_a_speed_whose_square_overflows():
    """φ' = 1e160 rad/s gave NaN forces, which contact showed as lift-off and slip; the
    analysis now refuses |φ'| past 1e150 rad/s by name, and computes finitely up to it."""
    paper = preset("paper")
    for call in (lambda: roller_gym.physics.acceleration(paper, 0.0, 1e160, 0.0),
                 lambda: roller_gym.physics.contact(paper, 0.0, [0.0, -1e200], 0.0),
                 lambda: roller_gym.physics.energy(paper, 0.0, 1e200)):
        with pytest.raises(ValueError, match=r"^phi_dot=.* must be within ±1e\+150 rad/s"):
            call()
    c = roller_gym.physics.contact(paper, 0.0, 1e150, 0.0)
    assert np.isfinite([c.normal, c.friction]).all()
    assert np.isfinite(roller_gym.physics.energy(paper, 0.0, 1e150))


def test_the_task_helpers_refuse_bad_arguments_naming_them():
    """hold_ranges took NaN or a negative torque limit as an empty range, truncated a
    fractional grid, and gave AttributeError for a preset's name; each is now refused by
    name (the rates too), and math.inf stays the limit of no limit."""
    from roller_gym import task

    paper = preset("paper")
    for call, error, message in (
            (lambda: task.hold_ranges(paper, float("nan")), ValueError, r"^max_torque=nan"),
            (lambda: task.hold_ranges(paper, -1.0), ValueError, r"^max_torque=-1\.0"),
            (lambda: task.hold_ranges(paper, "1"), ValueError, r"^max_torque='1'"),
            (lambda: task.hold_ranges(paper, 1.0, points=2.5), ValueError, r"^points=2\.5"),
            (lambda: task.hold_ranges(paper, 1.0, points=2**70), ValueError, r"^points="),
            (lambda: task.hold_ranges(paper, 1.0, friction_share=-1), ValueError,
             r"^friction_share=-1 must be a real number in \(0, 1\]"),
            (lambda: task.hold_range(paper, [1.0]), ValueError, r"^max_torque=\[1\.0\]"),
            (lambda: task.hold_ranges("paper", 1.0), TypeError, r"use preset\('paper'\)"),
            (lambda: task.wrap_rate("paper"), TypeError, r"^scene='paper' must be a Scene"),
            (lambda: task.angle_rate(None), TypeError, r"^scene=None must be a Scene")):
        with pytest.raises(error, match=message):
            call()
    low, high = task.hold_ranges(paper, math.inf)
    assert low[0] < 0 < high[0]


@pytest.mark.parametrize(("env_id", "damping"), [("roller_gym/RollerBalance-v2", 0.1),
                                                 ("roller_gym/RollerBalanceWeak-v0", 0.02)])
def test_balance_refuses_damping_the_swing_up_cannot_outrun(env_id, damping):
    """Damping 0.1 (Balance) or 0.02 (BalanceWeak) was accepted, yet the most power a policy
    can put in, τ = max_torque·sgn(φ'), peaked at 0.09 and 0.11 of the top's energy (a
    simulation of it here, 400 steps, confirms the top unreachable); randomize up to such
    damping was "proven". Both are refused by name; a damping the check allows is reached by
    the same bang-bang input."""
    scene = preset("balance").replace(damping=damping)
    with pytest.raises(ValueError, match=rf"damping={damping:g} N·m·s/rad .* the swing-up "
                                         r"cannot reach the unstable rest position"):
        gym.make(env_id, scene=scene)
    with pytest.raises(ValueError, match=r"randomize\['damping'\]=\(0\.0, 10\.0\) cannot be used"):
        gym.make(env_id, randomize={"damping": (0.0, 10.0)})

    def peak_share(damping: float) -> float:
        """The bang-bang input's highest energy over 400 steps, as a share of the top's."""
        scene = preset("balance").replace(damping=damping)
        top = float(roller_gym.physics.energy(scene, analysis.nearest_unstable_rests(
            np.array([scene.r]), np.array([scene.kappa]), np.array([scene.e]))[0], 0.0))
        tau = gym.make(env_id).unwrapped.task.max_torque
        phi, phi_dot, peak = 0.01, 0.0, 0.0
        for _ in range(400):
            result = step(scene, phi, phi_dot, tau * (1.0 if phi_dot >= 0 else -1.0), 0.05)
            phi, phi_dot = result.phi, result.phi_dot
            peak = max(peak, result.energy)
        return peak / top

    assert peak_share(damping) < 0.5
    allowed = 0.001  # below the check's bound for both tasks (0.0354 and 0.0088)
    gym.make(env_id, scene=preset("balance").replace(damping=allowed))
    assert peak_share(allowed) >= 1.0
    # a range up to nearly the check's bound is proven too (a bound of V(φ_b) as loose as
    # m g (2|R − r| + 2e) refused Balance's (0, 0.009) as not proven)
    task = gym.make(env_id).unwrapped.task
    balance = preset("balance")
    phi_b = task.default_target(balance)
    bound = (task.damping_share * task.max_torque
             / orbit_mean_speed(balance, phi_b, float(roller_gym.physics.energy(balance, phi_b,
                                                                                0.0))))
    gym.make(env_id, randomize={"damping": (0.0, 0.9 * bound)})


@pytest.mark.parametrize(("env_id", "kwargs"), [
    ("roller_gym/RollerSwing-v1", {"max_torque": 1e-3}),
    ("roller_gym/RollerSwing-v1", {"dt": 1e-3}),
    ("roller_gym/RollerBalance-v2", {"max_torque": 1e-4}),
    ("roller_gym/RollerBalanceWeak-v0", {"max_torque": 0.02})])
def test_a_target_the_torque_cannot_reach_within_the_episode_is_refused(env_id, kwargs):
    """A torque too weak (or an episode too short, dt 1e-3: 0.4 s) to bring the target's
    energy was accepted: no policy could succeed (on the swing, the bang-bang pump,
    τ = max_torque·sgn φ', the most power the torque puts in, reached 0.06 J of E* >= 0.5 J;
    on BalanceWeak at 0.02 N·m, 0.81 of what success needs). Refused by name; a simulation
    of that pump here confirms the target's energy out of reach over the episode, and the
    defaults are accepted."""
    share = re.escape(f"{roller_gym.task.Task.PUMP_SHARE:g}")
    with pytest.raises(ValueError, match=r"max_torque=.* N·m is too weak for .* needs .* s to "
                                         rf"bring the target's .* J, more than {share} of the "
                                         r"episode"):
        gym.make(env_id, **kwargs)
    env = gym.make(env_id).unwrapped  # the defaults: posed
    task, scene = env.task, env.scene
    needed = task.pump_time(scene)[0]
    tau = kwargs.get("max_torque", task.max_torque)
    dt = kwargs.get("dt", env.config.dt)
    phi, phi_dot, peak = 0.01, 0.0, 0.0
    for _ in range(task.max_episode_steps):
        result = step(scene, phi, phi_dot, tau * (1.0 if phi_dot >= 0 else -1.0), dt)
        phi, phi_dot, peak = result.phi, result.phi_dot, max(peak, result.energy)
    assert peak < needed


@pytest.mark.parametrize("tolerance", [5e-324, 1e-15, 1e-13])
def test_a_tolerance_float64_cannot_verify_is_refused(tolerance):
    """tolerance=5e-324 was accepted, and then every step reported tol_met=False (at 1e-14
    about half the steps, at 1e-13 one in a hundred). The environments refuse tolerances
    below TOLERANCE_MIN by name, single and vector; at TOLERANCE_MIN every step of a
    seeded episode of each task under random torques verifies it."""
    from roller_gym.config import TOLERANCE_MIN

    for make in (lambda: gym.make("roller_gym/RollerStabilize-v2", tolerance=tolerance),
                 lambda: gym.make_vec("roller_gym/RollerBalance-v2", num_envs=2,
                                      tolerance=tolerance)):
        with pytest.raises(ValueError, match=r"tolerance=\S+ is not allowed: it must be >= "
                                             r"1e-12 \(float64's rounding"):
            make()
    rng = np.random.default_rng(3)
    for env_id in [task.env_id() for task in roller_gym.TASKS.values()]:
        env = gym.make(env_id, tolerance=TOLERANCE_MIN)
        env.reset(seed=1)
        for _ in range(100):
            *_, terminated, truncated, info = env.step(rng.uniform(-1, 1, 1).astype(np.float32))
            assert info["tol_met"], env_id
            if terminated or truncated:
                break


def test_a_step_long_enough_for_a_held_torque_to_outrun_the_budget_is_refused():
    """dt = 100 s was accepted by Hold (and Track, HoldRandomized): the check counted the
    held torque's spin-up as sqrt(τ/J_min)·dt, not the speed it builds, (τ/J_min)·dt, which
    turns the fastest angle (τ/J_min) T dt²/2 rad in a step (T = 1 + 1/|1 − rκ|): 4e6 rad
    here, past the 1e4 the substep budget follows; random episodes then ended at the budget.
    Now refused at construction, naming dt and the torque's turns; dt = 1 s still passes."""
    scene = preset("paper")
    j_min = scene.m * (scene.k ** 2 + (scene.r - scene.e) ** 2)
    turns = 1.0 + 1.0 / abs(1.0 - scene.r / scene.R)
    for env_id in ("roller_gym/RollerHold-v2", "roller_gym/RollerTrack-v1"):
        max_torque = gym.make(env_id).unwrapped.task.max_torque
        held = max_torque / j_min * turns * 100.0 ** 2 / 2
        assert held > 1e4  # the independent count: past the budget's phase
        with pytest.raises(ValueError, match=r"^dt=100(\.0)? s is too long .*held max_torque"):
            gym.make(env_id, dt=100.0)
        gym.make(env_id, dt=1.0)  # (τ/J_min) T / 2 rad: well within
