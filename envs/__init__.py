"""roller-gym: Gymnasium environments on the instant-center dynamics of a driven roller.

``import envs`` registers the tasks with Gymnasium, so that ``gymnasium.make(ID)``,
``gymnasium.make("envs:ID")`` and ``gymnasium.make_vec(ID, num_envs=N)`` work:

======================  ==========================================  ==============
ID                      task                                        steps (dt)
======================  ==========================================  ==============
``RollerStabilize-v0``  bring the roller to rest at the bottom      200 (0.05 s)
``RollerHold-v0``       hold it at rest at a target on the wall     200 (0.05 s)
``RollerBalance-v0``    swing the mass center up and balance it     400 (0.05 s)
======================  ==========================================  ==============

The physics, which knows nothing of Gymnasium, is :mod:`envs.physics`; the tasks are
``envs/stabilize.py``, ``envs/hold.py`` and ``envs/balance.py``.
"""

from gymnasium.envs.registration import register, registry

from envs.balance import BalanceTask
from envs.hold import HoldTask
from envs.physics import PRESETS, Scene, preset
from envs.stabilize import StabilizeTask

__all__ = ["ENV_IDS", "PRESETS", "Scene", "preset"]

ENV_IDS = ("RollerStabilize-v0", "RollerHold-v0", "RollerBalance-v0")

for _module, _task in (("stabilize", StabilizeTask), ("hold", HoldTask),
                       ("balance", BalanceTask)):
    _id = f"{_task.name}-v0"
    if _id not in registry:
        register(
            id=_id,
            entry_point=f"envs.{_module}:{_task.name}Env",
            vector_entry_point=f"envs.{_module}:{_task.name}VectorEnv",
            max_episode_steps=_task.max_episode_steps,
            reward_threshold=_task.reward_threshold,
        )
