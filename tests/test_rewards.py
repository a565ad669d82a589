"""Rewards that rank policies as success does: for every task, on 100 seeded episodes, the
reward of resting (or moving with the target) is largest inside the success band, and
resting one band-width outside the band costs a clear share of it.

The holding torque at each offset is computed here from PHYSICS.md (τ = m g (r sin ψ +
e sin φ) at rest), so the test drives the task's reward with the torques a policy that
rests there must apply.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym import rewards

IDS = list(roller_gym.ENV_IDS)
#: Offsets [rad of φ] from the target at which the roller rests.
OFFSETS = np.linspace(-0.6, 0.6, 4801)


def holding(scene, phi):
    """The torque [N·m] that holds the roller at rest at φ (PHYSICS.md, cylinder form)."""
    m, r, R, e, g = (float(getattr(scene, f)) for f in ("m", "r", "R", "e", "g"))
    psi = r * phi / (R - r)
    return m * g * (r * np.sin(psi) + e * np.sin(phi))


def rest_rewards(task, scene, target, rate=0.0):
    """The task's reward at rest at target + OFFSETS (moving with the target if it moves),
    holding there with the torque that takes; and the errors the task measures there."""
    q = r_over = float(scene.r) / (float(scene.R) - float(scene.r))
    phi = target + OFFSETS
    tau = holding(scene, phi)
    error = task.error(phi, np.full_like(phi, target), q)
    step = {"position_error": error, "phi_dot": np.full_like(phi, rate),
            "target_phi_dot": rate, "torque": tau, "target_torque": holding(scene, target),
            "action": tau / task.max_torque}
    reachable = np.abs(tau) <= task.max_torque
    assert r_over > 0
    return np.where(reachable, task.reward(step), -np.inf), error


@pytest.mark.parametrize("env_id", IDS)
def test_resting_pays_most_inside_the_band_and_clearly_less_outside(env_id):
    env = gym.make(env_id)
    task, scene = env.unwrapped.task, env.unwrapped.scene
    band = task.success_band
    checked = 0
    for seed in range(100):
        _, info = env.reset(seed=seed)
        for target in {info["target_phi"], *((-info["target_phi"],) if task.symmetric_target
                                             else ())}:
            reward, error = rest_rewards(task, scene, target, info["target_phi_dot"])
            best = int(np.argmax(reward))
            assert abs(error[best]) <= band, (seed, target, error[best])
            at_target = reward[np.argmin(np.abs(OFFSETS))]
            assert at_target == pytest.approx(reward[best], rel=1e-12)
            for side in (-1.0, 1.0):
                outside = reward[np.argmin(np.abs(OFFSETS - side * 2.0 * band))]
                assert outside <= 0.9 * at_target, (seed, target, side, outside, at_target)
            checked += 1
    assert checked >= 100


def test_balance_pays_most_at_the_unstable_rest_position():
    """In Balance the target is the unstable rest position ±φ_b: resting there needs no
    torque at all, and its reward is the largest of all rest positions nearby."""
    env = gym.make("roller_gym/RollerBalance-v1")
    task, scene = env.unwrapped.task, env.unwrapped.scene
    phi_b = task.default_target(scene)
    assert abs(holding(scene, phi_b)) < 1e-9
    for target in (phi_b, -phi_b):
        reward, error = rest_rewards(task, scene, target)
        assert reward[np.argmin(np.abs(OFFSETS))] == pytest.approx(1.0, abs=1e-12)
        assert abs(error[int(np.argmax(reward))]) <= 1e-3


def test_tolerance_is_one_inside_the_band_and_near_outside():
    x = np.array([-0.3, -0.05, 0.0, 0.04, 0.05, 0.06, 0.3])
    got = rewards.tolerance(x, 0.05, 0.2)
    np.testing.assert_array_equal(got[1:5], 1.0)
    for xi, g in zip(x[[0, 5, 6]], got[[0, 5, 6]], strict=True):
        assert g == pytest.approx(math.exp(math.log(0.1) * ((abs(xi) - 0.05) / 0.2) ** 2))
    assert rewards.tolerance(0.25, 0.05, 0.2) == pytest.approx(0.1)
