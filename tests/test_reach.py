"""The target within reach in an episode, and not reached with no torque: the least times of
``roller_gym.bounds`` are lower bounds of what controllers achieve on the physics, their
refusals name the settings, and a proven range holds scene by scene."""

from __future__ import annotations

import math
import re

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from env_cases import farthest_at_rest
from roller_gym import Scene
from roller_gym.bounds import box_params, too_slow
from roller_gym.intervals import Interval
from roller_gym.physics import Stepper, equations

STABILIZE, HOLD, TRACK, RANDOMIZED = (roller_gym.TASKS[f"Roller{t}"].env_id() for t in (
    "Stabilize", "Hold", "Track", "HoldRandomized"))


def first_success(scene: Scene, phi: float, torque, seconds: float, dt: float = 0.01,
                  band: float = 0.05, speed: float = 0.1) -> float | None:
    """The first time [s] a roller started at rest at ``phi`` [rad] is within ``band`` of the
    bottom and below ``speed``, driven by ``torque(φ, φ')`` on the physics at tol 1e-10
    (None: not within ``seconds``, or it slipped or lifted off on the way)."""
    stepper = Stepper(scene, integrator="taylor", dt=dt, tolerance=1e-10)
    w, t = 0.0, 0.0
    while t < seconds:
        phi, w, *_, finite, _, _, _, lift, slip, _, _ = stepper.advance(
            phi, w, float(torque(phi, w)))
        t += dt
        if not finite or lift <= 0 or slip < 0:
            return None
        if abs(phi) <= band and abs(w) <= speed:
            return t
    return None


@pytest.mark.parametrize("kwargs", [{}, {"m": 5.0}, {"mu": 3.0}, {"m": 2.0, "mu": 2.0, "k": 0.2}],
                         ids=["paper", "m=5", "mu=3", "heavier"])
def test_the_least_times_are_below_what_the_fastest_brake_achieves(kwargs):
    """Bang-bang braking, τ = −max_torque sign φ' (the most power the torque can take out),
    from the farthest start: it comes to rest at the bottom no sooner than every least time
    says (each a lower bound; the energy bound within 15× of it, so not vacuous)."""
    task = roller_gym.TASKS["RollerStabilize"]()
    scene = Scene(**kwargs)
    far = farthest_at_rest(task, scene)
    tau = task.max_torque
    reached = first_success(scene, far, lambda phi, w: -tau * np.sign(w if w else phi), 40.0)
    assert reached is not None, kwargs
    times = task.least_times(box_params(scene, {}), Interval(far))
    for name, seconds in times.items():
        assert float(seconds.lo) <= reached + 0.01, (name, float(seconds.lo), reached)
    assert float(times["energy"].lo) > reached / 15


@pytest.mark.parametrize("damping", [0.004, 0.01, 0.02, 0.05, 0.2])
def test_the_unaided_time_is_below_the_free_motions_and_near_it(damping):
    """With no torque the damping alone brings the roller to rest at the bottom from the
    farthest start no sooner than the bound (J_min/2c) ln(E₀/E₁), and within 3× of it where
    the roller swings (c up to 0.02)."""
    task = roller_gym.TASKS["RollerStabilize"]()
    scene = Scene(damping=damping)
    far = farthest_at_rest(task, scene)
    settled = first_success(scene, far, lambda phi, w: 0.0, 60.0)
    assert settled is not None
    bound = task.unaided_time(box_params(scene, {}), Interval(far))
    assert float(bound.lo) <= settled + 0.01
    if damping <= 0.02:
        assert float(bound.lo) > settled / 3


def test_damping_that_settles_the_roller_unaided_is_refused_and_the_named_limit_holds():
    """Damping 0.02–1.0 let zero torque succeed in every episode: refused, naming a limit (5 %
    inside the bound's) that is accepted, as a range up to it, where 1.1× it is not; zero
    torque from the farthest start takes longer than the episode at the limit (the
    simulation, not the bound)."""
    for damping in (0.02, 0.2, 1.0):
        with pytest.raises(ValueError, match=r"damping=.*no torque at all.*use damping <="):
            gym.make(STABILIZE, scene=Scene(damping=damping))
    with pytest.raises(ValueError, match=r"use damping <= ([0-9.e-]+)") as info:
        gym.make(STABILIZE, scene=Scene(damping=0.02))
    limit = float(re.search(r"use damping <= ([0-9.e-]+)", str(info.value)).group(1))
    gym.make(STABILIZE, scene=Scene(damping=limit))
    with pytest.raises(ValueError, match="no torque at all"):
        gym.make(STABILIZE, scene=Scene(damping=1.1 * limit))
    task = roller_gym.TASKS["RollerStabilize"]()
    scene = Scene(damping=limit)
    far = farthest_at_rest(task, scene)
    assert first_success(scene, far, lambda phi, w: 0.0, 10.0) is None
    gym.make(STABILIZE, randomize={"damping": (0.0, limit)})
    with pytest.raises(ValueError, match="feasible part of the range"):
        gym.make(STABILIZE, randomize={"damping": (0.05, 0.2)})


@pytest.mark.parametrize("env_id", [STABILIZE, HOLD, TRACK, RANDOMIZED])
@pytest.mark.parametrize("kwargs", [
    {"dt": 1e-6}, {"max_torque": 1e-6}, {"scene": Scene(R=1e6)}, {"scene": Scene(R=1e300)},
    {"scene": Scene(R=-1e300)}, {"scene": Scene(e=10.0)}, {"scene": Scene(k=1e3)},
    {"scene": Scene(g=1e6)}, {"scene": Scene(damping=100.0)}, {"randomize": {"R": (0.3, 1e300)}},
    {"randomize": {"e": (0.0, 2.0)}}, {"randomize": {"k": (0.01, 10.0)}}],
    ids=lambda kw: ",".join(f"{k}={v}" for k, v in kw.items())[:40])
def test_a_target_out_of_reach_in_the_episode_is_refused(env_id, kwargs):
    """The settings an adversarial review found accepted though the task's own controller
    succeeded in none of 5–8 episodes: the farthest start is out of reach in the episode.
    Refused at construction (single and vector), the message saying what takes the time.
    RollerHoldRandomized draws R, e, k and m at every reset: a scene's values of those are
    never stepped, and are accepted."""
    drawn = roller_gym.TASKS["RollerHoldRandomized"].scene_ranges
    changed = {f for f, v in kwargs.get("scene", Scene()).as_dict().items()
               if v != getattr(Scene(), f)}
    for make in (lambda: gym.make(env_id, **kwargs),
                 lambda: gym.make_vec(env_id, num_envs=2, **kwargs)):
        if env_id == RANDOMIZED and changed and changed <= set(drawn):
            make().reset(seed=0)
            continue
        with pytest.raises(ValueError, match=r"cannot be solved in|no torque at all"):
            make()


def test_the_lift_off_speed_at_the_eccentric_masss_top_is_the_physics():
    """Where θ = π (the eccentric mass over the center) N/m = g cos ψ + (r²κ/s − e) φ'²
    whatever φ'': the contact forces of the physics vanish at φ'² = g cos ψ/(e − r²κ/s),
    the speed the lifted-travel bound takes (with cos ψ <= 1)."""
    for scene in (Scene(R=1e6), Scene(R=3.0, e=0.06), Scene(R=math.inf)):
        m, r, kappa, e, _, g, _ = scene.params
        s = 1.0 - r * kappa
        phi = math.pi * s * 7  # θ = 7π
        psi = r * kappa * phi / s
        w = math.sqrt(g * math.cos(psi) / (e - r * r * kappa / s))
        for phi_ddot in (-3.0, 0.0, 5.0):
            normal, _ = equations.contact_forces(phi, w, phi_ddot, m, r, kappa, e, g)
            assert abs(normal) < 1e-9 * m * g


def test_a_proven_range_holds_scene_by_scene():
    """Ranges the proof accepts (the hard tier's default, four fields of plain domain
    randomization, with R and e narrowed so that no corner holds a doomed start, damping
    below the limit): every one of 300 drawn scenes passes the scalar check."""
    rng = np.random.default_rng(0)
    for env_id, ranges in ((RANDOMIZED, None),
                           (STABILIZE, {"R": (0.4, 0.7), "e": (0.04, 0.07), "k": (0.05, 0.2),
                                        "m": (0.5, 2.0)}),
                           (STABILIZE, {"damping": (0.0, 0.004)})):
        env = gym.make(env_id, **({} if ranges is None else {"randomize": ranges})).unwrapped
        task, ranges = env.task, env.config.randomize
        for _ in range(100):
            scene = env.config.scene.replace(**{f: rng.uniform(*ranges[f]) for f in ranges})
            assert too_slow(task, scene, env.config.dt) is None, scene


def test_holding_targets_within_the_band_of_the_bottom_with_damping_is_refused():
    """With a torque so small that the targets it holds lie within the success band of the
    bottom (all of them, or one grid step short of all: ±0.0565 rad against 0.05), damping
    alone solved RollerHold and RollerTrack (zero torque: 9–10 of 10 episodes): refused
    where half the targets may lie within the band and the damping may settle the roller in
    the episode; not with a torque that holds targets further out, nor without damping."""
    for env_id, kwargs in ((HOLD, {"scene": Scene(damping=0.05), "max_torque": 0.02}),
                           (HOLD, {"scene": Scene(damping=0.2), "max_torque": 0.002}),
                           (TRACK, {"scene": Scene(damping=0.2), "max_torque": 0.01}),
                           (HOLD, {"scene": Scene(damping=0.1), "max_torque": 0.05}),
                           (TRACK, {"scene": Scene(damping=0.1), "max_torque": 0.07}),
                           (HOLD, {"randomize": {"damping": (0.05, 0.2)}, "max_torque": 0.02})):
        with pytest.raises(ValueError, match="a success for"):
            gym.make(env_id, **kwargs)
        low, high = roller_gym.rest.hold_range(Scene(), kwargs["max_torque"])
        assert max(-low, high) <= 0.1  # (half the targets within the band: the walk's range)
    for kwargs in ({"scene": Scene(damping=0.05), "max_torque": 0.1},
                   {"randomize": {"damping": (0.05, 0.2)}}):
        gym.make(HOLD, **kwargs)


def test_holds_past_implies_the_walks_range_reaches_past_the_band():
    """Where the interval check says the held range reaches past the band, the compiled walk
    of hold_ranges (an independent computation: a grid of points) finds it so, on 300 random
    scenes and torques, cylinders, floors and drums."""
    rng = np.random.default_rng(11)
    agreed = 0
    for _ in range(300):
        scene = Scene(R=float(rng.choice([rng.uniform(0.15, 50.0), math.inf,
                                          -rng.uniform(0.3, 5.0)])),
                      e=float(rng.uniform(0.0, 0.09)), mu=float(rng.uniform(0.2, 2.0)))
        torque = float(10 ** rng.uniform(-3, 0))
        wide = bool(roller_gym.bounds.holds_past(box_params(scene, {}), 0.8 * torque, 0.9,
                                                  0.05))
        low, high = roller_gym.rest.hold_range(scene, torque)
        if wide:
            assert high > 0.05 and -low > 0.05, (scene, torque)
        agreed += wide == (high > 0.05)
    assert agreed >= 270  # (and it seldom misses a range that does reach past)


def test_every_accepted_start_is_bounded_not_only_the_farthest():
    """On the ``drum`` the farthest accepted start (5.65 rad) lies past the potential's
    barrier, below the bottom's energy, so its energy bound is 0 s; nearer starts carry
    0.1–0.4 J, which max_torque = 3e-4 N·m takes minutes to take out (the LQR: 0 of 8).
    The bounds are now taken at every accepted start: refused, naming the start."""
    task = roller_gym.TASKS["RollerStabilize"](3e-4)
    scene = roller_gym.preset("drum")
    starts = task.accepted_starts(scene)
    times = task.least_times(box_params(scene, {}), Interval(starts))["energy"].lo
    assert times[np.argmax(starts)] == 0.0 and times.max() > 5.0
    with pytest.raises(ValueError, match=r"the start at rest at \|phi\| = "):
        gym.make(STABILIZE, scene="drum", max_torque=3e-4)
