"""RollerBalanceWeak: RollerBalance with a quarter of its torque, where the swing-up needs
many pumps; the claims of its docstring, checked against the physics and the classical
reference."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
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
