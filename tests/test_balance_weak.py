"""RollerBalanceWeak: RollerBalance with a quarter of its torque, where the swing-up needs
many pumps; the claims of its docstring, checked against the physics and the classical
reference."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
import roller_gym
from roller_gym.agents import controller_for, rollout
from roller_gym.physics.analysis import holding_torque

ID = "roller_gym/RollerBalanceWeak-v0"
BALANCE = "roller_gym/RollerBalance-v2"


def _half_swings(episode, band: float) -> int:
    """Reversals of the roller's rotation before it first enters the success band [rad]."""
    inside = np.flatnonzero(np.abs(episode.error) <= band)
    assert inside.size, "the swing-up never reached the band"
    turning = np.sign(np.diff(episode.phi[: inside[0] + 1]))
    return int(np.count_nonzero(np.diff(turning[turning != 0]) != 0))


def test_it_is_balance_with_a_torque_far_below_the_holding_torque_on_the_way_up():
    weak, balance = gym.make(ID).unwrapped, gym.make(BALANCE).unwrapped
    assert weak.observation_space == balance.observation_space
    assert weak.task.max_torque == 0.1 and balance.task.max_torque == 0.4
    scene = roller_gym.preset("balance")
    target = weak.task.default_target(scene)
    assert target == balance.task.default_target(scene)
    # the torque that holds the roller at rest, on the way from the bottom to the target
    way_up = np.abs(holding_torque(scene, np.linspace(0.0, target, 2001)))
    assert way_up.max() >= 9.0 * weak.task.max_torque


def test_the_swing_up_succeeds_after_many_more_pumps_than_on_balance():
    """The classical reference solves every episode of seeds 0–9 (the episodes are
    solvable), after at least three times as many half-swings as on RollerBalance; its return
    clears the registered threshold."""
    weak, balance = gym.make(ID), gym.make(BALANCE)
    episodes = [rollout(weak, controller_for(weak), s) for s in range(10)]
    assert all(e.success for e in episodes)
    assert np.mean([e.total_return for e in episodes]) >= weak.spec.reward_threshold
    strong = [rollout(balance, controller_for(balance), s) for s in range(10)]
    band = weak.unwrapped.task.success_band
    assert (min(_half_swings(e, band) for e in episodes)
            >= 3 * max(_half_swings(e, band) for e in strong))


@pytest.mark.parametrize(("env_id", "kwargs"), [
    ("roller_gym/RollerBalance-v2", {}), ("roller_gym/RollerBalanceWeak-v0", {}),
    ("roller_gym/RollerBalanceWeak-v0", {"max_torque": 0.04}), ("roller_gym/RollerSwing-v1", {})])
def test_the_pump_time_is_below_the_in_phase_pumps_and_leaves_it_the_episode(env_id, kwargs):
    """The full torque in phase with φ' (the most power the torque puts in, simulated at
    dt 0.01 s) brings the energy pump_time names no sooner than its bound, and within the
    episode wherever the bound fits PUMP_SHARE of it (here within 3 bounds: 2.3–2.8). At the
    settings an adversarial review found accepted though that pump fell short (Balance at
    max_torque 0.0215 N·m or dt 0.0027 s, BalanceWeak at dt 0.0108 s), refused."""
    from roller_gym.physics import energy, step

    env = gym.make(env_id, **kwargs).unwrapped
    task, scene = env.task, env.scene
    needed, _, bound = task.pump_time(scene)
    phi, phi_dot, t = 0.01, 0.0, 0.0
    goal = float(energy(scene, phi, 0.0)) + needed
    while t < 3.0 * bound:
        result = step(scene, phi, phi_dot, task.max_torque * (1.0 if phi_dot >= 0 else -1.0),
                      0.01)
        phi, phi_dot, t = result.phi, result.phi_dot, t + 0.01
        if result.energy >= goal:
            break
    assert bound <= t < 3.0 * bound
    assert task.PUMP_SHARE * 3.0 < 1.0
    for env_id, bad in (("roller_gym/RollerBalance-v2", {"max_torque": 0.0215}),
                        ("roller_gym/RollerBalance-v2", {"dt": 0.0027}),
                        ("roller_gym/RollerBalanceWeak-v0", {"dt": 0.0108})):
        with pytest.raises(ValueError, match="too weak"):
            gym.make(env_id, **bad)
