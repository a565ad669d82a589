"""roller-gym: Gymnasium environments on the instant-center dynamics of a driven roller.

``import roller_gym`` registers the tasks with Gymnasium under the namespace
``roller_gym``, so that ``gymnasium.make(ID)`` and ``gymnasium.make_vec(ID, num_envs=N)``
work. ``gymnasium.register_envs(roller_gym)`` is the same import, written so that linters
keep it; ``gymnasium.make("roller_gym:roller_gym/RollerStabilize-v0")`` imports the
package itself.

================================  ==========================================  ==============
ID                                task                                        steps (dt)
================================  ==========================================  ==============
``roller_gym/RollerStabilize-v0``  bring the roller to rest at the bottom      200 (0.05 s)
``roller_gym/RollerHold-v0``       hold it at rest at a target on the wall     200 (0.05 s)
``roller_gym/RollerBalance-v0``    swing the mass center up and balance it     400 (0.05 s)
================================  ==========================================  ==============

A change to a task's dynamics, reward, observation or spaces registers it under the next
version (``-v1``), as Gymnasium does.

The physics, which knows nothing of Gymnasium, is :mod:`roller_gym.physics`; the tasks
are :mod:`roller_gym.stabilize`, :mod:`roller_gym.hold` and :mod:`roller_gym.balance`;
the sample agents are :mod:`roller_gym.agents`.
"""

from gymnasium.envs.registration import register, registry
from roller_gym.balance import BalanceTask
from roller_gym.hold import HoldTask
from roller_gym.physics import PRESETS, Scene, preset
from roller_gym.stabilize import StabilizeTask

__all__ = ["ENV_IDS", "NAMESPACE", "PRESETS", "Scene", "file_name", "preset"]

#: The Gymnasium namespace of every task: ``roller_gym/<Task>-v<N>``.
NAMESPACE = "roller_gym"
#: The registered task IDs.
ENV_IDS = tuple(f"{NAMESPACE}/{t.name}-v0" for t in (StabilizeTask, HoldTask, BalanceTask))

for _module, _task in (("stabilize", StabilizeTask), ("hold", HoldTask),
                       ("balance", BalanceTask)):
    _id = f"{NAMESPACE}/{_task.name}-v0"
    if _id not in registry:
        register(
            id=_id,
            entry_point=f"roller_gym.{_module}:{_task.name}Env",
            vector_entry_point=f"roller_gym.{_module}:{_task.name}VectorEnv",
            max_episode_steps=_task.max_episode_steps,
            reward_threshold=_task.reward_threshold,
        )


def file_name(env_id: str) -> str:
    """A task ID as a file or folder name: the namespace dropped (``RollerHold-v0``)."""
    return env_id.split("/")[-1]
