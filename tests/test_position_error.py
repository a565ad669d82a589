"""The position error is zero only where the roller's pose is the target's: checked against
the geometry of the pose (roller_gym.physics.equations.positions: the roller's centre O1
and its centre of mass C), in scenes where the roller turns a whole number of times per
turn of its contact (every default scene), where it does not, on the floor and on a drum."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym.physics import Scene, equations
from roller_gym.task import position_error, psi_rate, wrap_rate


def pose(scene: Scene, phi: float) -> np.ndarray:
    """Where the roller is and how it is turned: O1's height, C − O1, and O1's place along
    the surface except on the floor (where a pose a circumference along is the same)."""
    o1x, o1y, cx, cy, _, _ = equations.positions(phi, scene.r, scene.kappa, scene.e)
    along = [] if math.isinf(scene.R) else [o1x]
    return np.array([*along, o1y, cx - o1x, cy - o1y], float)


def same_pose(scene: Scene, a: float, b: float) -> bool:
    return bool(np.allclose(pose(scene, a), pose(scene, b), rtol=0.0, atol=1e-9))


def scenes() -> list[Scene]:
    rng = np.random.default_rng(2026)
    r = 0.1
    whole = [Scene(r=r, R=r * (n + 1), e=0.05) for n in (1, 2, 4, 9)]  # 1/q = n
    tight = [Scene(r=r, R=r * (1 + 1 / n), e=0.05) for n in (2, 3)]  # q = n
    drums = [Scene(r=r, R=-r * (n - 1), e=0.05) for n in (3, 6)]  # 1/|q| = n
    drawn = [Scene(r=r, R=float(rng.uniform(0.15, 2.0)), e=0.05) for _ in range(20)]
    return [*roller_gym.PRESETS.values(), *whole, *tight, *drums, *drawn,
            Scene(r=r, R=0.35, e=0.05)]  # 1/q = 2.5


@pytest.mark.parametrize("scene", scenes(), ids=lambda s: f"R={s.R:.4g}")
def test_the_error_is_zero_only_at_the_targets_pose(scene):
    """At whole turns of the contact (ψ) and of the roller (φ) away from the target, the
    error is zero only where the pose is the target's; where the wrap rate is not 0 the pose
    repeats after 2π/|q| and the error there is zero."""
    target = 0.3
    q = wrap_rate(scene)
    contact_turn = 2 * math.pi / abs(psi_rate(scene)) if psi_rate(scene) else 2 * math.pi
    for shift in (*(k * contact_turn for k in (1, 2, 3)), 2 * math.pi, 4 * math.pi):
        for sign in (1.0, -1.0):
            phi = target + sign * shift
            error = float(position_error(phi, target, q, 0.0))
            if abs(error) < 1e-9:
                assert same_pose(scene, phi, target), (shift, error)
            else:
                # not wrapped by less than the shift: the distance to the target's pose
                assert abs(error) <= shift + 1e-9
    if q != 0.0:
        period = 2 * math.pi / abs(q)
        assert same_pose(scene, target + period, target)
        assert abs(position_error(target + period, target, q, 0.0)) < 1e-9


def test_the_default_scenes_are_wrapped_by_a_turn_of_the_contact_and_others_are_not():
    """Every default scene: 1/q whole, the error wraps by a turn of ψ as it always has. A
    scene where the roller turns 2.5 times per turn of its contact is not wrapped at all,
    and one that fits tightly (q = 100) is wrapped by a turn of φ, not of ψ."""
    for name in ("paper", "balance", "drum"):
        scene = roller_gym.PRESETS[name]
        assert wrap_rate(scene) == psi_rate(scene)
    assert wrap_rate(Scene(R=0.35)) == 0.0
    assert wrap_rate(roller_gym.PRESETS["tight_fit"]) == 1.0
    assert wrap_rate(roller_gym.PRESETS["floor"]) == 1.0
    batch = Scene.stack([Scene(R=0.35), roller_gym.PRESETS["paper"]])
    np.testing.assert_array_equal(wrap_rate(batch), [0.0, 0.25])


@pytest.mark.parametrize("vector", [False, True])
def test_a_roller_a_turn_of_its_contact_away_is_not_on_the_target(vector):
    """Through the environment: RollerHold in a scene with 1/q = 2.5, started at rest a
    whole turn of ψ (2π/q of φ) from its target, is 2π/q from it and not successful; in the
    paper scene (1/q = 4) the same start is the target's own pose, at zero error."""
    for scene, wrapped in ((Scene(R=0.35), False), (roller_gym.preset("paper"), True)):
        env = (gym.make_vec("roller_gym/RollerHold-v2", num_envs=1, scene=scene) if vector
               else gym.make("roller_gym/RollerHold-v2", scene=scene))
        turn = 2 * math.pi / psi_rate(scene)
        _, info = env.reset(seed=1, options={"target": 0.0, "state": (turn, 0.0)})
        error = float(np.ravel(info["position_error"])[0])
        success = bool(np.ravel(info["is_success"])[0])
        if wrapped:
            assert abs(error) < 1e-9 and success
        else:
            assert error == pytest.approx(turn) and not success
