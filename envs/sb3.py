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

    env = RollerVecEnv("roller_gym/RollerStabilize-v2", n_envs=16, seed=0)
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
from roller_gym.episode import INFO_KEYS, vector_seeds
from roller_gym.physics.integrators import DEFAULT_INTEGRATOR
from roller_gym.vector_env import BATCH_INTEGRATORS
from stable_baselines3.common.vec_env import DummyVecEnv
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices

__all__ = ["RollerVecEnv", "from_env_fns"]

#: Wrappers that ``gymnasium.make`` and SB3's ``make_vec_env`` add, which the native batch
#: does itself (``from_env_fns`` falls back to DummyVecEnv over any other wrapper).
#: ``PatchedTimeLimit`` is the ``TimeLimit`` of a process that imported rl-zoo3: it sets
#: ``info["TimeLimit.truncated"]`` as :class:`RollerVecEnv` does.
_PLAIN_WRAPPERS = {"Monitor", "TimeLimit", "PatchedTimeLimit", "OrderEnforcing",
                   "PassiveEnvChecker"}
#: Attributes whose sub-environment's value the native batch holds under another name.
_SINGLE = {"observation_space": "single_observation_space",
           "action_space": "single_action_space"}


class RollerVecEnv(VecEnv):
    """N sub-environments of a roller-gym task as one SB3 ``VecEnv``.

    Args:
        env_id: a registered task ID, e.g. ``"roller_gym/RollerStabilize-v2"``.
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
        if isinstance(n_envs, bool) or not isinstance(n_envs, int | np.integer) or n_envs < 1:
            raise ValueError(f"n_envs={n_envs!r} must be a positive integer")
        if not isinstance(monitor, bool | str):
            raise ValueError(f"monitor={monitor!r} must be True, False or a path (str)")
        _check_seed(seed, int(n_envs))  # before anything is built
        fixed = {"num_envs", "vectorization_mode", "autoreset_mode"} & set(env_kwargs)
        if fixed:
            raise ValueError(f"{', '.join(sorted(fixed))}: RollerVecEnv sets these itself "
                             "(n_envs sub-environments of the native batch, autoreset on the "
                             "same step as SB3 expects); leave them out")
        if not (isinstance(env_id, str) and env_id.rpartition(":")[2].startswith("roller_gym/")):
            raise ValueError(f"env_id={env_id!r} is not a roller-gym task ID "
                             "('roller_gym/<Task>-v<N>'): RollerVecEnv batches roller-gym's "
                             "tasks only; for other environments use SB3's make_vec_env")
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
    def seed(self, seed: int | None = None) -> Sequence[int | None]:
        """Seed the next reset: sub-environment i with ``seed`` + i (SB3's rule; None: a
        random seed)."""
        _check_seed(seed, self.num_envs)
        return super().seed(None if seed is None else int(seed))

    def reset(self) -> np.ndarray:
        """Every sub-environment starts a new episode, with the seeds and options set by
        ``seed()`` and ``set_options()`` (each sub-environment its own, as DummyVecEnv)."""
        n = self.num_envs
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        groups = _option_groups(self._options, n)
        self.reset_infos = [{} for _ in range(n)]
        for options, mask in groups:
            if len(groups) > 1:  # the sub-environments that share these options
                options = {**(options or {}), "reset_mask": mask}
            obs, info = self.venv.reset(seed=seeds, options=options)
            rows = _rows(info, n)
            for i in np.flatnonzero(mask):
                self.reset_infos[i] = rows[i]
        self._returns[:], self._lengths[:] = 0.0, 0
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions  # checked (and clipped) by the batch's step, naming them

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
        """The attribute of each sub-environment in ``indices``: an array of the native batch
        with one entry per sub-environment (``phi``, ``target``, …) gives each its own; the
        spaces are a sub-environment's; anything else is the batch's one value."""
        index = list(self._get_indices(indices))
        value = getattr(self.venv.unwrapped, _SINGLE.get(attr_name, attr_name))
        if self._per_env(value):
            return [value[i].item() if value.ndim == 1 else value[i] for i in index]
        return [value] * len(index)

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set the attribute of the sub-environments in ``indices``: the entries of an array
        with one entry per sub-environment; a value of the whole batch only for all of them."""
        index = list(self._get_indices(indices))
        current = getattr(self.venv.unwrapped, attr_name, None)  # (None: a new attribute)
        if self._per_env(current):
            current[index] = self._entries(attr_name, value, current, len(index))
        elif sorted(index) == list(range(self.num_envs)):
            setattr(self.venv.unwrapped, attr_name, value)
        else:
            raise ValueError(
                f"set_attr({attr_name!r}, indices={indices!r}): {attr_name!r} is one value for "
                f"the whole native batch of {self.num_envs} sub-environments, so it can only "
                f"be set for all of them (indices=None)")

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call a method of the native batch (once, for all sub-environments: the result is
        repeated for each). ``indices`` may only name all of them."""
        index = list(self._get_indices(indices))
        if sorted(index) != list(range(self.num_envs)):
            raise ValueError(
                f"env_method({method_name!r}, indices={indices!r}): the native batch's "
                f"methods act on all {self.num_envs} sub-environments at once, so indices "
                f"may only be None (all of them); DummyVecEnv over single environments calls "
                f"each on its own")
        result = getattr(self.venv.unwrapped, method_name)(*method_args, **method_kwargs)
        return [result] * len(index)

    @staticmethod
    def _entries(attr_name: str, value: Any, current: np.ndarray, count: int) -> np.ndarray:
        """``value`` as ``count`` entries of the per-sub-environment array ``current``: numbers
        of its kind (real and finite where it holds floats, as the state φ [rad], φ' [rad/s])."""
        new = np.asarray(value)
        wrong = (new.dtype.kind not in ("iuf" if current.dtype.kind == "f" else "biuf")
                 or (new.dtype.kind == "f" and not np.isfinite(new).all()))
        if wrong or new.ndim > current.ndim or (new.ndim and len(new) != count):
            kind = "finite real numbers" if current.dtype.kind == "f" else "integers or bools"
            raise ValueError(f"set_attr({attr_name!r}, value={value!r}): {attr_name!r} holds "
                             f"{kind}, one per sub-environment; give one, or one for each "
                             f"of the {count} indices")
        return new

    def _per_env(self, value: Any) -> bool:
        """Whether ``value`` is an array with one entry per sub-environment."""
        return isinstance(value, np.ndarray) and value.ndim >= 1 and \
            value.shape[0] == self.num_envs

    def env_is_wrapped(self, wrapper_class: type[gym.Wrapper],
                       indices: VecEnvIndices = None) -> list[bool]:
        """True for SB3's ``Monitor`` when ``monitor`` is on (the batch reports episodes as
        it does), else False: the sub-environments carry no wrappers."""
        from stable_baselines3.common.monitor import Monitor

        return [self.monitor and wrapper_class is Monitor] * len(self._get_indices(indices))


def _check_seed(seed: Any, n: int) -> None:
    """SB3's seed: None or one integer in range (sub-environment i gets seed + i), checked by
    the vector environments' rule (:func:`vector_seeds`) and refusing its list of seeds."""
    vector_seeds(seed, n)
    if seed is not None and not isinstance(seed, int | np.integer):
        raise ValueError(f"seed={seed!r} must be None or an integer: SB3 seeds "
                         "sub-environment i with seed + i (a list of seeds is not SB3's)")


def from_env_fns(env_fns: list[Any], **vec_env_kwargs: Any) -> VecEnv:
    """A ``vec_env_cls`` for SB3's ``make_vec_env`` (and rl-zoo3's
    ``ExperimentManager.default_vec_env_cls``): for the environments of a roller-gym task,
    the native batch (:class:`RollerVecEnv` reporting episodes as ``Monitor`` does), built
    from the task ID and keyword arguments of the first environment (so training and
    evaluation environments are of one type); ``DummyVecEnv`` for other tasks, when the
    environments carry wrappers of their own, or when their integrator is one the batch does
    not take (``"dop853"``)."""
    if not env_fns:
        raise ValueError("env_fns=[]: it needs at least one environment function")
    probe = env_fns[0]()
    wrappers, env, monitor, probe_file = set(), probe, True, None
    while isinstance(env, gym.Wrapper):
        wrappers.add(type(env).__name__)
        writer = getattr(env, "results_writer", None)
        if writer is not None:  # make_vec_env's monitor_dir: write there too
            probe_file = Path(writer.file_handler.name)
            monitor = str(probe_file.parent / "batch")
        env = env.env
    spec = probe.spec  # the outermost: it carries make()'s max_episode_steps
    probe.close()
    if (wrappers <= _PLAIN_WRAPPERS and spec is not None
            and spec.id.startswith("roller_gym/")
            and spec.kwargs.get("integrator", DEFAULT_INTEGRATOR) in BATCH_INTEGRATORS):
        if probe_file is not None:  # the probe's own Monitor file: never written to
            probe_file.unlink(missing_ok=True)
        kwargs = {k: v for k, v in spec.kwargs.items() if k != "render_mode"}
        return RollerVecEnv(spec.id, n_envs=len(env_fns), monitor=monitor,
                            max_episode_steps=spec.max_episode_steps, **kwargs)
    return DummyVecEnv(env_fns, **vec_env_kwargs)


def _option_groups(options: list[dict | None], n: int) -> list[tuple[dict | None,
                                                                       np.ndarray]]:
    """The sub-environments' reset options as groups that share them: (options, mask), the
    empty ones (None or {}) as one group (SB3's ``set_options`` repeats one dict)."""
    groups: dict[int, tuple[dict | None, np.ndarray]] = {}
    for i in range(n):
        value = options[i] if options and options[i] else None
        key = 0 if value is None else id(value)
        groups.setdefault(key, (value, np.zeros(n, dtype=bool)))[1][i] = True
    return list(groups.values())


def _rows(info: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """A vector info as one dict per sub-environment (Python scalars), SB3's layout."""
    keys = [k for k in INFO_KEYS if k in info]
    columns = [np.asarray(info[k]).tolist() for k in keys]
    return [dict(zip(keys, row, strict=True)) for row in zip(*columns, strict=True)] if keys \
        else [{} for _ in range(n)]
