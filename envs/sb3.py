"""A stable-baselines3 ``VecEnv`` over the native vector environment.

SB3 cannot take a Gymnasium ``VectorEnv``, and its ``make_vec_env`` builds N single
environments stepped one by one in Python. :class:`RollerVecEnv` gives SB3 the native
batch instead: every ``step`` advances the N rollers in one compiled call. It follows
``DummyVecEnv``'s conventions exactly (automatic reset, ``info["terminal_observation"]``,
``info["TimeLimit.truncated"]``, seeds ``seed + i``), so with the same seeds it gives the
same episodes as ``DummyVecEnv`` over single environments, and it works under
``VecNormalize``, ``VecMonitor`` and ``VecCheckNan``::

    from roller_gym.sb3 import RollerVecEnv
    from stable_baselines3 import PPO

    env = RollerVecEnv("roller_gym/RollerStabilize-v1", n_envs=16, seed=0)
    PPO("MlpPolicy", env).learn(100_000)

Importing this module needs stable-baselines3 (the ``train`` extra).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from roller_gym.episode import INFO_KEYS
from stable_baselines3.common.vec_env import DummyVecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

__all__ = ["RollerVecEnv", "from_env_fns"]

#: Wrappers that ``gymnasium.make`` and SB3's ``make_vec_env`` add, which the native batch
#: does itself (``from_env_fns`` falls back to DummyVecEnv over any other wrapper).
_PLAIN_WRAPPERS = {"Monitor", "TimeLimit", "OrderEnforcing", "PassiveEnvChecker"}


class RollerVecEnv(VecEnv):
    """N sub-environments of a roller-gym task as one SB3 ``VecEnv``.

    Args:
        env_id: a registered task ID, e.g. ``"roller_gym/RollerStabilize-v1"``.
        n_envs: the number of sub-environments.
        seed: the seed of sub-environment 0 (sub-environment i gets ``seed + i``), as
            ``make_vec_env(env_id, n_envs, seed=seed)``; None for fresh seeds.
        monitor: also report each ended episode's return, length and time in
            ``info["episode"]`` (``{"r", "l", "t"}``), as SB3's ``Monitor`` does for the single
            environments of ``make_vec_env``; a path (``".../name"``) also writes them to
            ``name.monitor.csv`` in Monitor's format.
        **env_kwargs: the environment's keyword arguments (``scene``, ``dt``,
            ``max_torque``, ``randomize``, ``max_episode_steps``, …).
    """

    def __init__(self, env_id: str, n_envs: int = 1, seed: int | None = None,
                 monitor: bool | str = False, **env_kwargs: Any) -> None:
        self.venv = gym.make_vec(env_id, num_envs=n_envs, vectorization_mode="vector_entry_point",
                                 autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
        base = self.venv.unwrapped
        self.render_mode = base.render_mode
        super().__init__(base.num_envs, base.single_observation_space,
                         base.single_action_space)
        if seed is not None:
            self.seed(seed)
        self._actions: np.ndarray | None = None
        self.monitor = bool(monitor)
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._start = time.time()
        self._writer = None
        if isinstance(monitor, str):
            from stable_baselines3.common.monitor import ResultsWriter

            self._writer = ResultsWriter(monitor, header={"t_start": self._start,
                                                          "env_id": env_id})

    # -- SB3's VecEnv API ----------------------------------------------------------------
    def reset(self) -> np.ndarray:
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        options = self._options[0] if self._options and self._options[0] else None
        obs, info = self.venv.reset(seed=seeds, options=options)
        self.reset_infos = _rows(info, self.num_envs)
        self._returns[:], self._lengths[:] = 0.0, 0
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=np.float32).reshape(self.num_envs, -1)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, terminated, truncated, info = self.venv.step(self._actions)
        dones = terminated | truncated
        infos = _rows(info, self.num_envs)
        ended = np.flatnonzero(dones)
        if ended.size:
            final = _rows(info["final_info"], self.num_envs)
            for i in ended:
                self.reset_infos[i] = infos[i]  # the next episode's first info
                infos[i] = final[i]
                infos[i]["terminal_observation"] = info["final_obs"][i]
        for i, (te, tr) in enumerate(zip(terminated.tolist(), truncated.tolist(), strict=True)):
            infos[i]["TimeLimit.truncated"] = tr and not te
        if self.monitor:
            self._returns += reward
            self._lengths += 1
            elapsed = round(time.time() - self._start, 6)
            for i in ended:
                infos[i]["episode"] = {"r": round(float(self._returns[i]), 6),
                                       "l": int(self._lengths[i]), "t": elapsed}
                if self._writer is not None:
                    self._writer.write_row(infos[i]["episode"])
            self._returns[ended], self._lengths[ended] = 0.0, 0
        return obs, reward.astype(np.float32), dones, infos

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return list(frames) if frames is not None else [None] * self.num_envs

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        value = getattr(self.venv.unwrapped, attr_name)
        return [value] * len(self._get_indices(indices))

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        setattr(self.venv.unwrapped, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        result = getattr(self.venv.unwrapped, method_name)(*method_args, **method_kwargs)
        return [result] * len(self._get_indices(indices))

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        """True for SB3's ``Monitor`` when ``monitor`` is on (the batch reports episodes as
        it does), else False: the sub-environments carry no wrappers."""
        from stable_baselines3.common.monitor import Monitor

        return [self.monitor and wrapper_class is Monitor] * len(self._get_indices(indices))


def from_env_fns(env_fns: list[Any], **vec_env_kwargs: Any) -> VecEnv:
    """A ``vec_env_cls`` for SB3's ``make_vec_env`` (and rl-zoo3's
    ``ExperimentManager.default_vec_env_cls``): for the environments of a roller-gym task,
    the native batch (:class:`RollerVecEnv` reporting episodes as ``Monitor`` does), built
    from the task ID and keyword arguments of the first environment (so training and
    evaluation environments are of one type); ``DummyVecEnv`` for other tasks, or when the
    environments carry wrappers of their own."""
    if env_fns:
        probe = env_fns[0]()
        wrappers, env, monitor = set(), probe, True
        while isinstance(env, gym.Wrapper):
            wrappers.add(type(env).__name__)
            writer = getattr(env, "results_writer", None)
            if writer is not None:  # make_vec_env's monitor_dir: write there too
                monitor = str(Path(writer.file_handler.name).parent / "batch")
            env = env.env
        spec = probe.spec  # the outermost: it carries make()'s max_episode_steps
        probe.close()
        if wrappers <= _PLAIN_WRAPPERS and spec is not None and spec.id.startswith(
                "roller_gym/"):
            kwargs = {k: v for k, v in spec.kwargs.items() if k != "render_mode"}
            return RollerVecEnv(spec.id, n_envs=len(env_fns), monitor=monitor,
                                max_episode_steps=spec.max_episode_steps, **kwargs)
    return DummyVecEnv(env_fns, **vec_env_kwargs)


def _rows(info: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """A vector info as one dict per sub-environment (Python scalars), SB3's layout."""
    keys = [k for k in INFO_KEYS if k in info]
    columns = [np.asarray(info[k]).tolist() for k in keys]
    return [dict(zip(keys, row, strict=True)) for row in zip(*columns, strict=True)] if keys \
        else [{} for _ in range(n)]
