"""roller_gym/RollerStabilize-v0: bring the roller to rest at the bottom.

A roller rolls without slipping inside a fixed cylinder (the scene of
``docs/PHYSICS.md``; by default the preset ``"paper"``). A torque drives it. It
starts somewhere around the bottom, moving; the agent must bring it to rest at φ = 0,
where its mass center hangs straight below the axle at the lowest point.

## Action space

``Box(-1, 1, (1,), float32)``: the torque τ = action · ``max_torque`` [N·m] (default
0.5 N·m), positive in the sense of φ (clockwise). Out-of-range actions are clipped; NaN
or inf raise ``ValueError``.

## Observation space

``Box(-1, 1, (5,), float32)``:

=====  =====================  ====================================
index  observation            meaning
=====  =====================  ====================================
0, 1   cos ψ, sin ψ           position on the cylinder (ψ = 0 at the bottom)
2, 3   cos φ, sin φ           rotation of the roller
4      tanh(φ' / 10 rad/s)    angular speed
=====  =====================  ====================================

## Reward

In [0, 1] per step, ε the position error (rad of φ, one turn of ψ either way):
``near(ε, 2 rad) · (0.5 + 0.5 near(φ', 5 rad/s)) · (0.8 + 0.2 near(action, 1))``, with
``near(x, m) = exp(ln(0.1) (x/m)²)`` (see ``envs/task.py``).

## Starting state

ψ uniform in ±60°, φ' uniform in ±1 rad/s, redrawn until the roller rolls there.

## Episode end

* Terminated: the roller slips (|F| > μN) or leaves the wall (N <= 0) during a step, or a
  step could not stay finite (``info["nonfinite"]``).
* Truncated: 200 steps (10 s at the default dt = 0.05 s).
* ``info["is_success"]``: |ε| <= 0.05 rad and |φ'| <= 0.1 rad/s.

## Arguments

``gymnasium.make("roller_gym/RollerStabilize-v0", scene=..., dt=..., max_torque=..., tolerance=...,
integrator=..., substeps=..., randomize=..., render_mode=...)``: see
:class:`roller_gym.roller_env.RollerEnv`.
"""

from __future__ import annotations

import numpy as np
from roller_gym.physics import Scene
from roller_gym.roller_env import RollerEnv
from roller_gym.task import Task
from roller_gym.vector_env import RollerVectorEnv

__all__ = ["RollerStabilizeEnv", "RollerStabilizeVectorEnv", "StabilizeTask"]


class StabilizeTask(Task):
    name = "RollerStabilize"
    reward_threshold = 183.0  # LQR/swing-up return − 5% (docs/RESULTS.md)

    def sample_target(self, rng: np.random.Generator, scene: Scene) -> float:
        return 0.0


class RollerStabilizeEnv(RollerEnv):
    __doc__ = __doc__
    task_class = StabilizeTask


class RollerStabilizeVectorEnv(RollerVectorEnv):
    """The native vector environment of roller_gym/RollerStabilize-v0 (``gymnasium.make_vec``)."""

    task_class = StabilizeTask
