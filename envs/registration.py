"""The entry points of the task IDs: the ID decides the task.

Each ID ``roller_gym/<Task>-v<version>`` is registered with a :class:`TaskEntry` (for
``gymnasium.make``) and one for ``gymnasium.make_vec``: a picklable callable that makes the
single or the vector environment of that task, and refuses a ``task=`` keyword that names
another task (``gymnasium.make`` would otherwise let it replace the ID's).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass
from typing import Any

from roller_gym.physics.scene import shown
from roller_gym.task import get_task

__all__ = ["TaskEntry"]


@dataclass(frozen=True)
class TaskEntry:
    """Makes the environment of ``task`` (a registry name): the single one, or with
    ``vector`` the native vector environment."""

    task: str
    vector: bool = False

    def _env_class(self) -> type:
        if self.vector:
            from roller_gym.vector_env import RollerVectorEnv

            return RollerVectorEnv
        from roller_gym.roller_env import RollerEnv

        return RollerEnv

    @property
    def __signature__(self) -> inspect.Signature:
        """The environment class's keywords, but ``task``, which the ID sets."""
        signature = inspect.signature(self._env_class())
        return signature.replace(parameters=[p for p in signature.parameters.values()
                                             if p.name != "task"])

    @property
    def metadata(self) -> dict[str, Any]:
        """The environment class's metadata (Gymnasium checks ``render_mode`` against it)."""
        return self._env_class().metadata

    def __call__(self, **kwargs: Any) -> Any:
        """The environment, made with ``kwargs``.

        Raises:
            ValueError: ``task=`` names another task than the ID's.
        """
        if "task" in kwargs:
            given = kwargs.pop("task")
            ours = get_task(self.task)
            if get_task(given, current=True) is not ours:
                raise ValueError(f"task={shown(given)} contradicts the ID {ours.env_id()}, whose "
                                 f"task is {shown(self.task)}: make {get_task(given).env_id()} "
                                 "instead, or leave task= out")
        return self._env_class()(task=self.task, **kwargs)
