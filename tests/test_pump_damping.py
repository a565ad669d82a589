"""The pump tasks' damping rule, c·mean|φ'| over the target's swing <= 0.8 max_torque,
against their classical controllers run with the rule lifted: damping it accepts is
solved, damping it refuses is not."""

import gymnasium as gym
import pytest
from env_cases import controller_wins
from roller_gym.agents import controller_for
from roller_gym.physics import PRESETS


def _wins(env_id, scene):
    env = gym.make(env_id, scene=scene)
    return controller_wins(env, controller_for(env))


@pytest.mark.parametrize(("env_id", "preset", "accepted", "refused"), [
    ("roller_gym/RollerBalance-v2", "balance", 0.034, 0.04),
    ("roller_gym/RollerBalanceWeak-v0", "balance", 0.008, 0.01),
    ("roller_gym/RollerSwing-v1", "paper", 0.0085, 0.015),
])
def test_the_damping_rule_parts_what_the_swing_ups_solve(env_id, preset, accepted, refused,
                                                          monkeypatch):
    """Near the rule's edge on either side (the old rule, c·ω <= 0.5 max_torque, refused
    both): the accepted damping is solved in every episode; the refused one, with the rule
    lifted, in at most one of four."""
    scene = PRESETS[preset]
    assert _wins(env_id, scene.replace(damping=accepted)) == 4
    with pytest.raises(ValueError, match=rf"damping={refused:g} N·m·s/rad .* on average"):
        gym.make(env_id, scene=scene.replace(damping=refused))
    task_class = type(gym.make(env_id).unwrapped.task)
    monkeypatch.setattr(task_class, "damping_share", 1e9)
    assert _wins(env_id, scene.replace(damping=refused)) <= 1
