"""The starts the checks count cover every start the draw takes: the environments' own draws
(4,096 a reset) against roller_gym.start_set.covering and the range proofs' farthest start,
in scenes where the accepted starts are patchy or, moving, lie past every start at rest."""

import gymnasium as gym
import numpy as np
import pytest
from env_cases import cell_width, farthest_at_rest
from roller_gym import Scene, feasibility, start_set

STABILIZE = "roller_gym/RollerStabilize-v2"
#: A cylinder (R = 2 m) where, at these torques, the starts the draw accepts come in patches
#: out to 18 rad, past every candidate at rest that rolls (6 rad); and the default scene,
#: where moving starts roll a little past the starts at rest.
PATCHY = Scene(R=2.0, e=0.0919, k=0.0507, mu=1.364)
CASES = [(PATCHY, 2.434), (PATCHY, 3.0), (Scene(), 0.5)]


def _draws(env, seeds=(0, 1)):
    """|φ| [rad] of the env's starts, over resets."""
    return np.concatenate([np.abs(env.reset(seed=seed)[1]["phi"]) for seed in seeds])


@pytest.mark.parametrize(("scene", "max_torque"), CASES)
def test_every_drawn_start_lies_in_a_covered_cell(scene, max_torque):
    env = gym.make_vec(STABILIZE, num_envs=4096, scene=scene, max_torque=max_torque)
    task = env.unwrapped.task
    phi = _draws(env)
    # past the farthest candidate at rest: all that the checks on starts counted before
    assert phi.max() > farthest_at_rest(task, scene, task.start_points)
    cover = start_set.covering(task, scene)
    width = cell_width(task, scene)
    cell = np.searchsorted(cover.phi, phi)  # the nearest covered far end at or past each
    assert (cell < cover.phi.size).all()
    assert (cover.phi[cell] - phi <= width * (1 + 1e-9)).all()  # ... is its own cell's
    assert task.accepted_starts(scene).max() >= phi.max()
    env.close()


@pytest.mark.parametrize("box", [{"R": (1.9, 2.1), "mu": (1.3, 1.4)}, {"mu": (1.3, 1.4)},
                                 {"R": (1.95, 2.05)}])
def test_the_range_proofs_farthest_start_holds_every_drawn_start(box):
    """The interval the range proof takes the farthest start from reaches past every start
    the env draws from scenes of the range."""
    env = gym.make_vec(STABILIZE, num_envs=4096, scene=PATCHY, max_torque=2.434,
                       randomize=box)
    task = env.unwrapped.task
    phi = _draws(env, seeds=range(4))
    proven, farthest = feasibility._starts_proven(task, PATCHY, [box],
                                                  feasibility._boxes_params(PATCHY, [box]))
    assert proven[0] and phi.max() <= farthest.hi[0]
    env.close()
