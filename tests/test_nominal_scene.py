"""The nominal scene of a randomized environment (EnvConfig.nominal_scene): the target shown
before the first reset and the classical controller's design, never a base value the
ranges replace."""

import gymnasium as gym
import pytest
from env_cases import controller_wins
from roller_gym import Scene
from roller_gym.agents import controller_for


def test_the_controller_designs_for_the_ranges_not_a_base_value_they_replace():
    """A base m = 100 kg that randomize={"m": (0.8, 1.2)} replaces: the LQR designed for
    it fails; controller_for designs for the middle of the range (m = 1 kg) and holds."""
    env = gym.make("roller_gym/RollerHold-v2", scene=Scene(m=100.0), randomize={"m": (0.8, 1.2)})
    assert env.unwrapped.config.nominal_scene == Scene(m=1.0)
    assert controller_wins(env, controller_for(env)) >= 3
    assert controller_wins(env, controller_for(env, scene=Scene(m=100.0))) <= 1
    kept = gym.make("roller_gym/RollerHold-v2", randomize={"m": (0.8, 1.2)})
    assert kept.unwrapped.config.nominal_scene == Scene()  # (a base within the range stays)


@pytest.mark.parametrize("base", [Scene(R=1.0, e=0.0), Scene(R=1.0, e=0.08, mu=0.01)])
def test_a_base_value_the_ranges_replace_is_not_checked(base):
    """RollerBalance's base scene with no unstable rest position that rolls (e = 0: none;
    mu = 0.01: it slips) constructs where randomize draws those fields from ranges that
    have one, and shows the target of the ranges' middle before the first reset."""
    ranges = {"e": (0.075, 0.085), "mu": (0.9, 1.0)}
    env = gym.make("roller_gym/RollerBalance-v2", scene=base, randomize=ranges).unwrapped
    middle = gym.make("roller_gym/RollerBalance-v2", scene=base.replace(e=0.08, mu=0.95)).unwrapped
    assert env.target == middle.target
    env.reset(seed=0)
