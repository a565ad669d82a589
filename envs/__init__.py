"""roller-gym: Gymnasium environments on the instant-center dynamics of a driven roller.

``import roller_gym`` registers the tasks with Gymnasium under the namespace
``roller_gym``, so that ``gymnasium.make(ID)`` and ``gymnasium.make_vec(ID, num_envs=N)``
work. ``gymnasium.register_envs(roller_gym)`` is the same import, written so that linters
keep it; ``gymnasium.make("roller_gym:roller_gym/RollerStabilize-v2")`` imports the
package itself.

The IDs are those of the tasks in :data:`roller_gym.task.TASKS`
(``[task.env_id() for task in TASKS.values()]``, ``roller_gym/<name>-v<version>``); the
README's table describes each task, and each task's module documents it in full.

A change to a task's dynamics, reward, observation or spaces registers it under the next
version (``-v1``), as Gymnasium does.

The physics, which knows nothing of Gymnasium, is :mod:`roller_gym.physics`; the tasks
are in the registry :data:`roller_gym.task.TASKS` (one module each, :data:`TASK_MODULES`),
and every task runs in the same two environments, :class:`roller_gym.roller_env.RollerEnv` and
:class:`roller_gym.vector_env.RollerVectorEnv`; the sample agents are
:mod:`roller_gym.agents`.
"""

import importlib
import importlib.metadata

from gymnasium.envs.registration import register, registry
from roller_gym import kernel_cache  # noqa: F401  (first: before any kernel is defined)
from roller_gym.physics import PRESETS, Scene, preset
from roller_gym.registration import TaskEntry
from roller_gym.task import NAMESPACE, TASKS

#: The modules of the tasks, in the order they are listed; importing one registers its task.
TASK_MODULES = ("stabilize", "hold", "balance", "track", "swing", "hold_randomized",
                "balance_weak")
for _module in TASK_MODULES:
    importlib.import_module(f"roller_gym.{_module}")

try:  # one source: pyproject.toml's version, as pip installed it
    __version__ = importlib.metadata.version("roller-gym")
except importlib.metadata.PackageNotFoundError:  # imported from a source tree, not installed
    __version__ = "0+unknown"

__all__ = ["ENV_IDS", "NAMESPACE", "PRESETS", "TASKS", "TASK_MODULES", "Scene", "__version__",
           "file_name", "preset"]

#: The registered task IDs, one per task of the registry.
ENV_IDS = tuple(cls.env_id() for cls in TASKS.values())

for _task in TASKS.values():
    if _task.env_id() not in registry:
        register(
            id=_task.env_id(),
            entry_point=TaskEntry(_task.name),
            vector_entry_point=TaskEntry(_task.name, vector=True),
            max_episode_steps=_task.max_episode_steps,
            reward_threshold=_task.reward_threshold,
        )

def file_name(env_id: str) -> str:
    """A task ID as a file or folder name: the namespace dropped (``RollerHold-v2``)."""
    return env_id.split("/")[-1]
